"""Stability-lobe results: individual lobes, the envelope over spindle speed, a table."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from jointdb.errors import InputError

__all__ = ["Lobe", "LobeResult", "lobes_from_transfer", "envelope", "spindle_speeds", "check_max_lobes"]


def spindle_speeds(values) -> np.ndarray:
    """Validated spindle speeds [rpm], sorted, shape ``(n,)``.

    Raises
    ------
    InputError
        If empty, not 1-D, non-finite or not > 0.
    """
    try:
        s = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"spindle speeds must be numbers in rpm, got {values!r}") from None
    if s.ndim != 1 or s.size == 0:
        raise InputError(f"spindle speeds must be a non-empty 1-D list in rpm, got shape {s.shape}")
    if not np.all(np.isfinite(s)) or np.any(s <= 0):
        raise InputError(f"spindle speeds must be finite and > 0 rpm, got {s[~(np.isfinite(s) & (s > 0))][:3].tolist()}")
    return np.sort(s)


def check_max_lobes(max_lobes) -> int:
    """``max_lobes`` as a whole number >= 1 (InputError otherwise)."""
    if int(max_lobes) != max_lobes or max_lobes < 1:
        raise InputError(f"max_lobes must be a whole number >= 1, got {max_lobes}")
    return int(max_lobes)


def _ro(a, dtype=None) -> np.ndarray:
    a = np.array(a, dtype=dtype)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class Lobe:
    """One lobe curve (lobe number k): depth and chatter frequency against spindle speed.

    Arrays of equal length, ordered by chatter frequency (not necessarily by speed).

    Attributes
    ----------
    number
        Lobe number k (k = 0 at the highest speeds).
    spindle_speed_rpm
        Spindle speed [rpm] per point, shape ``(n,)``.
    depth_m
        Limiting axial depth of cut [m] per point, shape ``(n,)`` (NaN where the curve breaks).
    chatter_freq_hz
        Chatter frequency [Hz] per point, shape ``(n,)``.
    family
        The eigenvalue branch (milling ZOA has one per direction).
    """

    number: int
    spindle_speed_rpm: np.ndarray
    depth_m: np.ndarray
    chatter_freq_hz: np.ndarray
    family: int = 0


@dataclass(frozen=True, eq=False)
class LobeResult:
    """Limiting depth of cut over spindle speed (the lobe envelope) and its details.

    Attributes
    ----------
    method
        ``"turning"``, ``"milling-zoa"`` or ``"milling-sd"``.
    spindle_speed_rpm
        Spindle speeds [rpm], shape ``(n,)``, increasing.
    depth_m
        Limiting (critical) depth of cut [m] at each speed; ``inf`` when no limit
        was found below the search ceiling, ``nan`` when no lobe covers the speed.
    chatter_freq_hz
        Chatter frequency at the limit [Hz].
    lobe
        Lobe number k (whole chatter-vibration waves per tooth period, ``floor(f_c·T)``);
        −1 where undefined.
    kind
        ``"hopf"`` (secondary Hopf: complex multiplier pair) or ``"flip"``
        (period doubling: multiplier −1); ZOA and turning give Hopf only.
    lobes
        Individual lobe curves (turning and ZOA), empty for SD.
    info
        The inputs (cutting coefficients, teeth, immersion, ...) for reports.
    """

    method: str
    spindle_speed_rpm: np.ndarray
    depth_m: np.ndarray
    chatter_freq_hz: np.ndarray
    lobe: np.ndarray
    kind: np.ndarray
    lobes: tuple[Lobe, ...] = ()
    info: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "spindle_speed_rpm", _ro(self.spindle_speed_rpm, float))
        object.__setattr__(self, "depth_m", _ro(self.depth_m, float))
        object.__setattr__(self, "chatter_freq_hz", _ro(self.chatter_freq_hz, float))
        object.__setattr__(self, "lobe", _ro(self.lobe, int))
        object.__setattr__(self, "kind", _ro(self.kind, "<U4"))

    @property
    def min_depth_m(self) -> float:
        """Smallest finite limiting depth over the speeds (the "floor" seen on this grid)."""
        d = self.depth_m[np.isfinite(self.depth_m)]
        return float(d.min()) if d.size else float("nan")

    def table(self) -> list[dict]:
        """One row per spindle speed: speed, depth, chatter frequency, lobe number, kind.

        Returns
        -------
        list of dict
        """
        return [
            {
                "spindle_speed_rpm": float(n),
                "depth_m": float(a),
                "chatter_freq_hz": float(f),
                "lobe": int(k),
                "kind": str(s),
            }
            for n, a, f, k, s in zip(self.spindle_speed_rpm, self.depth_m, self.chatter_freq_hz, self.lobe, self.kind)
        ]


def lobes_from_transfer(
    freq_hz: np.ndarray, g: np.ndarray, n_teeth: int, max_lobes: int, family: int = 0
) -> tuple[Lobe, ...]:
    """Lobes from a complex "oriented transfer" ``g(ω)`` of a characteristic equation.

    The characteristic equation ``1 + a (1 − e^{−iωT}) g(ω) = 0`` (turning:
    ``g = K_f G_o``; milling ZOA: ``g`` an eigenvalue of ``H̄ Φ(iω)``) has, for real
    depth ``a``, the solution ``a = −1 / (2 Re g)`` on lines with ``Re g < 0`` and
    ``ωT = ε + 2kπ`` with ``ε = (2 arg g − π) mod 2π`` (docs/theory.md §5; equivalent to
    Altintas's ``ε = 3π + 2ψ`` and ``ε = π − 2 tan⁻¹κ``). Spindle speed
    ``n = 60 / (N T)`` rpm.

    Parameters
    ----------
    freq_hz
        Frequency lines [Hz], shape ``(n_freq,)``.
    g
        The oriented transfer on those lines [1/m], complex, shape ``(n_freq,)``.
    n_teeth
        Number of teeth N (1 for turning).
    max_lobes
        Lobes k = 0..max_lobes−1.
    family
        Branch number stored in each :class:`Lobe`.

    Returns
    -------
    tuple of Lobe
        One per lobe number; empty when ``Re g`` is nowhere negative.
    """
    f = np.asarray(freq_hz, dtype=float)
    g = np.asarray(g, dtype=complex)
    ok = (g.real < 0) & (f > 0)
    if not np.any(ok):
        return ()
    # lines with Re g >= 0 stay in the arrays as NaN so that curves break there
    with np.errstate(divide="ignore", invalid="ignore"):
        depth = np.where(ok, -1.0 / (2.0 * g.real), np.nan)
    eps = np.mod(2.0 * np.angle(g) - np.pi, 2 * np.pi)
    eps = np.where(ok, eps, np.nan)
    w = 2 * np.pi * np.where(f > 0, f, np.nan)
    out = []
    for k in range(max_lobes):
        t = (eps + 2 * np.pi * k) / w
        with np.errstate(divide="ignore"):
            n = 60.0 / (n_teeth * t)
        out.append(Lobe(k, n, depth, f, family))
    return tuple(out)


def envelope(lobes: tuple[Lobe, ...], speeds: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Lowest lobe at each spindle speed: (depth, chatter frequency, lobe number).

    Each lobe is treated as a polyline in (speed, depth); at a speed the depth of
    every segment spanning it is interpolated and the minimum kept. ``nan`` and
    ``-1`` where no lobe covers a speed.

    Parameters
    ----------
    lobes
        The lobe curves (:func:`lobes_from_transfer`).
    speeds
        Spindle speeds [rpm], ascending, shape ``(n,)``.

    Returns
    -------
    depth : ndarray, shape (n,)
        Limiting depth [m].
    chatter_freq : ndarray, shape (n,)
        Chatter frequency [Hz] of the lowest lobe.
    lobe : ndarray of int, shape (n,)
        Its lobe number.

    Raises
    ------
    ValueError
        If ``speeds`` are not ascending.
    """
    s = np.asarray(speeds, dtype=float)
    if np.any(np.diff(s) < 0):
        raise ValueError("envelope speeds must be sorted ascending")
    best = np.full(s.size, np.inf)
    freq = np.full(s.size, np.nan)
    num = np.full(s.size, -1)
    for lobe in lobes:
        n, a, f = lobe.spindle_speed_rpm, lobe.depth_m, lobe.chatter_freq_hz
        if n.size < 2:
            continue
        n0, n1, a0, a1, f0, f1 = n[:-1], n[1:], a[:-1], a[1:], f[:-1], f[1:]
        fin = np.isfinite(n0) & np.isfinite(n1) & np.isfinite(a0) & np.isfinite(a1)
        # a jump of eps across 0/2π joins the ends of two different lobes: not a segment
        fin &= np.abs(n1 - n0) <= 0.25 * np.maximum(np.abs(n0), np.abs(n1))
        idx = np.flatnonzero(fin)
        lo, hi = np.minimum(n0[idx], n1[idx]), np.maximum(n0[idx], n1[idx])
        # (segment, speed) pairs with the speed inside the segment: sorted-grid search, no dense mask
        i0 = np.searchsorted(s, lo, side="left")
        i1 = np.searchsorted(s, hi, side="right")
        counts = np.maximum(i1 - i0, 0)
        if counts.sum() == 0:
            continue
        seg = np.repeat(idx, counts)
        starts = np.repeat(i0, counts)
        offsets = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
        col = starts + offsets
        dn = n1[seg] - n0[seg]
        t = np.where(dn != 0, (s[col] - n0[seg]) / np.where(dn != 0, dn, 1.0), 0.0)
        aa = a0[seg] + t * (a1[seg] - a0[seg])
        ff = f0[seg] + t * (f1[seg] - f0[seg])
        order = np.lexsort((aa, col))
        col_s, aa_s, ff_s = col[order], aa[order], ff[order]
        first = np.ones(col_s.size, bool)
        first[1:] = col_s[1:] != col_s[:-1]
        c, av, fv = col_s[first], aa_s[first], ff_s[first]
        better = av < best[c]
        best[c[better]] = av[better]
        freq[c[better]] = fv[better]
        num[c[better]] = lobe.number
    best[~np.isfinite(best)] = np.nan
    return best, freq, num
