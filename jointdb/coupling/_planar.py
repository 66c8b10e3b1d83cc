"""Planar spring–damper joint from two translational assembly FRFs (docs/theory.md §2a, thesis §4.2).

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
"""

from __future__ import annotations

import numpy as np

from jointdb.coupling._common import IdentificationResult, fetch, fill_bad_lines, receptances_on_one_grid
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


def identify_planar_joint(
    assembly: FRF, substructure_a: FRF, a_point: int, substructure_b: FRF, b_contact: int, b_tip: int, *,
    translation: str = "x", rotation: str = "ry", smoothing: int | None = None, smoothing_order: int = 4,
    passivity_tol: float = 1e-6, condition_limit: float = 1e8, consistency_tol: float = 1e-6,
) -> IdentificationResult:
    """Identify a planar spring–damper joint ``diag(h_t, h_r)`` (docs/theory.md §2a, thesis eq. 4.12–4.13).

    How (quadratic elimination, root choice by passivity, re-coupling and continuity): see the
    module docstring.

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
    smoothing_order
        Polynomial order of the Savitzky–Golay filter.
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

    Examples
    --------
    A carbide tool (B: free beam, tip node 1, face node 2) held by a steel holder (A: clamped
    beam, nose node 3) through a spring–damper joint of known stiffness and damping; the
    "measured" tip FRFs are coupled from them, and the identification gets the joint back:

    >>> import numpy as np
    >>> from jointdb.fe import BeamModel, Segment, NamedPoint, Clamp, HystereticDamping
    >>> from jointdb.coupling import (Interface, couple, spring_damper_joint, identify_planar_joint,
    ...                               fit_constant_kc)
    >>> freq = np.linspace(200.0, 3000.0, 15)                                    # Hz
    >>> holder = BeamModel(segments=(Segment(0.1, 0.04, material="steel"),),
    ...                    points=(NamedPoint("nose", 0.0, node=3),),
    ...                    ingredients=(Clamp(0.1), HystereticDamping(0.002)))
    >>> tool = BeamModel(segments=(Segment(0.06, 0.012, material="carbide"),),
    ...                  points=(NamedPoint("tip", 0.0, node=1), NamedPoint("face", 0.06, node=2)))
    >>> A, B = holder.frf(freq, points=["nose"]), tool.frf(freq, points=["tip", "face"])
    >>> true_joint = spring_damper_joint(freq, k=[2e7, 5e5], c=[200.0, 5.0], dofs_=["3x", "3ry"])
    >>> measured = couple({"A": A, "B": B},
    ...                   [Interface("A", ["3x", "3ry"], "B", ["2x", "2ry"], joint=true_joint)],
    ...                   outputs=[("B", "1x"), ("B", "2x")], inputs=[("B", "1x")])
    >>> result = identify_planar_joint(measured, A, 3, B, b_contact=2, b_tip=1)
    >>> [str(dof) for dof in result.joint.outputs], int(result.unreliable.sum())
    (['3x', '3ry'], 0)
    >>> fit = fit_constant_kc(result.joint)
    >>> fit.k.round(-2), fit.c.round(3)                       # N/m, N·m/rad; N·s/m, N·m·s/rad
    (array([20000000.,   500000.]), array([200.,   5.]))
    """
    t, r = translation, rotation
    _check_points(t, r, b_contact, b_tip)
    freq, p3, HB, H33, meas = _blocks(assembly, substructure_a, a_point, substructure_b, b_contact, b_tip, t, r)
    if smoothing:
        meas = savgol_smooth(meas, int(smoothing), smoothing_order)
    eq = _Equations(HB, H33, meas)
    h_t, h_r, cond, flags, extra = _solve(eq, passivity_tol, consistency_tol, condition_limit)
    settings = {"a_point": a_point, "b_contact": b_contact, "b_tip": b_tip, "translation": t, "rotation": r,
                "smoothing": smoothing, "smoothing_order": smoothing_order, "passivity_tol": passivity_tol,
                "condition_limit": condition_limit, "consistency_tol": consistency_tol}
    values = np.zeros((freq.size, 2, 2), dtype=complex)
    values[:, 0, 0], values[:, 1, 1] = h_t, h_r
    values = fill_bad_lines(values, flags["degenerate"], freq, "planar joint identification")
    return IdentificationResult(
        joint=FRF(freq, values, p3, p3, Quantity.RECEPTANCE), model="planar",
        residual=eq.recouple_residual(values[:, 0, 0], values[:, 1, 1]),
        condition=np.where(np.isfinite(cond), cond, np.inf), unreliable=np.logical_or.reduce(list(flags.values())),
        flags=flags, extra=extra, settings=settings,
    )


def _check_points(t: str, r: str, b_contact: int, b_tip: int) -> None:
    """InputError unless ``t`` is a translation, ``r`` a rotation and the tip another node than the contact."""
    if Dof(0, t).is_rotation or not Dof(0, r).is_rotation:
        raise InputError(f"translation {t!r} must be a translation and rotation {r!r} a rotation direction")
    if b_contact == b_tip:
        raise InputError(f"b_contact and b_tip are both node {b_tip}; the tip must be another node of B")


def _solve(eq: "_Equations", passivity_tol: float, consistency_tol: float, condition_limit: float) -> tuple:
    """The chosen root per line: ``h_t``, ``h_r``, the condition number, the flags (ambiguous,
    non_passive, inconsistent, ill_conditioned, degenerate) and both roots with the choice."""
    xs, ys, ht, hr = eq.roots()
    passive, consistent, cand_res = eq.judge(ht, hr, passivity_tol, consistency_tol)
    choice, ambiguous = _choose_roots(consistent & passive, cand_res, ht, hr)
    idx = np.arange(xs.shape[0])
    h_t = ht[idx, choice]
    h_r = hr[idx, choice]
    degenerate = ~np.isfinite(h_t) | ~np.isfinite(h_r)
    cond = eq.condition(xs[idx, choice], ys[idx, choice])
    flags = {"ambiguous": ambiguous, "non_passive": ~passive[idx, choice] & ~degenerate,
             "inconsistent": ~consistent[idx, choice] & ~degenerate, "ill_conditioned": cond > condition_limit,
             "degenerate": degenerate}
    return h_t, h_r, cond, flags, {"roots_x": xs, "roots_y": ys, "choice": choice}


def _blocks(assembly, substructure_a, a_point, substructure_b, b_contact, b_tip, t, r):
    """The grid, A's contact DOFs, B's tip/contact block, A's contact block and the measured
    ``G_11``, ``G_12`` ``(nf, 2)`` (InputError naming what is missing)."""
    freq, G, A, B = receptances_on_one_grid(assembly, substructure_a, substructure_b)
    p3 = [Dof(a_point, t), Dof(a_point, r)]
    p1t, p1r, p2t, p2r = Dof(b_tip, t), Dof(b_tip, r), Dof(b_contact, t), Dof(b_contact, r)
    H33 = fetch("substructure A", A, p3, p3, "the contact block incl. rotations is needed")
    HB = fetch("substructure B", B, [p1t, p1r, p2t, p2r], [p1t, p1r, p2t, p2r], "tip and contact, incl. rotations")
    meas = np.stack(
        [fetch("assembly", G, [p1t], [p1t])[:, 0, 0], fetch("assembly", G, [p1t], [p2t])[:, 0, 0]], axis=1
    )
    return freq, p3, HB, H33, meas


class _Equations:
    """The two bilinear coupling equations of one planar identification, per line.

    ``d_j (xy − P) = a_j y + e_j x + f_j`` (j = 1, 2) in ``x = h_22 + h_33 + h_t`` and
    ``y = p_22 + p_33 + h_r``, from B's tip/contact block ``HB (nf, 4, 4)`` (tip t, tip r,
    contact t, contact r), A's contact block ``H33 (nf, 2, 2)`` and the measured tip FRFs
    ``meas (nf, 2)`` (``G_11``, ``G_12``).
    """

    def __init__(self, HB: np.ndarray, H33: np.ndarray, meas: np.ndarray) -> None:
        self.meas = meas
        h11, h12, l12 = HB[:, 0, 0], HB[:, 0, 2], HB[:, 0, 3]
        h21, n21 = HB[:, 2, 0], HB[:, 3, 0]
        h22, l22, n22, p22 = HB[:, 2, 2], HB[:, 2, 3], HB[:, 3, 2], HB[:, 3, 3]
        h33, l33, n33, p33 = H33[:, 0, 0], H33[:, 0, 1], H33[:, 1, 0], H33[:, 1, 1]
        self.h12, self.l12 = h12, l12
        self.x0, self.y0 = h22 + h33, p22 + p33          # x and y without the joint
        self.btr, self.brt = l22 + l33, n22 + n33
        self.prod = self.btr * self.brt
        self.d1, self.d2 = h11 - meas[:, 0], h12 - meas[:, 1]
        self.a1, self.a2 = h12 * h21, h12 * h22
        self.e1, self.e2 = l12 * n21, l12 * n22
        self.f1 = -h12 * n21 * self.btr - l12 * h21 * self.brt
        self.f2 = -h12 * n22 * self.btr - l12 * h22 * self.brt
        self.h_b = np.stack([np.stack([h11, h21, n21], 1), np.stack([h12, h22, n22], 1)], axis=2)  # (nf, 3, 2)

    def roots(self):
        """Both roots ``(x, y)`` per line, reduced to a quadratic in x, and the joint terms
        ``h_t``, ``h_r`` they give: four ``(nf, 2)`` arrays."""
        d1, d2, a1, a2, e1, e2, f1, f2 = self.d1, self.d2, self.a1, self.a2, self.e1, self.e2, self.f1, self.f2
        with np.errstate(divide="ignore", invalid="ignore"):
            den = d2 * a1 - d1 * a2
            alpha = -(d2 * e1 - d1 * e2) / den
            beta = -(d2 * f1 - d1 * f2) / den
            x1, x2 = _quadratic_roots(d1 * alpha, d1 * beta - a1 * alpha - e1, -d1 * self.prod - a1 * beta - f1)
            xs = np.stack([x1, x2], axis=1)
            ys = alpha[:, None] * xs + beta[:, None]
            ht = xs - self.x0[:, None]
            hr = ys - self.y0[:, None]
        return xs, ys, ht, hr

    def judge(self, ht: np.ndarray, hr: np.ndarray, passivity_tol: float, consistency_tol: float):
        """Per root ``(nf, 2)``: passive (``Im h ≤ tol·|h|`` for both terms), consistent (re-coupling
        reproduces the measurement to ``consistency_tol``) and the re-coupling residual."""
        finite = np.isfinite(ht) & np.isfinite(hr)
        passive = (
            finite
            & (ht.imag <= passivity_tol * np.abs(ht))
            & (hr.imag <= passivity_tol * np.abs(hr))
        )
        # Each candidate re-coupled: the elimination can introduce a spurious root
        # that solves the quadratic but not the coupling equations.
        cand_res = np.stack(
            [self.recouple_residual(np.where(finite[:, k], ht[:, k], 0), np.where(finite[:, k], hr[:, k], 0))
             for k in range(2)],
            axis=1,
        )
        cand_res = np.where(finite, cand_res, np.inf)
        return passive, cand_res <= consistency_tol, cand_res

    def recouple_residual(self, h_t: np.ndarray, h_r: np.ndarray) -> np.ndarray:
        """Relative residual of ``G_1j = h_1j − v B⁻¹ u_j`` (j = 1, 2) against the measurement."""
        bm = np.empty((h_t.size, 2, 2), dtype=complex)
        bm[:, 0, 0] = self.x0 + h_t
        bm[:, 0, 1], bm[:, 1, 0] = self.btr, self.brt
        bm[:, 1, 1] = self.y0 + h_r
        v = np.stack([self.h12, self.l12], axis=1)[:, None, :]
        rec = self.h_b[:, 0, :] - (v @ pinv(bm) @ self.h_b[:, 1:, :])[:, 0, :]
        meas = self.meas
        return np.linalg.norm(rec - meas, axis=1) / np.maximum(np.linalg.norm(meas, axis=1), 1e-300)

    def condition(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Condition number of the Jacobian of ``F_j(x, y) = d_j (xy − P) − a_j y − e_j x − f_j`` at a root."""
        jac = np.empty((x.size, 2, 2), dtype=complex)
        jac[:, 0, 0], jac[:, 0, 1] = self.d1 * y - self.e1, self.d1 * x - self.a1
        jac[:, 1, 0], jac[:, 1, 1] = self.d2 * y - self.e2, self.d2 * x - self.a2
        jac = np.where(np.isfinite(jac), jac, 0.0)
        s = np.linalg.svd(jac, compute_uv=False)
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(s[:, 1] > 0, s[:, 0] / s[:, 1], np.inf)


def _choose_roots(ok: np.ndarray, cand_res: np.ndarray, ht: np.ndarray, hr: np.ndarray):
    """Per line, the root to keep (index 0 or 1) and whether the choice was ambiguous.

    The one root that is consistent and passive (``ok``); with none, the best re-coupling; with
    both, the one nearest (in log distance) to the choice at the nearest unambiguous line.
    """
    n_ok = ok.sum(axis=1)
    clear = n_ok == 1
    choice = np.where(clear, np.argmax(ok, axis=1), np.argmin(cand_res, axis=1))
    # several consistent and passive roots: decide by continuity
    ambiguous = n_ok >= 2
    idx = np.arange(ok.shape[0])
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
    return choice, ambiguous
