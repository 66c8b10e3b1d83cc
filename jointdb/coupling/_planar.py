"""Planar spring–damper joint from two translational assembly FRFs (docs/theory.md §2a, thesis §4.2)."""

from __future__ import annotations

import numpy as np

from jointdb.coupling._common import IdentificationResult, as_receptance, fetch, fill_bad_lines, same_grid
from jointdb.coupling._linalg import pinv, savgol_smooth
from jointdb.errors import InputError
from jointdb.frf import FRF, Dof, Quantity

__all__ = ["identify_planar_joint"]


def _quadratic_roots(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Both roots of ``a x² + b x + c = 0`` per line, cancellation-free (linear if a ≈ 0)."""
    disc = np.sqrt(b * b - 4 * a * c)
    sign = np.where((np.conj(b) * disc).real >= 0, 1.0, -1.0)
    q = -0.5 * (b + sign * disc)
    with np.errstate(divide="ignore", invalid="ignore"):
        r1 = q / a
        r2 = c / q
        linear = np.abs(a) * np.maximum(np.abs(r2), 1e-300) < 1e-14 * np.abs(b)
        r1 = np.where(linear, np.nan + 0j, r1)
        r2 = np.where(linear, -c / b, r2)
    return r1, r2


def _recouple_residual(h_t, h_r, h_b, h12, l12, h22, h33, p22, p33, btr, brt, meas):
    """Relative residual of ``G_1j = h_1j − v B⁻¹ u_j`` (j = 1, 2) against the measurement."""
    bm = np.empty((h_t.size, 2, 2), dtype=complex)
    bm[:, 0, 0] = h22 + h33 + h_t
    bm[:, 0, 1], bm[:, 1, 0] = btr, brt
    bm[:, 1, 1] = p22 + p33 + h_r
    v = np.stack([h12, l12], axis=1)[:, None, :]
    rec = h_b[:, 0, :] - (v @ pinv(bm) @ h_b[:, 1:, :])[:, 0, :]
    return np.linalg.norm(rec - meas, axis=1) / np.maximum(np.linalg.norm(meas, axis=1), 1e-300)


def identify_planar_joint(
    assembly: FRF,
    substructure_a: FRF,
    a_point: int,
    substructure_b: FRF,
    b_contact: int,
    b_tip: int,
    *,
    translation: str = "x",
    rotation: str = "ry",
    smoothing: int | None = None,
    smoothing_order: int = 4,
    passivity_tol: float = 1e-6,
    condition_limit: float = 1e8,
    consistency_tol: float = 1e-6,
) -> IdentificationResult:
    """Identify a planar spring–damper joint ``diag(h_t, h_r)`` (docs/theory.md §2a, thesis eq. 4.12–4.13).

    Substructure A (e.g. machine + holder; only its contact-point block
    ``H_33`` incl. rotations is needed) is joined at point ``a_point`` to
    substructure B (e.g. the tool, from a model) at ``b_contact``; ``b_tip`` is
    B's free end. From the measured translational assembly FRFs ``G_11`` (tip
    direct) and ``G_12`` (tip response, force at B's contact point), the two
    bilinear equations ``d_j (xy − b_tr b_rt) = h_12 h_2j y − h_12 n_2j b_tr −
    l_12 h_2j b_rt + l_12 n_2j x`` are reduced to a quadratic in
    ``x = h_22 + h_33 + h_t``. Of its two roots, the one making both joint
    terms passive (``Im h ≤ 0``) and that reproduces the measurement when
    coupled back is chosen (the elimination can add a spurious root); where
    two roots pass both tests the choice follows the nearest unambiguous line
    (continuity) and the line is flagged ``ambiguous``.

    Parameters
    ----------
    assembly
        Measured assembly FRF containing ``(b_tip, b_tip)`` and
        ``(b_tip, b_contact)`` (or its reciprocal) in the translation direction.
    substructure_a
        A's receptance with the 2×2 block at ``a_point`` (translation, rotation).
    substructure_b
        B's receptance over tip and contact points, translation and rotation.
    a_point, b_contact, b_tip
        Node numbers (DOF labels ``Dof(node, translation|rotation)``).
    translation, rotation
        Directions of the plane (default ``x`` and ``ry``).
    smoothing
        Optional odd Savitzky–Golay window (lines) applied to the measured FRFs.
    passivity_tol
        Relative tolerance on ``Im h ≤ tol·|h|`` in the passivity test.
    condition_limit
        Lines whose Jacobian condition number exceeds this are flagged.
    consistency_tol
        A root is consistent when re-coupling with it reproduces the measured
        FRFs to this relative residual.

    Returns
    -------
    IdentificationResult
        ``joint``: 2×2 diagonal receptance labelled ``(a_point, translation),
        (a_point, rotation)``; ``condition``: condition number of the Jacobian
        of the two equations at the chosen root; flags ``ambiguous``,
        ``non_passive``, ``inconsistent``, ``ill_conditioned``, ``degenerate``.

    Raises
    ------
    InputError
        Missing DOFs (e.g. a substructure without rotational terms), grid mismatch.
    NumericalError
        If no line gives a finite solution.
    """
    t, r = translation, rotation
    if Dof(0, t).is_rotation or not Dof(0, r).is_rotation:
        raise InputError(f"translation {t!r} must be a translation and rotation {r!r} a rotation direction")
    if b_contact == b_tip:
        raise InputError(f"b_contact and b_tip are both node {b_tip}; the tip must be another node of B")
    G = as_receptance("assembly", assembly)
    A = as_receptance("substructure A", substructure_a)
    B = as_receptance("substructure B", substructure_b)
    freq = same_grid({"assembly": G, "substructure A": A, "substructure B": B})
    p3 = [Dof(a_point, t), Dof(a_point, r)]
    p1t, p1r, p2t, p2r = Dof(b_tip, t), Dof(b_tip, r), Dof(b_contact, t), Dof(b_contact, r)
    H33 = fetch("substructure A", A, p3, p3, "the contact block incl. rotations is needed")
    HB = fetch("substructure B", B, [p1t, p1r, p2t, p2r], [p1t, p1r, p2t, p2r], "tip and contact, incl. rotations")
    meas = np.stack(
        [fetch("assembly", G, [p1t], [p1t])[:, 0, 0], fetch("assembly", G, [p1t], [p2t])[:, 0, 0]], axis=1
    )
    if smoothing:
        meas = savgol_smooth(meas, int(smoothing), smoothing_order)

    h11, h12, l12 = HB[:, 0, 0], HB[:, 0, 2], HB[:, 0, 3]
    h21, n21 = HB[:, 2, 0], HB[:, 3, 0]
    h22, l22, n22, p22 = HB[:, 2, 2], HB[:, 2, 3], HB[:, 3, 2], HB[:, 3, 3]
    h33, l33, n33, p33 = H33[:, 0, 0], H33[:, 0, 1], H33[:, 1, 0], H33[:, 1, 1]
    btr, brt = l22 + l33, n22 + n33
    prod = btr * brt
    d1, d2 = h11 - meas[:, 0], h12 - meas[:, 1]
    # d_j (xy − P) = a_j y + e_j x + f_j
    a1, a2 = h12 * h21, h12 * h22
    e1, e2 = l12 * n21, l12 * n22
    f1 = -h12 * n21 * btr - l12 * h21 * brt
    f2 = -h12 * n22 * btr - l12 * h22 * brt
    with np.errstate(divide="ignore", invalid="ignore"):
        den = d2 * a1 - d1 * a2
        alpha = -(d2 * e1 - d1 * e2) / den
        beta = -(d2 * f1 - d1 * f2) / den
        x1, x2 = _quadratic_roots(d1 * alpha, d1 * beta - a1 * alpha - e1, -d1 * prod - a1 * beta - f1)
        xs = np.stack([x1, x2], axis=1)
        ys = alpha[:, None] * xs + beta[:, None]
        ht = xs - (h22 + h33)[:, None]
        hr = ys - (p22 + p33)[:, None]
    finite = np.isfinite(ht) & np.isfinite(hr)
    passive = (
        finite
        & (ht.imag <= passivity_tol * np.abs(ht))
        & (hr.imag <= passivity_tol * np.abs(hr))
    )
    # Each candidate re-coupled: the elimination can introduce a spurious root
    # that solves the quadratic but not the coupling equations.
    h_b = np.stack([np.stack([h11, h21, n21], 1), np.stack([h12, h22, n22], 1)], axis=2)  # (nf, 3, 2)
    cand_res = np.stack(
        [_recouple_residual(np.where(finite[:, k], ht[:, k], 0), np.where(finite[:, k], hr[:, k], 0),
                            h_b, h12, l12, h22, h33, p22, p33, btr, brt, meas) for k in range(2)],
        axis=1,
    )
    cand_res = np.where(finite, cand_res, np.inf)
    consistent = cand_res <= consistency_tol
    ok = consistent & passive
    n_ok = ok.sum(axis=1)
    clear = n_ok == 1
    choice = np.where(clear, np.argmax(ok, axis=1), np.argmin(cand_res, axis=1))
    # several consistent and passive roots: decide by continuity
    ambiguous = n_ok >= 2
    idx = np.arange(freq.size)
    if ambiguous.any() and clear.any():
        clear_idx = idx[clear]
        amb = idx[ambiguous]
        pos = np.clip(np.searchsorted(clear_idx, amb), 0, clear_idx.size - 1)
        left = clear_idx[np.clip(pos - 1, 0, clear_idx.size - 1)]
        right = clear_idx[pos]
        nearest = np.where(np.abs(amb - left) <= np.abs(right - amb), left, right)
        ref_t = ht[nearest, choice[nearest]]
        ref_r = hr[nearest, choice[nearest]]
        with np.errstate(divide="ignore", invalid="ignore"):
            dist = np.abs(np.log(ht[amb] / ref_t[:, None])) + np.abs(np.log(hr[amb] / ref_r[:, None]))
        dist = np.where(np.isfinite(dist) & ok[amb], dist, np.inf)
        choice[amb] = np.argmin(dist, axis=1)
    h_t = ht[idx, choice]
    h_r = hr[idx, choice]
    x = xs[idx, choice]
    y = ys[idx, choice]
    degenerate = ~np.isfinite(h_t) | ~np.isfinite(h_r)
    # Jacobian of F_j(x, y) = d_j (xy − P) − a_j y − e_j x − f_j at the chosen root
    jac = np.empty((freq.size, 2, 2), dtype=complex)
    jac[:, 0, 0], jac[:, 0, 1] = d1 * y - e1, d1 * x - a1
    jac[:, 1, 0], jac[:, 1, 1] = d2 * y - e2, d2 * x - a2
    jac = np.where(np.isfinite(jac), jac, 0.0)
    s = np.linalg.svd(jac, compute_uv=False)
    with np.errstate(divide="ignore", invalid="ignore"):
        cond = np.where(s[:, 1] > 0, s[:, 0] / s[:, 1], np.inf)
    non_passive = ~passive[idx, choice] & ~degenerate
    inconsistent = ~consistent[idx, choice] & ~degenerate
    ill = cond > condition_limit
    values = np.zeros((freq.size, 2, 2), dtype=complex)
    values[:, 0, 0], values[:, 1, 1] = h_t, h_r
    values = fill_bad_lines(values, degenerate, freq, "planar joint identification")
    joint = FRF(freq, values, p3, p3, Quantity.RECEPTANCE)

    residual = _recouple_residual(
        values[:, 0, 0], values[:, 1, 1], h_b, h12, l12, h22, h33, p22, p33, btr, brt, meas
    )
    flags = {
        "ambiguous": ambiguous,
        "non_passive": non_passive,
        "inconsistent": inconsistent,
        "ill_conditioned": ill,
        "degenerate": degenerate,
    }
    unreliable = ambiguous | non_passive | inconsistent | ill | degenerate
    return IdentificationResult(
        joint=joint,
        model="planar",
        residual=residual,
        condition=np.where(np.isfinite(cond), cond, np.inf),
        unreliable=unreliable,
        flags=flags,
        extra={"roots_x": xs, "roots_y": ys, "choice": choice},
        settings={
            "a_point": a_point,
            "b_contact": b_contact,
            "b_tip": b_tip,
            "translation": t,
            "rotation": r,
            "smoothing": smoothing,
            "smoothing_order": smoothing_order,
            "passivity_tol": passivity_tol,
            "condition_limit": condition_limit,
            "consistency_tol": consistency_tol,
        },
    )
