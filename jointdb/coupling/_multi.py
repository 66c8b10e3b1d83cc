"""Multi-DOF joint identification: n translational joints (docs/theory.md §2b, thesis ch. 5),
and the least-squares helpers shared with the full joint matrix (``_matrix``)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from jointdb.coupling._common import (
    IdentificationResult,
    LazyExtra,
    fetch,
    receptances_on_one_grid,
    require_determined,
    solver_settings,
)
from jointdb.coupling._linalg import (
    Regularisation,
    condition,
    equilibrated_pinvs,
    frobenius,
    inverse,
    savgol_smooth,
)
from jointdb.errors import InputError
from jointdb.frf import FRF, Dof, Quantity, dofs

__all__ = ["identify_n_point_joints"]


def _measured(G: FRF, labels: Sequence[Dof], smoothing: int | None, order: int, symmetrize: bool) -> np.ndarray:
    g = fetch("assembly", G, labels, labels, "the measured DOFs, directly or by reciprocity")
    if smoothing:
        g = savgol_smooth(g, int(smoothing), order)
    if symmetrize:
        g = 0.5 * (g + np.swapaxes(g, 1, 2))
    return g


def _pinv_pair(
    h_left: "list[np.ndarray]", h_right: "list[np.ndarray]", reg: Regularisation
) -> tuple[list[np.ndarray], list[np.ndarray], np.ndarray, np.ndarray]:
    """Pseudo-inverses for the least squares ``X`` with ``h_left X h_right ≈ d``, ``X = h_left⁺ d h_right⁺``.

    ``h_left`` (tall) and ``h_right`` (wide) are given by their diagonal blocks
    (one block each for a full matrix). The columns of ``h_left`` and rows of
    ``h_right`` are equilibrated (scaled to unit norm per line) before the
    pseudo-inverses, so that mixed units (translations and rotations) do not
    inflate the condition number and the regularisation threshold is unit-free;
    the scaling is undone in the returned blocks. When ``h_right`` is exactly
    ``h_leftᵀ`` (reciprocal substructures), its pseudo-inverse is the transpose
    of the left one and is not computed again.

    Returns
    -------
    left, right : lists of blocks of ``h_left⁺`` and ``h_right⁺``
    cond_left, cond_right : ``(n_freq,)``
        Condition numbers of the equilibrated ``h_left`` and ``h_right``.
    """
    if all(_transposed(r, lb) for lb, r in zip(h_left, h_right)):
        ((left, cond_l),) = equilibrated_pinvs([(h_left, False)], reg)
        return left, [np.swapaxes(x, 1, 2) for x in left], cond_l, cond_l
    (left, cond_l), (right, cond_r) = equilibrated_pinvs([(h_left, False), (h_right, True)], reg)
    return left, right, cond_l, cond_r


def _transposed(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether ``a == bᵀ`` exactly at every line (decided on the first line first: usually enough to say no)."""
    bt = np.swapaxes(b, 1, 2)
    if a.shape != bt.shape:
        return False
    return bool(np.array_equal(a[:1], bt[:1]) and np.array_equal(a, bt))


def _sym(a: np.ndarray) -> np.ndarray:
    return 0.5 * (a + np.swapaxes(a, 1, 2))


def _diagonal_part(hj_full: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The diagonal of a joint matrix (independent springs) and the off-diagonal residue
    ``‖offdiag H_J‖_F / ‖diag H_J‖`` per line."""
    n = hj_full.shape[1]
    diag_idx = np.arange(n)
    diag_part = np.zeros_like(hj_full)
    diag_part[:, diag_idx, diag_idx] = hj_full[:, diag_idx, diag_idx]
    off = np.linalg.norm(hj_full - diag_part, axis=(1, 2)) / np.maximum(
        np.linalg.norm(diag_part, axis=(1, 2)), 1e-300
    )
    return diag_part, off


def _rel_residual(rec: np.ndarray, meas: np.ndarray) -> np.ndarray:
    return frobenius(rec - meas) / np.maximum(frobenius(meas), 1e-300)


def _n_point_blocks(assembly, substructure_a, substructure_b, I, a, b, smoothing, smoothing_order, symmetrize):
    """The grid, the measured ``G_II`` (smoothed, symmetrised as asked) and A's ``h_II``, ``H_Ia``,
    ``H_aI``, ``H_aa`` and B's ``H_bb``."""
    freq, G, A, B = receptances_on_one_grid(assembly, substructure_a, substructure_b)
    g = _measured(G, I, smoothing, smoothing_order, symmetrize)
    h_ii = fetch("substructure A", A, I, I)
    h_ia = fetch("substructure A", A, I, a)
    h_ai = fetch("substructure A", A, a, I)
    h_aa = fetch("substructure A", A, a, a)
    h_bb = fetch("substructure B", B, b, b)
    return freq, g, (h_ii, h_ia, h_ai, h_aa, h_bb)


def identify_n_point_joints(
    assembly: FRF, substructure_a: FRF, internal: Sequence["Dof | str"], a_contact: Sequence["Dof | str"],
    substructure_b: FRF, b_contact: Sequence["Dof | str"], *, diagonal: bool = True,
    regularisation: "Regularisation | str | None" = None, smoothing: int | None = None, smoothing_order: int = 4,
    symmetrize: bool = True, condition_limit: float = 1e8,
) -> IdentificationResult:
    """Identify n translational joints between two bodies (docs/theory.md §2b, thesis eq. 5.1–5.10).

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
    smoothing_order
        Polynomial order of the Savitzky–Golay filter.
    symmetrize
        Average the measured matrix with its transpose (reciprocity).
    condition_limit
        Lines where cond(H_Ia) exceeds this are flagged ``ill_conditioned``; if every line
        does, the measured points cannot determine the joints (NumericalError).

    Returns
    -------
    IdentificationResult
        ``joint`` labelled with ``a_contact``; ``condition`` = cond(H_Ia) per
        line (columns equilibrated); ``extra``: ``"full_joint"`` (n_freq, n, n), ``"off_diagonal"``.

    Raises
    ------
    InputError
        m < n, missing DOFs, grid mismatch.

    Examples
    --------
    A free steel beam (A) held on a clamped-clamped beam (B) by two translational springs
    (A's nodes 2 and 4 to B's nodes 6 and 7); the assembly is "measured" at A's ends (nodes
    1 and 5), and the two springs come back:

    >>> import numpy as np
    >>> from jointdb.fe import BeamModel, Segment, NamedPoint, Clamp, HystereticDamping
    >>> from jointdb.coupling import (Interface, couple, spring_damper_joint, identify_n_point_joints,
    ...                               fit_constant_kc)
    >>> freq = np.linspace(200.0, 3000.0, 15)                                    # Hz
    >>> pts = lambda *p: tuple(NamedPoint(name, z, node=n) for name, z, n in p)
    >>> A = BeamModel(segments=(Segment(0.3, 0.03, material="steel"),),
    ...               points=pts(("p1", 0.0, 1), ("c2", 0.05, 2), ("c4", 0.25, 4), ("p5", 0.3, 5)),
    ...               ).frf(freq, points=["p1", "c2", "c4", "p5"])
    >>> B = BeamModel(segments=(Segment(0.3, 0.06, material="steel"),),
    ...               points=pts(("c6", 0.05, 6), ("c7", 0.25, 7)),
    ...               ingredients=(Clamp(0.0), Clamp(0.3), HystereticDamping(0.01)),
    ...               ).frf(freq, points=["c6", "c7"])
    >>> springs = spring_damper_joint(freq, k=[5e7, 8e7], c=[300.0, 500.0], dofs_=["2x", "4x"])
    >>> measured = couple({"A": A, "B": B}, [Interface("A", ["2x", "4x"], "B", ["6x", "7x"], joint=springs)],
    ...                   outputs=[("A", "1x"), ("A", "5x")])
    >>> result = identify_n_point_joints(measured, A, ["1x", "5x"], ["2x", "4x"], B, ["6x", "7x"])
    >>> fit = fit_constant_kc(result.joint)
    >>> fit.k.round(-2), fit.c.round(3)                                           # N/m, N·s/m
    (array([50000000., 80000000.]), array([300., 500.]))
    """
    I, a, b = _contacts(internal, a_contact, b_contact)
    reg = Regularisation.parse(regularisation)
    freq, g, blocks = _n_point_blocks(
        assembly, substructure_a, substructure_b, I, a, b, smoothing, smoothing_order, symmetrize)
    b_inv, cond = _b_inverse(g, blocks, reg)
    require_determined(cond, condition_limit, "H_Ia (measured internal DOFs × connection DOFs)",
                       f"the measured points do not determine the {len(a)} joints — measure other points")
    settings = {"internal": [str(x) for x in I], "a_contact": [str(x) for x in a], "b_contact": [str(x) for x in b],
                "diagonal": diagonal, **solver_settings(reg, smoothing, smoothing_order, symmetrize)}
    return _n_point_result(freq, g, blocks, b_inv, cond, (a, diagonal, condition_limit), settings)


def _contacts(internal, a_contact, b_contact) -> tuple:
    """The measured internal DOFs and the paired contact DOFs on A and B, checked (InputError)."""
    I, a, b = dofs(internal), dofs(a_contact), dofs(b_contact)
    if len(a) != len(b):
        raise InputError(f"a_contact has {len(a)} DOFs but b_contact has {len(b)}; they are paired")
    if len(I) < len(a):
        raise InputError(
            f"{len(I)} measured internal DOFs cannot identify {len(a)} joints; measure at least {len(a)}"
        )
    return I, a, b


def _b_inverse(g: np.ndarray, blocks: tuple, reg: Regularisation) -> tuple[np.ndarray, np.ndarray]:
    """Least squares ``B⁻¹ = H_Ia⁺ (h_II − G) H_aI⁺`` per line, and cond(H_Ia)."""
    h_ii, h_ia, h_ai, _, _ = blocks
    (left,), (right,), cond, _ = _pinv_pair([h_ia], [h_ai], reg)
    return left @ (h_ii - g) @ right, cond


def _n_point_result(freq, g, blocks, b_inv, cond, options: tuple, settings: dict) -> IdentificationResult:
    """``H_J = B − H_aa − H_bb`` (its diagonal if ``diagonal``), re-coupled and packaged;
    ``options``: ``(a, diagonal, condition_limit)``."""
    a, diagonal, condition_limit = options
    h_ii, h_ia, h_ai, h_aa, h_bb = blocks
    hj_full = inverse(b_inv) - h_aa - h_bb
    diag_part, off = _diagonal_part(hj_full)
    diag_idx = np.arange(len(a))
    hj = diag_part if diagonal else hj_full
    rec = h_ii - h_ia @ np.linalg.solve(h_aa + h_bb + hj, h_ai)
    passive = np.all(hj[:, diag_idx, diag_idx].imag <= 1e-6 * np.abs(hj[:, diag_idx, diag_idx]), axis=1)
    ill = cond > condition_limit
    return IdentificationResult(
        joint=FRF(freq, hj, a, a, Quantity.RECEPTANCE),
        model="n-point",
        residual=_rel_residual(rec, g),
        condition=cond,
        unreliable=ill | ~passive,
        flags={"ill_conditioned": ill, "non_passive": ~passive},
        extra=LazyExtra({"full_joint": hj_full, "off_diagonal": off}, {"condition_b": lambda: condition(b_inv)}),
        settings=settings,
    )
