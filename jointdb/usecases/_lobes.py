"""Stability lobes of a tool-tip FRF over a grid of spindle speeds (milling ZOA or SD, or turning)."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence
from typing import Any

from jointdb.errors import InputError
from jointdb.frf import FRF

#: Chunks of speeds the SD method is solved in (each a step of the caller's progress).
SD_CHUNKS = 25


def sd_lobes_in_chunks(model, cut, speeds, intervals: int,
                       progress: Callable[[Iterable], Iterable] = lambda steps: steps, n_chunks: int = SD_CHUNKS):
    """``stability.milling_lobes_sd`` over ``speeds`` [rpm] in ``n_chunks`` chunks, each a step of ``progress``.

    Each speed is solved independently (same start depth, which depends only on the model
    and the cut), so the result equals one call over all speeds.
    """
    import numpy as np

    from jointdb.stability import LobeResult, milling_lobes_sd

    chunks = np.array_split(speeds, min(n_chunks, speeds.size))
    parts = [milling_lobes_sd(model, cut, chunk, n_intervals=intervals) for chunk in progress(chunks)]
    info = dict(parts[0].info)
    info["evaluations"] = int(sum(p.info.get("evaluations", 0) for p in parts))
    return LobeResult(parts[0].method, *(np.concatenate([getattr(p, a) for p in parts]) for a in
                      ("spindle_speed_rpm", "depth_m", "chatter_freq_hz", "lobe", "kind")), (), info)


def stability_lobes(frf: FRF, op: str = "milling", *, rpm_min: float = 2000.0, rpm_max: float = 20000.0,
                    n_speeds: int = 300, kf: float | None = None, teeth: int = 2, kt: float | None = None,
                    kr: float | None = None, immersion: float = 1.0, up: bool = False, refine: int = 0,
                    frf_y: FRF | None = None, cross_terms: bool = False, orientation: Sequence[float] | None = None,
                    method: str = "zoa", tip_model: Any = None, intervals: int = 40,
                    progress: Callable[[Iterable], Iterable] = lambda steps: steps):
    """Stability lobes of a tool-tip FRF: turning (Tlusty) or milling (zero-order approximation or
    semi-discretization).

    Parameters
    ----------
    frf
        Tool-tip receptance [m/N] at the cutting point, shape ``(n_freq, n, n)``.
    op
        ``"milling"`` or ``"turning"``.
    rpm_min, rpm_max, n_speeds
        Spindle-speed grid [rev/min], ``n_speeds`` evenly spaced speeds, ``0 < rpm_min < rpm_max``.
    kf
        Turning: cutting coefficient [N/m²].
    teeth, kt, kr, immersion, up
        Milling: number of teeth, tangential and radial coefficients [N/m²], radial immersion
        a_e/D in (0, 1], up-milling (default down-milling).
    refine
        Rounds of extra speeds near the lobes' minima and pockets (0: the grid only).
    frf_y
        Milling ZOA: a separate y-direction tool-tip FRF [m/N] (default: the x one, axisymmetric).
    cross_terms
        Milling ZOA: use the x–y cross FRFs of ``frf``.
    orientation
        Turning: directional factor per driving point (default 1 each).
    method
        Milling: ``"zoa"`` (from the FRF) or ``"sd"`` (from ``tip_model``).
    tip_model
        Milling SD: the fitted modal model of the tool tip (:func:`jointdb.modal.fit_tool_tip`).
    intervals
        Milling SD: intervals per tooth period.
    progress
        Wraps the SD method's chunks of speeds (e.g. a progress bar); identity by default.

    Returns
    -------
    jointdb.stability.LobeResult
        Limiting depth [m] and chatter frequency [Hz] per speed (``table()`` rows).

    Raises
    ------
    InputError
        A bad speed range or method, or the coefficients (or the modal model) of the
        operation missing.
    """
    import numpy as np

    from jointdb import stability

    if not (math.isfinite(rpm_max) and 0 < rpm_min < rpm_max):
        raise InputError("need finite 0 < rpm_min < rpm_max")
    speeds = np.linspace(rpm_min, rpm_max, n_speeds)

    def on_speeds(compute):  # rounds=0: the grid only (and info["refined_speeds"] = 0)
        return stability.refine_lobes(compute, speeds, rounds=refine)

    if op == "turning":
        if kf is None:
            raise InputError("turning needs kf (cutting coefficient in N/m²)")
        return on_speeds(lambda s: stability.turning_lobes(frf, kf, orientation, spindle_speed_rpm=s))
    if op != "milling":
        raise InputError(f"op must be milling or turning, got {op!r}")
    if kt is None or kr is None:
        raise InputError("milling needs kt and kr (cutting coefficients in N/m²)")
    cut = stability.MillingCut(teeth, kt, kr, immersion, not up)
    if method == "sd":
        if tip_model is None:
            raise InputError("milling by semi-discretization needs the tool tip's modal model")
        return on_speeds(lambda s: sd_lobes_in_chunks(tip_model, cut, s, intervals, progress))
    if method != "zoa":
        raise InputError(f"method must be zoa or sd, got {method!r}")
    return on_speeds(lambda s: stability.milling_lobes_zoa(frf, cut, frf_y, cross_terms=cross_terms,
                                                           spindle_speed_rpm=s))
