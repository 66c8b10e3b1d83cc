"""``jointdb rotations``: a contact point's rotational receptances from translational measurements.

Wraps the two estimates of :mod:`jointdb.coupling.rotational` (extension
method; finite differences) for files, and measures how much they amplify
measurement noise: the estimate is repeated on copies of the measured FRFs
with seeded relative complex noise of level ``ε`` added, and the
amplification of an entry is its RMS relative change divided by ``ε``
(1 = the rotations are as accurate as the measurements; 30 = a 1 % noise
becomes a 30 % error). Reported per entry (``h = x/F``, ``n = θ/F``,
``p = θ/M``) as the median and the 90th percentile over the frequency lines.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from jointdb.errors import InputError
from jointdb.frf import FRF

__all__ = ["RotationEstimate", "estimate_rotations", "noise_amplification"]

_ENTRIES = {"h": (0, 0), "n": (1, 0), "p": (1, 1)}


@dataclass(frozen=True, eq=False)
class RotationEstimate:
    """The 2×2 contact-point receptance and its noise amplification.

    ``amplification`` maps ``h``, ``n``, ``p`` to ``(median, p90)`` over the lines;
    ``condition`` is the extension method's per-line condition number (or None).
    """

    frf: FRF
    method: str
    amplification: dict[str, tuple[float, float]]
    noise_level: float
    trials: int
    condition: np.ndarray | None = None

    def rows(self) -> list[dict]:
        return [{"entry": k, "meaning": m, "amplification_median": a[0], "amplification_p90": a[1]}
                for (k, a), m in zip(self.amplification.items(), ("x/F", "θ/F", "θ/M"))]


def noise_amplification(estimate: Callable[[FRF], FRF], measured: FRF, reference: FRF, level: float = 0.01,
                        trials: int = 20, seed: int = 0) -> dict[str, tuple[float, float]]:
    """RMS relative change of ``h, n, p`` per unit relative noise on ``measured`` (median, 90th percentile).

    Parameters
    ----------
    estimate
        ``measured FRF -> 2×2 FRF`` (the estimator under test).
    measured
        The translational measurements the estimator reads.
    reference
        ``estimate(measured)`` (the noise-free estimate).
    level
        Relative complex noise level ε (> 0), e.g. 0.01 for 1 %.
    trials
        Number of noisy copies (>= 2).

    Raises
    ------
    InputError
        ``level`` not in (0, 1) or ``trials`` < 2.
    """
    if not (0 < level < 1):
        raise InputError(f"--noise must be between 0 and 1 (relative level, e.g. 0.01), got {level!r}")
    if trials < 2:
        raise InputError(f"--trials must be >= 2, got {trials}")
    rng = np.random.default_rng(seed)
    ref = reference.values
    sq = {k: np.zeros(ref.shape[0]) for k in _ENTRIES}
    for _ in range(trials):
        v = measured.values
        z = (rng.standard_normal(v.shape) + 1j * rng.standard_normal(v.shape)) / np.sqrt(2)
        noisy = estimate(measured.replace(values=v * (1 + level * z))).values
        for k, (i, j) in _ENTRIES.items():
            with np.errstate(divide="ignore", invalid="ignore"):
                sq[k] += np.abs(noisy[:, i, j] / ref[:, i, j] - 1.0) ** 2
    out = {}
    for k, s in sq.items():
        a = np.sqrt(s / trials) / level
        a = a[np.isfinite(a)]
        out[k] = (float(np.median(a)), float(np.percentile(a, 90))) if a.size else (float("nan"), float("nan"))
    return out


def estimate_rotations(measured: FRF, method: str, *, node: int, extension=None, joint_point: str | None = None,
                       points: tuple[str, str] | None = None, inner: int | None = None,
                       spacing: float | None = None, order: str = "first-order", noise: float = 0.01,
                       trials: int = 20, seed: int = 0) -> RotationEstimate:
    """Estimate the contact point's (x, ry) receptance and its noise amplification.

    Parameters
    ----------
    measured
        Translational FRFs: for ``"extension"`` G_11, G_12, G_22 at the extension's two measured
        points (node numbers of ``extension``'s named points); for ``"finite-difference"``
        h_33 and h_43 (and h_44 for ``order="second-order"``) at ``node`` and ``inner``.
    method
        ``"extension"`` or ``"finite-difference"``.
    node
        The contact point's node number (labels of the result; the measured node for finite differences).
    extension, joint_point, points
        Extension method: the extension's :class:`jointdb.fe.BeamModel`, its named point attached
        to the contact point, and its two measured named points.
    inner, spacing, order
        Finite differences: the second node, its distance [m] and ``first-order`` / ``second-order``.
    noise, trials, seed
        Noise amplification: relative level, number of noisy copies, seed.

    Raises
    ------
    InputError
        Unknown method, missing options (named as CLI flags), missing DOFs.
    NumericalError
        From the estimators (singular equations).
    """
    from jointdb.coupling import rotational

    measured = measured.to("receptance")
    cond = None
    if method == "extension":
        if extension is None or joint_point is None or points is None:
            raise InputError("the extension method needs --extension MODEL.json, --joint-point NAME and "
                             "--points NAME1,NAME2")
        pts = [extension.point(joint_point), *(extension.point(p) for p in points)]
        e_frf = extension.frf(measured.freq, [p.name for p in pts])
        e_nodes = (pts[1].node, pts[2].node)

        def run(m: FRF) -> FRF:
            return rotational.rotations_by_extension(m, e_frf, pts[0].node, e_nodes, node)[0]

        ref, cond = rotational.rotations_by_extension(measured, e_frf, pts[0].node, e_nodes, node)
    elif method == "finite-difference":
        if inner is None or spacing is None:
            raise InputError("the finite-difference method needs --inner NODE and --spacing METRES")

        def run(m: FRF) -> FRF:
            return rotational.rotations_by_finite_difference(m, node, inner, spacing, method=order)

        ref = run(measured)
    else:
        raise InputError(f"--method {method!r}: expected extension or finite-difference")
    amp = noise_amplification(run, measured, ref, noise, trials, seed)
    return RotationEstimate(ref, method, amp, noise, trials, cond)
