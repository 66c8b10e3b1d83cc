"""Multi-DOF joint identification: n translational joints (theory.md §2b, thesis ch. 5)
and the full joint matrix with inertia (theory.md §2c, thesis ch. 6)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from jointdb.coupling._common import IdentificationResult, as_receptance, fetch, same_grid
from jointdb.coupling._linalg import Regularisation, condition, pinv, savgol_smooth
from jointdb.errors import InputError, NumericalError
from jointdb.frf import FRF, Dof, Quantity, dofs

__all__ = ["identify_n_point_joints", "identify_joint_matrix"]


def _measured(G: FRF, labels: Sequence[Dof], smoothing: int | None, order: int, symmetrize: bool) -> np.ndarray:
    g = fetch("assembly", G, labels, labels, "the measured DOFs, directly or by reciprocity")
    if smoothing:
        g = savgol_smooth(g, int(smoothing), order)
    if symmetrize:
        g = 0.5 * (g + np.swapaxes(g, 1, 2))
    return g


def _scaled_ls(h_left: np.ndarray, d: np.ndarray, h_right: np.ndarray, reg: Regularisation) -> np.ndarray:
    """Least squares ``X`` with ``h_left X h_right ≈ d``: ``X = h_left⁺ d h_right⁺``.

    The columns of ``h_left`` and rows of ``h_right`` are equilibrated (scaled to
    unit norm per line) before the pseudo-inverses, so that mixed units
    (translations and rotations) do not inflate the condition number and the
    regularisation threshold is unit-free; the scaling is undone afterwards.
    """
    sl = np.linalg.norm(h_left, axis=1)  # (nf, nc)
    sr = np.linalg.norm(h_right, axis=2)  # (nf, nc)
    sl = np.where(sl > 0, sl, 1.0)
    sr = np.where(sr > 0, sr, 1.0)
    x = pinv(h_left / sl[:, None, :], reg) @ d @ pinv(h_right / sr[:, :, None], reg)
    return x / sl[:, :, None] / sr[:, None, :]


def _scaled_condition(h: np.ndarray, axis: int) -> np.ndarray:
    s = np.linalg.norm(h, axis=axis, keepdims=True)
    return condition(h / np.where(s > 0, s, 1.0))


def _rel_residual(rec: np.ndarray, meas: np.ndarray) -> np.ndarray:
    num = np.linalg.norm(rec - meas, axis=(1, 2))
    return num / np.maximum(np.linalg.norm(meas, axis=(1, 2)), 1e-300)


def identify_n_point_joints(
    assembly: FRF,
    substructure_a: FRF,
    internal: Sequence["Dof | str"],
    a_contact: Sequence["Dof | str"],
    substructure_b: FRF,
    b_contact: Sequence["Dof | str"],
    *,
    diagonal: bool = True,
    regularisation: "Regularisation | str | None" = None,
    smoothing: int | None = None,
    smoothing_order: int = 4,
    symmetrize: bool = True,
    condition_limit: float = 1e8,
) -> IdentificationResult:
    """Identify n translational joints between two bodies (theory.md §2b, thesis eq. 5.1–5.10).

    ``G = h_II − H_Ia B⁻¹ H_aI`` with ``B = H_aa + H_bb + H_J``: with m
    measured internal DOFs of A and n connection DOFs (m ≥ n),
    ``B⁻¹ = H_Ia⁺ (h_II − G) H_aI⁺`` and ``H_J = B − H_aa − H_bb``.

    Parameters
    ----------
    assembly
        Measured assembly receptances on A's ``internal`` DOFs (m×m, missing
        entries filled by reciprocity).
    substructure_a
        A's free receptance over ``internal`` and ``a_contact``.
    internal
        The m measured DOFs on A (m ≥ n).
    a_contact, b_contact
        The n paired connection DOFs on A and B (one per spring).
    substructure_b
        B's receptance over ``b_contact``.
    diagonal
        Keep only the diagonal of the identified ``H_J`` (independent springs,
        the thesis model); the off-diagonal residue
        ``‖offdiag H_J‖_F / ‖diag H_J‖`` per line is reported in
        ``extra["off_diagonal"]`` as a model-validity measure.
    regularisation
        For the pseudo-inverses of ``H_Ia`` and ``H_aI`` (``"tikhonov:1e-3"``,
        ``"tsvd:1e-4"``, a :class:`Regularisation`, or None).
    smoothing
        Optional odd Savitzky–Golay window applied to the measured FRFs.
    symmetrize
        Average the measured matrix with its transpose (reciprocity).

    Returns
    -------
    IdentificationResult
        ``joint`` labelled with ``a_contact``; ``condition`` = cond(H_Ia) per
        line (columns equilibrated); ``extra``: ``"full_joint"`` (n_freq, n, n), ``"off_diagonal"``.

    Raises
    ------
    InputError
        m < n, missing DOFs, grid mismatch.
    """
    I, a, b = dofs(internal), dofs(a_contact), dofs(b_contact)
    if len(a) != len(b):
        raise InputError(f"a_contact has {len(a)} DOFs but b_contact has {len(b)}; they are paired")
    if len(I) < len(a):
        raise InputError(
            f"{len(I)} measured internal DOFs cannot identify {len(a)} joints; measure at least {len(a)}"
        )
    reg = Regularisation.parse(regularisation)
    G = as_receptance("assembly", assembly)
    A = as_receptance("substructure A", substructure_a)
    B = as_receptance("substructure B", substructure_b)
    freq = same_grid({"assembly": G, "substructure A": A, "substructure B": B})
    g = _measured(G, I, smoothing, smoothing_order, symmetrize)
    h_ii = fetch("substructure A", A, I, I)
    h_ia = fetch("substructure A", A, I, a)
    h_ai = fetch("substructure A", A, a, I)
    h_aa = fetch("substructure A", A, a, a)
    h_bb = fetch("substructure B", B, b, b)
    d = h_ii - g
    b_inv = _scaled_ls(h_ia, d, h_ai, reg)
    bmat = pinv(b_inv)
    hj_full = bmat - h_aa - h_bb
    n = len(a)
    diag_idx = np.arange(n)
    diag_part = np.zeros_like(hj_full)
    diag_part[:, diag_idx, diag_idx] = hj_full[:, diag_idx, diag_idx]
    off = np.linalg.norm(hj_full - diag_part, axis=(1, 2)) / np.maximum(
        np.linalg.norm(diag_part, axis=(1, 2)), 1e-300
    )
    hj = diag_part if diagonal else hj_full
    rec = h_ii - h_ia @ np.linalg.solve(h_aa + h_bb + hj, h_ai)
    cond = _scaled_condition(h_ia, 1)
    if np.all(cond > condition_limit):
        raise NumericalError(
            f"H_Ia (measured internal DOFs × connection DOFs) is singular at every line (condition > "
            f"{condition_limit:g}); the measured points do not determine the {n} joints — measure other points"
        )
    passive = np.all(hj[:, diag_idx, diag_idx].imag <= 1e-6 * np.abs(hj[:, diag_idx, diag_idx]), axis=1)
    ill = cond > condition_limit
    return IdentificationResult(
        joint=FRF(freq, hj, a, a, Quantity.RECEPTANCE),
        model="n-point",
        residual=_rel_residual(rec, g),
        condition=cond,
        unreliable=ill | ~passive,
        flags={"ill_conditioned": ill, "non_passive": ~passive},
        extra={"full_joint": hj_full, "off_diagonal": off, "condition_b": condition(b_inv)},
        settings={
            "internal": [str(x) for x in I],
            "a_contact": [str(x) for x in a],
            "b_contact": [str(x) for x in b],
            "diagonal": diagonal,
            "regularisation": f"{reg.method}:{reg.rel:g}",
            "smoothing": smoothing,
            "smoothing_order": smoothing_order,
            "symmetrize": symmetrize,
        },
    )


def identify_joint_matrix(
    assembly: FRF,
    substructures: Mapping[str, FRF],
    measured: Sequence[tuple[str, "Dof | str"]],
    a: str,
    a_dofs: Sequence["Dof | str"],
    b: str,
    b_dofs: Sequence["Dof | str"],
    *,
    regularisation: "Regularisation | str | None" = None,
    smoothing: int | None = None,
    smoothing_order: int = 4,
    symmetrize: bool = True,
    condition_limit: float = 1e8,
) -> IdentificationResult:
    """Identify the full receptance matrix of a joint with inertia (theory.md §2c, thesis eq. 6.1–6.15).

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
    a_dofs, b_dofs
        Contact DOFs (e.g. all six at one node on each side); nc = total.
    regularisation
        For the pseudo-inverses of ``H_IC`` and ``H_CI`` (``"tikhonov:1e-3"``, ``"tsvd:1e-4"``).
    smoothing, smoothing_order, symmetrize
        As in :func:`identify_n_point_joints`.

    Returns
    -------
    IdentificationResult
        ``joint``: the joint body's free receptance over ``a_dofs + b_dofs``
        (use ``result.joint_substructure()`` in :func:`couple`);
        ``condition``: cond(H_IC)·cond(H_CI) per line (the Kronecker system's
        condition number, after column/row equilibration); ``extra["condition_p"]``: cond(P).

    Raises
    ------
    InputError
        L < nc, unknown names or DOFs, label clashes, grid mismatch.
    """
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
    reg = Regularisation.parse(regularisation)
    G = as_receptance("assembly", assembly)
    A = as_receptance(f"substructure {a!r}", substructures[a])
    B = as_receptance(f"substructure {b!r}", substructures[b])
    freq = same_grid({"assembly": G, f"substructure {a!r}": A, f"substructure {b!r}": B})
    g = _measured(G, labels, smoothing, smoothing_order, symmetrize)
    ia = [i for i, (n, _) in enumerate(pairs) if n == a]
    ib = [i for i, (n, _) in enumerate(pairs) if n == b]
    nf = freq.size
    h_ii = np.zeros((nf, L, L), dtype=complex)
    h_ic = np.zeros((nf, L, nc), dtype=complex)
    h_ci = np.zeros((nf, nc, L), dtype=complex)
    h_cc = np.zeros((nf, nc, nc), dtype=complex)
    ca, cb = np.arange(len(ad)), len(ad) + np.arange(len(bd))
    for rows, sub, name, side, cidx in ((ia, A, a, ad, ca), (ib, B, b, bd, cb)):
        if not rows:
            continue
        lab = [labels[i] for i in rows]
        r = np.array(rows)
        h_ii[:, r[:, None], r[None, :]] = fetch(f"substructure {name!r}", sub, lab, lab)
        h_ic[:, r[:, None], cidx[None, :]] = fetch(f"substructure {name!r}", sub, lab, side)
        h_ci[:, cidx[:, None], r[None, :]] = fetch(f"substructure {name!r}", sub, side, lab)
    h_cc[:, ca[:, None], ca[None, :]] = fetch(f"substructure {a!r}", A, ad, ad, "contact DOFs incl. rotations")
    h_cc[:, cb[:, None], cb[None, :]] = fetch(f"substructure {b!r}", B, bd, bd, "contact DOFs incl. rotations")
    d = h_ii - g
    p = _scaled_ls(h_ic, d, h_ci, reg)
    if symmetrize:
        p = 0.5 * (p + np.swapaxes(p, 1, 2))
    hj = pinv(p) - h_cc
    if symmetrize:
        hj = 0.5 * (hj + np.swapaxes(hj, 1, 2))
    rec = h_ii - h_ic @ np.linalg.solve(h_cc + hj, h_ci)
    cond = _scaled_condition(h_ic, 1) * _scaled_condition(h_ci, 2)
    if np.all(cond > condition_limit):
        raise NumericalError(
            f"H_IC (measured DOFs × contact DOFs) is singular at every line (condition > {condition_limit:g}); "
            f"the {L} measured DOFs do not determine the {nc}×{nc} joint — measure other DOFs"
        )
    ill = cond > condition_limit
    return IdentificationResult(
        joint=FRF(freq, hj, ad + bd, ad + bd, Quantity.RECEPTANCE),
        model="matrix",
        residual=_rel_residual(rec, g),
        condition=cond,
        unreliable=ill,
        flags={"ill_conditioned": ill},
        extra={"condition_p": condition(p), "n_measured": L, "nc": nc},
        settings={
            "measured": [f"{n}:{d}" for n, d in pairs],
            "a": a,
            "a_dofs": [str(x) for x in ad],
            "b": b,
            "b_dofs": [str(x) for x in bd],
            "regularisation": f"{reg.method}:{reg.rel:g}",
            "smoothing": smoothing,
            "smoothing_order": smoothing_order,
            "symmetrize": symmetrize,
        },
    )
