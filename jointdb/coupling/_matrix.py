"""Full joint matrix with inertia by inverse receptance coupling (docs/theory.md §2c, thesis ch. 6).

Computed block by block: a DOF measured on body A sees the joint only through
A's contact DOFs, so ``H_IC = diag(H_{I_a C_a}, H_{I_b C_b})`` and
``H_CI = diag(H_{C_a I_a}, H_{C_b I_b})`` (after ordering the measured DOFs by
body). Their pseudo-inverses are block diagonal too, and ``P = H_IC⁺ D H_CI⁺``
is formed from the four blocks ``P_xy = H_{I_x C_x}⁺ D_xy H_{C_y I_y}⁺``; the
zero blocks are never stored or multiplied. The lines are processed in passes
of ``_LINES`` so that every intermediate array stays in the processor's cache.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import NamedTuple

import numpy as np

from jointdb.coupling._common import (
    IdentificationResult,
    LazyExtra,
    as_receptance,
    fetch,
    require_determined,
    same_grid,
    solver_settings,
)
from jointdb.coupling._linalg import Regularisation, condition, frobenius, inverse, savgol_smooth
from jointdb.coupling._multi import _pinv_pair, _sym, _transposed
from jointdb.errors import InputError, NumericalError
from jointdb.frf import FRF, Dof, Quantity, dofs

__all__ = ["identify_joint_matrix"]


#: Frequency lines per pass: every array of a pass stays in the processor's cache.
_LINES = 1024


def _p_pass(h_ii, h_ic, h_ci, g, rows, span, reg: Regularisation, symmetrize: bool) -> tuple:
    """``P = H_IC⁺ D H_CI⁺`` on one pass of lines: ``(p, cond, d, ‖G‖²)`` with ``D = H_II − G``.

    ``g``: the measured assembly FRFs ``(w, L, L)``, measured DOFs ordered by
    body (``rows[x]`` on body x), symmetrised here if asked; ``span[x]``:
    body x's contact DOFs in the joint.
    """
    w, nl, nc = g.shape[0], g.shape[1], span[1].stop
    d = np.empty((w, nl, nl), dtype=complex)
    if symmetrize:
        np.add(g, np.swapaxes(g, 1, 2), out=d)
        d *= -0.5
    else:
        np.negative(g, out=d)
    den = frobenius(d) ** 2
    for x in (0, 1):  # H_II is block diagonal
        d[:, rows[x], rows[x]] += h_ii[x]
    left, right, cond_ic, cond_ci = _pinv_pair(h_ic, h_ci, reg)
    n = np.empty((w, nc, nl), dtype=complex)  # H_IC⁺ D
    for x in (0, 1):
        np.matmul(left[x], d[:, rows[x], :], out=n[:, span[x], :])
    p = np.empty((w, nc, nc), dtype=complex)  # H_IC⁺ D H_CI⁺
    for y in (0, 1):
        np.matmul(n[:, :, rows[y]], right[y], out=p[:, :, span[y]])
    if symmetrize:
        p = _sym(p)
    return p, cond_ic * cond_ci, d, den


def _pass(h_ii, h_ic, h_ci, h_cc, g, rows, span, reg: Regularisation, symmetrize: bool, hj) -> tuple:
    """Identify the joint on one pass of lines into ``hj``: ``(cond, num², den²)`` of the residual (see :func:`_p_pass`)."""
    p, cond, d, den = _p_pass(h_ii, h_ic, h_ci, g, rows, span, reg, symmetrize)
    w, nl, nc = d.shape[0], d.shape[1], span[1].stop
    inverse(p, out=hj)
    for x in (0, 1):
        hj[:, span[x], span[x]] -= h_cc[x]
    if symmetrize:
        hj[...] = _sym(hj)
    # Re-coupled measurement: G_rec − G = D − H_IC (H_CC + H^J)⁻¹ H_CI. H_CC + H^J is the inverse of
    # P exactly without symmetrisation and, with it, when H_CC is symmetric: then (H_CC + H^J)⁻¹ = P
    # to round-off and no further inverse is needed.
    if symmetrize and not all(_transposed(c, c) for c in h_cc):
        joined = hj.copy()
        for x in (0, 1):
            joined[:, span[x], span[x]] += h_cc[x]
        q = inverse(joined)  # (pseudo-inverse on singular lines: those are flagged, or all are and it raises)
    else:
        q = p
    y_ = np.empty((w, nl, nc), dtype=complex)  # H_IC q
    for x in (0, 1):
        np.matmul(h_ic[x], q[:, span[x], :], out=y_[:, rows[x], :])
    rec = np.empty((w, nl, nl), dtype=complex)  # H_IC q H_CI
    for y in (0, 1):
        np.matmul(y_[:, :, span[y]], h_ci[y], out=rec[:, :, rows[y]])
    rec -= d  # G_rec − G up to the sign
    return cond, frobenius(rec) ** 2, den


def _layout(substructures, measured, a: str, a_dofs, b: str, b_dofs):
    """The contact DOFs of ``a`` and ``b`` and the measured ``(name, Dof)`` pairs, checked
    (InputError: unknown names, overlapping labels, fewer measured DOFs than contact DOFs)."""
    if a not in substructures or b not in substructures:
        raise InputError(f"substructures must contain {a!r} and {b!r} (have: {', '.join(substructures)})")
    ad, bd = dofs(a_dofs), dofs(b_dofs)
    if set(ad) & set(bd):
        raise InputError(
            f"contact DOF labels on {a!r} and {b!r} overlap ({', '.join(map(str, set(ad) & set(bd)))}); "
            "use distinct node numbers on the two bodies"
        )
    pairs = [(str(n), Dof.parse(d)) for n, d in measured]
    for name, _ in pairs:
        if name not in (a, b):
            raise InputError(f"measured DOF on {name!r}: only {a!r} and {b!r} take part in this joint")
    labels = [d for _, d in pairs]
    if len(set(labels)) != len(labels):
        raise InputError("measured DOF labels must be distinct between the two bodies")
    nc = len(ad) + len(bd)
    L = len(pairs)
    if L < nc:
        raise InputError(f"{L} measured DOFs cannot identify a {nc}×{nc} joint matrix; measure at least {nc}")
    return ad, bd, pairs


def _body_blocks(bodies, meas, contacts):
    """Per body x: its receptance over measured DOFs I_x and contacts C_x (one gather), split into
    ``H_II``, ``H_IC``, ``H_CI``, ``H_CC``: four lists of two views."""
    h_ii, h_ic, h_ci, h_cc = [], [], [], []
    for x, (name, sub) in enumerate(bodies):
        m, lab = len(meas[x]), meas[x] + contacts[x]
        blk = fetch(f"substructure {name!r}", sub, lab, lab, "measured and contact DOFs, incl. rotations", view=True)
        h_ii.append(blk[:, :m, :m])
        h_ic.append(blk[:, :m, m:])
        h_ci.append(blk[:, m:, :m])
        h_cc.append(blk[:, m:, m:])
    return h_ii, h_ic, h_ci, h_cc


class _Problem(NamedTuple):
    """One joint-matrix identification, checked and gathered: the grid, the contact DOFs of A and B
    (``contacts = ad + bd``), the measured ``(name, Dof)`` pairs, each body's four receptance blocks
    (lists of two), the measured assembly FRFs ``g`` ordered by body, and where body x's measured
    rows (``rows[x]``) and contact DOFs (``span[x]``) sit."""

    freq: np.ndarray
    ad: tuple
    bd: tuple
    pairs: list
    blocks: tuple
    g: np.ndarray
    rows: list
    span: list

    @property
    def contacts(self) -> tuple:
        return self.ad + self.bd


def _problem(assembly, substructures, measured, side_a, side_b, smoothing, smoothing_order) -> _Problem:
    """Check the inputs (InputError) and gather the blocks of :func:`identify_joint_matrix`;
    ``side_a``, ``side_b``: ``(name, contact DOFs)``."""
    (a, a_dofs), (b, b_dofs) = side_a, side_b
    ad, bd, pairs = _layout(substructures, measured, a, a_dofs, b, b_dofs)
    G = as_receptance("assembly", assembly)
    A = as_receptance(f"substructure {a!r}", substructures[a])
    B = as_receptance(f"substructure {b!r}", substructures[b])
    freq = same_grid({"assembly": G, f"substructure {a!r}": A, f"substructure {b!r}": B})
    # Per body x: measured DOFs I_x, contacts C_x, and one gather of its receptance over I_x + C_x.
    meas = [[d for n, d in pairs if n == a], [d for n, d in pairs if n == b]]
    blocks = _body_blocks(((a, A), (b, B)), meas, [list(ad), list(bd)])
    order = meas[0] + meas[1]
    g = fetch("assembly", G, order, order, "the measured DOFs, directly or by reciprocity", view=True)
    if smoothing:
        g = savgol_smooth(g, int(smoothing), smoothing_order)
    rows = [slice(0, len(meas[0])), slice(len(meas[0]), len(pairs))]
    span = [slice(0, len(ad)), slice(len(ad), len(ad) + len(bd))]
    return _Problem(freq, ad, bd, pairs, blocks, g, rows, span)


def _solve_by_passes(pb: _Problem, reg: Regularisation, symmetrize: bool):
    """The joint ``H^J``, cond(H_IC)·cond(H_CI), the residual's numerator and denominator per line,
    solved in passes of ``_LINES`` lines; and a function computing cond(P) the same way when asked."""
    (h_ii, h_ic, h_ci, h_cc), g, rows, span = pb.blocks, pb.g, pb.rows, pb.span
    nf = g.shape[0]
    nc = h_cc[0].shape[1] + h_cc[1].shape[1]
    hj = np.empty((nf, nc, nc), dtype=complex)
    cond, num, den = np.empty(nf), np.empty(nf), np.empty(nf)
    passes = [slice(start, start + _LINES) for start in range(0, nf, _LINES)]
    for s in passes:
        cond[s], num[s], den[s] = _pass(
            [h[s] for h in h_ii], [h[s] for h in h_ic], [h[s] for h in h_ci], [h[s] for h in h_cc],
            g[s], rows, span, reg, symmetrize, hj[s],
        )

    def condition_p() -> np.ndarray:  # P again (the same operations, so the same numbers), when first asked for
        return np.concatenate([
            condition(_p_pass([h[s] for h in h_ii], [h[s] for h in h_ic], [h[s] for h in h_ci], g[s], rows, span,
                              reg, symmetrize)[0])
            for s in passes
        ])
    return hj, cond, num, den, condition_p


def identify_joint_matrix(
    assembly: FRF, substructures: Mapping[str, FRF], measured: Sequence[tuple[str, "Dof | str"]],
    a: str, a_dofs: Sequence["Dof | str"], b: str, b_dofs: Sequence["Dof | str"], *,
    regularisation: "Regularisation | str | None" = None, smoothing: int | None = None, smoothing_order: int = 4,
    symmetrize: bool = True, condition_limit: float = 1e8,
) -> IdentificationResult:
    """Identify the full receptance matrix of a joint with inertia (docs/theory.md §2c, thesis eq. 6.1–6.15).

    With the joint a body ``J`` rigidly attached to A's ``a_dofs`` and B's
    ``b_dofs`` (``C = [a_dofs; b_dofs]``, nc DOFs) and L measured DOFs ``I``
    on A and B: ``H_IC P H_CI = D = H_II − G_II`` with
    ``P = (H_CC + H^J)⁻¹``; least squares ``P = H_IC⁺ D H_CI⁺`` (L ≥ nc), then
    ``H^J = P⁻¹ − H_CC``.

    Parameters
    ----------
    assembly
        Measured assembly receptances on the L measured DOFs (labelled by the
        substructures' DOF labels, so these must be distinct between A and B).
    substructures
        Mapping with (at least) ``a`` and ``b``: free receptances over their
        measured and contact DOFs (incl. rotations at the contacts).
    measured
        ``(name, Dof)`` pairs of the L measured DOFs, on ``a`` or ``b``.
    a, b
        Names (keys of ``substructures``) of the two bodies the joint connects.
    a_dofs, b_dofs
        Contact DOFs (e.g. all six at one node on each side); nc = total.
    regularisation
        For the pseudo-inverses of ``H_IC`` and ``H_CI`` (``"tikhonov:1e-3"``, ``"tsvd:1e-4"``).
    smoothing, smoothing_order, symmetrize
        As in :func:`identify_n_point_joints`.
    condition_limit
        Lines whose condition number exceeds this are flagged ``ill_conditioned``; if every
        line does, the measured DOFs do not determine the joint (NumericalError).

    Returns
    -------
    IdentificationResult
        ``joint``: the joint body's free receptance over ``a_dofs + b_dofs``
        (use ``result.joint_substructure()`` in :func:`couple`);
        ``condition``: cond(H_IC)·cond(H_CI) per line (the Kronecker system's
        condition number, after column/row equilibration); ``residual``: the
        measured FRFs re-coupled with the identified joint,
        ``‖H_II − H_IC (H_CC + H^J)⁻¹ H_CI − G_II‖ / ‖G_II‖``;
        ``extra["condition_p"]``: cond(P) (computed when first read).

    Raises
    ------
    InputError
        L < nc, unknown names or DOFs, label clashes, grid mismatch.
    NumericalError
        If ``H_IC`` is singular at every line (the measured DOFs do not
        determine the joint), or the identified joint is not finite.

    Examples
    --------
    Two steel beams joined through a 10 mm long joint body with mass and rotary inertia (a
    free 20 mm beam segment); five measured DOFs on A and B give back the body's free
    receptance over its four contact DOFs:

    >>> import numpy as np
    >>> from jointdb.fe import BeamModel, Segment, NamedPoint, Clamp, HystereticDamping
    >>> from jointdb.coupling import Interface, JointSubstructure, couple, identify_joint_matrix
    >>> freq = np.linspace(100.0, 2000.0, 12)                                    # Hz
    >>> pts = lambda *p: tuple(NamedPoint(name, z, node=n) for name, z, n in p)
    >>> A = BeamModel(segments=(Segment(0.2, 0.03, material="steel"),),
    ...               points=pts(("p1", 0.0, 1), ("p2", 0.1, 2), ("c3", 0.2, 3)),
    ...               ).frf(freq, points=["p1", "p2", "c3"])
    >>> B = BeamModel(segments=(Segment(0.2, 0.05, material="steel"),),
    ...               points=pts(("c4", 0.0, 4), ("p5", 0.1, 5)),
    ...               ingredients=(Clamp(0.2), HystereticDamping(0.01))).frf(freq, points=["c4", "p5"])
    >>> J = BeamModel(segments=(Segment(0.01, 0.02, material="steel"),),
    ...               points=pts(("a", 0.0, 8), ("b", 0.01, 9))).frf(freq, points=["a", "b"])
    >>> body = JointSubstructure(J, ["8x", "8ry"], ["9x", "9ry"])
    >>> subs = {"A": A, "B": B}
    >>> points = [("A", "1x"), ("A", "1ry"), ("A", "2x"), ("B", "5x"), ("B", "5ry")]
    >>> measured = couple(subs, [Interface("A", ["3x", "3ry"], "B", ["4x", "4ry"], joint=body)],
    ...                   outputs=points)
    >>> result = identify_joint_matrix(measured, subs, points, "A", ["3x", "3ry"], "B", ["4x", "4ry"])
    >>> [str(dof) for dof in result.joint.outputs]
    ['3x', '3ry', '4x', '4ry']
    >>> scale = np.abs(J.values).max(axis=(1, 2))[:, None, None]
    >>> bool(np.max(np.abs(result.joint.values - J.values) / scale) < 1e-6)
    True
    """
    reg = Regularisation.parse(regularisation)
    pb = _problem(assembly, substructures, measured, (a, a_dofs), (b, b_dofs), smoothing, smoothing_order)
    solved = _solve_by_passes(pb, reg, symmetrize)
    nc, L = len(pb.contacts), len(pb.pairs)
    require_determined(solved[1], condition_limit, "H_IC (measured DOFs × contact DOFs)",
                       f"the {L} measured DOFs do not determine the {nc}×{nc} joint — measure other DOFs")
    settings = {"measured": [f"{n}:{d}" for n, d in pb.pairs], "a": a, "a_dofs": [str(x) for x in pb.ad],
                "b": b, "b_dofs": [str(x) for x in pb.bd], **solver_settings(reg, smoothing, smoothing_order, symmetrize)}
    return _result(pb, solved, condition_limit, settings)


def _result(pb: _Problem, solved: tuple, condition_limit: float, settings: dict) -> IdentificationResult:
    """Package what :func:`_solve_by_passes` gave (NumericalError if the joint is not finite)."""
    hj, cond, num, den, condition_p = solved
    if not np.all(np.isfinite(hj)):
        raise NumericalError("the identified joint matrix is not finite at some line; check the measured FRFs")
    ill = cond > condition_limit
    return IdentificationResult(
        joint=FRF._trusted(pb.freq, hj, pb.contacts, pb.contacts, Quantity.RECEPTANCE), model="matrix",
        residual=np.sqrt(num) / np.maximum(np.sqrt(den), 1e-300), condition=cond, unreliable=ill,
        flags={"ill_conditioned": ill},
        extra=LazyExtra({"n_measured": len(pb.pairs), "nc": hj.shape[1]}, {"condition_p": condition_p}),
        settings=settings,
    )
