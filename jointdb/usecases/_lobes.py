"""Stability lobes of a tool-tip FRF over a grid of spindle speeds (milling ZOA, or turning)."""

from __future__ import annotations

import math

from jointdb.errors import InputError
from jointdb.frf import FRF


def stability_lobes(frf: FRF, op: str = "milling", *, rpm_min: float = 2000.0, rpm_max: float = 20000.0,
                    n_speeds: int = 300, kf: float | None = None, teeth: int = 2, kt: float | None = None,
                    kr: float | None = None, immersion: float = 1.0, up: bool = False, refine: int = 0):
    """Stability lobes of a tool-tip FRF: turning (Tlusty) or milling (zero-order approximation).

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

    Returns
    -------
    jointdb.stability.LobeResult
        Limiting depth [m] and chatter frequency [Hz] per speed (``table()`` rows).

    Raises
    ------
    InputError
        A bad speed range, or the coefficients of the operation missing.
    """
    import numpy as np

    from jointdb import stability

    if not (math.isfinite(rpm_max) and 0 < rpm_min < rpm_max):
        raise InputError("need finite 0 < rpm_min < rpm_max")
    speeds = np.linspace(rpm_min, rpm_max, n_speeds)

    def on_speeds(compute):
        return compute(speeds) if not refine else stability.refine_lobes(compute, speeds, rounds=refine)

    if op == "turning":
        if kf is None:
            raise InputError("turning needs kf (cutting coefficient in N/m²)")
        return on_speeds(lambda s: stability.turning_lobes(frf, kf, None, spindle_speed_rpm=s))
    if op != "milling":
        raise InputError(f"op must be milling or turning, got {op!r}")
    if kt is None or kr is None:
        raise InputError("milling needs kt and kr (cutting coefficients in N/m²)")
    cut = stability.MillingCut(teeth, kt, kr, immersion, not up)
    return on_speeds(lambda s: stability.milling_lobes_zoa(frf, cut, spindle_speed_rpm=s))
