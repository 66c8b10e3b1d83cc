"""Adaptive spindle-speed sampling of a lobe diagram: more speeds where the envelope turns.

A uniform speed grid draws the lobe envelope as a coarse polyline exactly where
it matters: at the bottoms of the lobes (the limiting depths) and at the
pockets between lobes (the best speeds). :func:`refine_lobes` computes the
lobes on the given speeds, then, a few rounds, adds the midpoints of the two
intervals on either side of every local minimum and maximum of the limiting
depth and computes only those new speeds.

Every lobe method computes each spindle speed on its own (turning and ZOA
evaluate the lobe curves at the speed; SD solves one critical depth per
speed), so the refined result equals the plain computation at every speed they
share — the refinement only adds speeds.

Speeds whose boundary is a fold (kind ``"fold"``, a real Floquet multiplier
+1 — not a chatter limit: a tooth-periodic motion is not regenerated) and
non-finite depths are ignored when looking for turning points.
"""

from __future__ import annotations

import logging
from collections.abc import Callable

import numpy as np

from jointdb.stability._results import LobeResult, spindle_speeds

__all__ = ["refine_lobes", "merge_lobe_results", "plottable_depth"]

log = logging.getLogger(__name__)


def plottable_depth(result: LobeResult) -> np.ndarray:
    """Limiting depth [m] with folds and non-finite values as NaN (what a lobe plot may draw).

    Parameters
    ----------
    result
        Lobes from any of the methods (a :class:`LobeResult`), folds included.

    Returns
    -------
    ndarray, shape (n,)
        Depth [m] per speed of ``result``.
    """
    d = np.where(np.isfinite(result.depth_m), result.depth_m, np.nan)
    return np.where(result.kind == "fold", np.nan, d)


def merge_lobe_results(a: LobeResult, b: LobeResult) -> LobeResult:
    """The rows of two results of the same computation, sorted by speed (``a``'s lobes and info kept).

    Parameters
    ----------
    a, b
        :class:`LobeResult` s of one method at different speeds.

    Returns
    -------
    LobeResult
        All rows, by ascending speed; ``info["evaluations"]`` is summed.

    Raises
    ------
    ValueError
        If the two results were made by different methods or share a speed.
    """
    if a.method != b.method:
        raise ValueError(f"cannot merge {a.method} and {b.method} lobes")
    speed = np.concatenate([a.spindle_speed_rpm, b.spindle_speed_rpm])
    order = np.argsort(speed, kind="stable")
    if np.any(np.diff(speed[order]) == 0):
        raise ValueError("merged lobe results share a spindle speed")
    cols = [np.concatenate([getattr(a, name), getattr(b, name)])[order]
            for name in ("spindle_speed_rpm", "depth_m", "chatter_freq_hz", "lobe", "kind")]
    info = dict(a.info)
    if "evaluations" in a.info or "evaluations" in b.info:
        info["evaluations"] = int(a.info.get("evaluations", 0)) + int(b.info.get("evaluations", 0))
    return LobeResult(a.method, *cols, a.lobes, info)


def _turning_points(speed: np.ndarray, depth: np.ndarray) -> np.ndarray:
    """Indices of interior local minima and maxima of ``depth`` over its finite points."""
    ok = np.flatnonzero(np.isfinite(depth))
    if ok.size < 3:
        return np.array([], dtype=int)
    d = depth[ok]
    left, mid, right = d[:-2], d[1:-1], d[2:]
    turn = ((mid <= left) & (mid <= right)) | ((mid >= left) & (mid >= right))
    return ok[1:-1][turn]


def refine_lobes(
    compute: Callable[[np.ndarray], LobeResult],
    spindle_speed_rpm,
    *,
    rounds: int = 3,
    min_step_rpm: float = 0.5,
) -> LobeResult:
    """Lobes on ``spindle_speed_rpm`` plus speeds added around the envelope's minima and maxima.

    Parameters
    ----------
    compute
        Speeds [rpm], shape ``(n,)`` → :class:`LobeResult` on exactly those speeds
        (e.g. ``lambda s: milling_lobes_zoa(frf, cut, spindle_speed_rpm=s)``).
    spindle_speed_rpm
        Base speeds [rpm]; always part of the result, with the same values as
        ``compute(spindle_speed_rpm)``.
    rounds
        Refinement rounds; each adds at most two speeds per turning point
        (0: the plain computation).
    min_step_rpm
        Intervals narrower than this [rpm] are not split further.

    Returns
    -------
    LobeResult
        Sorted by speed; ``info["refined_speeds"]`` is the number of speeds added.

    Raises
    ------
    InputError
        Bad speeds (as the lobe functions), ``rounds < 0``.
    """
    from jointdb.errors import InputError

    if int(rounds) != rounds or rounds < 0:
        raise InputError(f"refinement rounds must be a whole number >= 0, got {rounds}")
    base = spindle_speeds(spindle_speed_rpm)
    result = compute(base)
    added = 0
    for r in range(int(rounds)):
        speed, depth = result.spindle_speed_rpm, plottable_depth(result)
        new = []
        for i in _turning_points(speed, depth):
            for j in (i - 1, i):
                if speed[j + 1] - speed[j] >= 2 * min_step_rpm:
                    new.append(0.5 * (speed[j] + speed[j + 1]))
        new = np.setdiff1d(np.unique(np.asarray(new, dtype=float)), speed)
        if new.size == 0:
            break
        log.debug("lobe refinement round %d: %d new speeds", r + 1, new.size)
        result = merge_lobe_results(result, compute(new))
        added += int(new.size)
    log.info("lobes: %d base speeds, %d added near minima and maxima of the envelope", base.size, added)
    info = dict(result.info, refined_speeds=added)
    return LobeResult(result.method, result.spindle_speed_rpm, result.depth_m, result.chatter_freq_hz,
                      result.lobe, result.kind, result.lobes, info)
