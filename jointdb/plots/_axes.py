"""Small drawing helpers shared by the figures: phase without wrap bars, robust axis limits."""

from __future__ import annotations

import numpy as np

__all__ = ["phase_deg", "phase_unwrapped", "robust_limits", "plot_clipped", "percent"]


def phase_deg(freq, h) -> tuple[np.ndarray, np.ndarray]:
    """Phase of ``h`` in degrees in (−180, 180], with the line broken where it wraps.

    A wrap (a jump of more than 180° between neighbouring lines) gets a NaN
    inserted between the two points, so a plotted line stops at ±180° instead of
    drawing a vertical bar across the axis.

    Parameters
    ----------
    freq
        Frequencies [Hz], ``(n,)``.
    h
        Complex FRF values, ``(n,)``.

    Returns
    -------
    (freq, phase)
        Arrays of equal length (``len(freq)`` plus one per wrap).
    """
    f = np.asarray(freq, dtype=float)
    p = np.degrees(np.angle(np.asarray(h)))
    jumps = np.flatnonzero(np.abs(np.diff(p)) > 180.0) + 1
    if jumps.size == 0:
        return f, p
    return np.insert(f, jumps, np.nan), np.insert(p, jumps, np.nan)


def phase_unwrapped(freq, h, reference: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """Phase of ``h`` in degrees, continuous along frequency (no ±180° wraps), on a shared branch.

    Noisy measured phase near ±180° wraps back and forth; wrapped, it draws as scattered bars,
    broken, as dashes at both edges. Unwrapped it is one line. The whole curve is then shifted by a
    multiple of 360° so that it lies on the branch of ``reference`` (the median difference over the
    common band within ±180°), or, without one, so that its first value is in (−180°, 180°].

    Parameters
    ----------
    freq
        Frequencies [Hz], ``(n,)``, ascending.
    h
        Complex FRF values, ``(n,)``.
    reference
        ``(freq, phase_deg)`` of a curve already unwrapped, to share its branch; or None.

    Returns
    -------
    ndarray, shape (n,)
        Phase [deg]; NaN where ``h`` is not finite or zero.
    """
    f = np.asarray(freq, dtype=float)
    h = np.asarray(h)
    ok = np.isfinite(h) & (h != 0)
    p = np.full(f.size, np.nan)
    if not ok.any():
        return p
    p[ok] = np.degrees(np.unwrap(np.angle(h[ok])))
    if reference is not None:
        rf, rp = (np.asarray(v, dtype=float) for v in reference)
        common = ok & (f >= np.nanmin(rf)) & (f <= np.nanmax(rf))
        good = np.isfinite(rp)
        if common.any() and good.sum() > 1:
            diff = np.nanmedian(p[common] - np.interp(f[common], rf[good], rp[good]))
            return p - 360.0 * np.round(diff / 360.0)
    first = p[ok][0]
    return p - 360.0 * np.ceil((first - 180.0) / 360.0)


def robust_limits(y, *, lower_pct: float = 2.0, upper_pct: float = 98.0, margin: float = 0.15,
                  include_zero: bool = False) -> tuple[float, float] | None:
    """Axis limits from percentiles of the finite values (single spikes do not set the scale).

    Parameters
    ----------
    y
        The values to be plotted (non-finite ones are ignored).
    lower_pct, upper_pct
        Percentiles (0–100) that set the range.
    margin
        Fraction of the range added on each side.
    include_zero
        Widen the range to include 0.

    Returns
    -------
    (low, high) or None
        The limits; None when no value is finite.
    """
    v = np.asarray(y, dtype=float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return None
    lo, hi = np.percentile(v, [lower_pct, upper_pct])
    if include_zero:
        lo, hi = min(lo, 0.0), max(hi, 0.0)
    span = hi - lo if hi > lo else (abs(hi) or 1.0)
    return float(lo - margin * span), float(hi + margin * span)


def plot_clipped(ax, x, y, limits, **line_kw):
    """Plot ``y`` against ``x`` within ``limits``; values outside are triangles on the edge, not line.

    Returns the number of clipped points (also put in the legend as "n clipped").
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    if limits is None:
        ax.plot(x, y, **line_kw)
        return 0
    lo, hi = limits
    above, below = y > hi, y < lo
    # the line stops at off-scale values (no bars running into the edge); a marker on the edge shows each
    line, = ax.plot(x, np.where(above | below, np.nan, y), **line_kw)
    colour = line.get_color()
    if above.any():
        ax.plot(x[above], np.full(above.sum(), hi), "^", color=colour, ms=4, clip_on=False)
    if below.any():
        ax.plot(x[below], np.full(below.sum(), lo), "v", color=colour, ms=4, clip_on=False)
    n = int(above.sum() + below.sum())
    if n:
        ax.plot([], [], "^", color=colour, ms=4, label=f"{n} values off scale (at the edge)")
    ax.set_ylim(lo, hi)
    return n


def percent(x: float) -> str:
    """A relative width as a percentage a reader sees as non-zero: ``0.05 → "5.0%"``, ``0.0005 → "0.05%"``."""
    return f"{x:.1%}" if abs(x) >= 0.01 or x == 0 else f"{100 * x:.2g}%"
