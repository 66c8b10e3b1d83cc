"""What a lobe figure draws: the envelope between the FRF lines, gap-free shading, the depth cap, the caption.

Pure numpy on :class:`jointdb.stability.LobeResult` (no matplotlib), so each piece is tested on its own.
"""

from __future__ import annotations

import numpy as np

__all__ = ["drawn_envelope", "densify_lobe", "shade_depth", "depth_cap", "cut_caption", "DRAWN_SPEEDS",
           "FLOOR_MULTIPLE"]

#: Speeds of the drawn envelope over the plotted range (plus every speed of the result).
DRAWN_SPEEDS = 2000

#: Without a flute length the depth axis stops at this multiple of the lowest limit (the floor).
FLOOR_MULTIPLE = 4.0


def _slopes(x: np.ndarray, y: np.ndarray, ok: np.ndarray) -> np.ndarray:
    """dy/dx at each point: centred where both neighbouring segments are valid, else one-sided."""
    with np.errstate(divide="ignore", invalid="ignore"):
        seg = np.where(ok, (y[1:] - y[:-1]) / (x[1:] - x[:-1]), np.nan)
        left = np.concatenate([[np.nan], seg])
        right = np.concatenate([seg, [np.nan]])
        both = np.concatenate([[False], ok[:-1] & ok[1:], [False]])
        centred = np.full(x.size, np.nan)
        centred[1:-1] = (y[2:] - y[:-2]) / (x[2:] - x[:-2])
    return np.where(both, centred, np.where(np.isfinite(right), right, left))


def _hermite(y0, y1, m0, m1, h, t):
    """Cubic Hermite interpolation on segments of length ``h`` at fractions ``t``."""
    t2, t3 = t * t, t * t * t
    return ((2 * t3 - 3 * t2 + 1) * y0 + (t3 - 2 * t2 + t) * h * m0 + (-2 * t3 + 3 * t2) * y1
            + (t3 - t2) * h * m1)


def densify_lobe(lobe, step_rpm: float, max_sub: int = 256):
    """One lobe with points added between its FRF lines, so that no segment spans more than ``step_rpm``.

    A lobe point on line ``f`` has speed ``n = 60 f / (N (k + ε/2π))`` and depth ``a = −1/(2 Re g)``.
    Between two lines ``Re g`` (so ``1/a``) and the phase ``ε`` (so ``f/n``) are interpolated in
    ``f`` by cubic Hermite curves (slopes from the neighbouring lines), and each added point is
    mapped to speed exactly. Near a resonance a few hertz of FRF span thousands of rpm on the low
    lobes: a straight line in (speed, depth) between two lines, or a kink at every line, is then
    visible; the FRF itself is smooth on the scale of its lines, and so is this.

    Parameters
    ----------
    lobe
        A :class:`jointdb.stability.Lobe` (points ordered by chatter frequency).
    step_rpm
        Largest speed step [rpm] of a segment after densifying.
    max_sub
        At most this many sub-segments per original segment.

    Returns
    -------
    (speed_rpm, depth_m, chatter_freq_hz)
        Arrays of equal length; NaN separates the densified segments.
    """
    n, a, f = (np.asarray(v, dtype=float) for v in (lobe.spindle_speed_rpm, lobe.depth_m, lobe.chatter_freq_hz))
    if n.size < 2:
        return n, a, f
    n0, n1 = n[:-1], n[1:]
    ok = np.isfinite(n0) & np.isfinite(n1) & np.isfinite(a[:-1]) & np.isfinite(a[1:]) & (n0 > 0) & (n1 > 0)
    # a jump of ε across 0/2π joins the ends of two different lobes (as in stability.envelope)
    ok &= np.abs(n1 - n0) <= 0.25 * np.maximum(np.abs(n0), np.abs(n1))
    idx = np.flatnonzero(ok)
    if idx.size == 0:
        return np.full(1, np.nan), np.full(1, np.nan), np.full(1, np.nan)
    with np.errstate(divide="ignore", invalid="ignore"):
        q, r = f / n, 1.0 / a                       # f/n: linear in ε; 1/a = −2 Re g
    mq, mr = _slopes(f, q, ok), _slopes(f, r, ok)
    m = np.clip(np.ceil(np.abs(n1[idx] - n0[idx]) / step_rpm), 1, max_sub).astype(int)
    per = m + 2                                     # m + 1 points and a NaN separator per segment
    seg = np.repeat(idx, per)
    j = np.arange(per.sum()) - np.repeat(np.cumsum(per) - per, per)
    mm = np.repeat(m, per)
    t = np.minimum(j, mm) / mm
    h = f[seg + 1] - f[seg]
    ff = f[seg] + t * h
    qq = _hermite(q[seg], q[seg + 1], mq[seg], mq[seg + 1], h, t)
    rr = _hermite(r[seg], r[seg + 1], mr[seg], mr[seg + 1], h, t)
    sep = j == mm + 1
    with np.errstate(divide="ignore", invalid="ignore"):
        speed = np.where(sep | (qq <= 0), np.nan, ff / qq)
        depth = np.where(sep | (rr <= 0), np.nan, 1.0 / rr)
    return speed, depth, np.where(sep, np.nan, ff)


def drawn_envelope(result, n_speeds: int = DRAWN_SPEEDS) -> tuple[np.ndarray, np.ndarray]:
    """The envelope a figure draws: on ``n_speeds`` even speeds plus the result's own, between FRF lines.

    For a frequency-domain result (turning, ZOA: ``result.lobes`` present) the lobes are densified
    (:func:`densify_lobe`) and their lower envelope is evaluated on the fine speeds; at the
    result's own speeds this differs from ``result.depth_m`` only by the interpolation between
    FRF lines. SD (no lobes) is drawn at its computed speeds, folds and non-finite depths as gaps.

    Parameters
    ----------
    result
        A :class:`jointdb.stability.LobeResult`.
    n_speeds
        Even speeds over the result's range.

    Returns
    -------
    (speed_rpm, depth_m)
        Ascending speeds ``(n,)`` and the depth [m] to draw (NaN: a gap).
    """
    from jointdb.stability import Lobe, envelope, plottable_depth

    s = np.asarray(result.spindle_speed_rpm, dtype=float)
    if not result.lobes or s.size < 2:
        return s, plottable_depth(result)
    lo, hi = float(s[0]), float(s[-1])
    step = (hi - lo) / n_speeds
    dense = []
    for lobe in result.lobes:
        n, a, f = densify_lobe(lobe, step)
        dense.append(Lobe(lobe.number, n, a, f, lobe.family))
    speeds = np.union1d(np.linspace(lo, hi, n_speeds + 1), s)
    depth, _, _ = envelope(tuple(dense), speeds)
    return speeds, depth


def shade_depth(depth: np.ndarray, top: float) -> np.ndarray:
    """Depth to shade as stable at each speed: no gaps where the line has none to draw.

    A gap of NaN (an SD fold, no lobe found) is shaded up to the lower of the nearest drawn depths
    on either side (the conservative choice; the line itself stays broken there); ``+inf`` (no limit
    below the search ceiling) is shaded to ``top``.

    Parameters
    ----------
    depth
        Limiting depth per speed (any unit), NaN where not drawn, ``inf`` where unlimited.
    top
        The top of the depth axis (same unit).

    Returns
    -------
    ndarray
        Finite everywhere when any depth is finite (else zeros).
    """
    d = np.where(np.isposinf(depth), top, np.asarray(depth, dtype=float))
    ok = np.isfinite(d)
    if not ok.any():
        return np.zeros_like(d)
    i = np.arange(d.size)
    left = np.maximum.accumulate(np.where(ok, i, -1))
    right = np.minimum.accumulate(np.where(ok, i, d.size)[::-1])[::-1]
    from_left = np.where(left >= 0, d[np.clip(left, 0, None)], np.nan)
    from_right = np.where(right < d.size, d[np.clip(right, None, d.size - 1)], np.nan)
    return np.where(ok, d, np.fmin(from_left, from_right))


def depth_cap(depths, floor: float, flute_length: float | None,
              multiple: float = FLOOR_MULTIPLE) -> tuple[float, str]:
    """Top of the depth axis and the sentence saying what set it.

    ``1.1 ×`` the largest drawn depth, but never above the flute length (when known; a deeper
    cut is impossible) nor, without it, above ``multiple ×`` the floor (pockets above that are
    clipped at the edge and their height stated).

    Parameters
    ----------
    depths
        Every depth drawn (one unit; NaN/inf ignored).
    floor
        The lowest limiting depth (same unit).
    flute_length
        The tool's flute (cutting) length in the same unit, or None.
    multiple
        Cap as a multiple of the floor when no flute length is given.

    Returns
    -------
    (top, note)
        ``note`` is empty when nothing was capped.
    """
    v = np.asarray(depths, dtype=float)
    v = v[np.isfinite(v)]
    top = 1.1 * float(v.max()) if v.size else 1.0
    if flute_length is not None and flute_length > 0:
        if top > flute_length:
            return float(flute_length), "depth axis capped at the flute length"
        return top, ""
    if np.isfinite(floor) and floor > 0 and top > multiple * floor:
        return multiple * floor, f"depth axis capped at {multiple:g} × the floor"
    return top, ""


def cut_caption(info: dict, method: str) -> str:
    """The cutting parameters of a lobe result as one line, from its ``info``.

    Parameters
    ----------
    info
        :attr:`jointdb.stability.LobeResult.info`.
    method
        ``"turning"``, ``"milling-zoa"`` or ``"milling-sd"``.

    Returns
    -------
    str
        E.g. ``"milling ZOA: 4 teeth, K_t 796 N/mm², K_r 169 N/mm², a_e/D 0.5, down-milling"``.
    """
    parts = []
    if "n_teeth" in info:
        parts.append(f"{info['n_teeth']} teeth")
    for key, name in (("kt", "K_t"), ("kr", "K_r"), ("kf", "K_f")):
        if info.get(key) is not None:
            parts.append(f"{name} {info[key] / 1e6:.4g} N/mm²")
    if info.get("radial_immersion") is not None:
        parts.append(f"a_e/D {info['radial_immersion']:g}")
    if "down_milling" in info:
        parts.append("down-milling" if info["down_milling"] else "up-milling")
    head = {"turning": "turning", "milling-zoa": "milling ZOA", "milling-sd": "milling SD"}.get(method, method)
    return f"{head}: " + ", ".join(parts) if parts else head
