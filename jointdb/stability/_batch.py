"""Zero-order milling lobes of many tool tips at once: candidates × lines × speeds in arrays.

The same arithmetic as :func:`jointdb.stability.milling_lobes_zoa` (eigenvalues of ``H̄ Φ``, branch
tracking, lobes ``a = −1/(2 Re g)``, ``n = 60/(N τ)``, the lowest lobe at each speed by linear
interpolation along each lobe's polyline), element for element, with a leading candidate axis instead
of a Python loop over candidates and lobes — so the result equals the one-candidate function to the
last digit (tests/optimize/test_batch_zoa.py).
"""

from __future__ import annotations

import numpy as np

from jointdb.errors import InputError
from jointdb.stability._cutting import MillingCut, mean_directional_matrix

__all__ = ["zoa_envelope_batch"]


def _track_branches_batch(ev: np.ndarray) -> np.ndarray:
    """:func:`jointdb.stability._frequency._track_branches` over a leading candidate axis, ev (C, F, 2)."""
    if ev.shape[1] < 2:
        return ev
    same = np.abs(ev[:, 1:, 0] - ev[:, :-1, 0]) + np.abs(ev[:, 1:, 1] - ev[:, :-1, 1])
    swap = np.abs(ev[:, 1:, 0] - ev[:, :-1, 1]) + np.abs(ev[:, 1:, 1] - ev[:, :-1, 0])
    parity = np.concatenate([np.zeros((ev.shape[0], 1), int), np.cumsum(swap < same, axis=1) % 2], axis=1).astype(bool)
    return np.where(parity[..., None], ev[..., ::-1], ev)


def _lobe_curves(freq: np.ndarray, g: np.ndarray, n_teeth: int, max_lobes: int):
    """Speed, depth and frequency of every lobe: n (C, L, F), depth (C, F), f (F,) for one eigenvalue family."""
    ok = (g.real < 0) & (freq > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        depth = np.where(ok, -1.0 / (2.0 * g.real), np.nan)
    eps = np.where(ok, np.mod(2.0 * np.angle(g) - np.pi, 2 * np.pi), np.nan)
    w = 2 * np.pi * np.where(freq > 0, freq, np.nan)
    k = np.arange(max_lobes)[None, :, None]
    t = (eps[:, None, :] + 2 * np.pi * k) / w
    with np.errstate(divide="ignore"):
        n = 60.0 / (n_teeth * t)
    return n, depth, ok


def zoa_envelope_batch(freq_hz: np.ndarray, phi: np.ndarray, cut: MillingCut, speeds: np.ndarray,
                       max_lobes: int = 30) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Zero-order stability envelope of C tool tips at S speeds.

    Parameters
    ----------
    freq_hz
        Lines [Hz], shape (F,), > 0.
    phi
        Tool-tip receptance matrices in (x, y) [m/N], shape (C, F, 2, 2).
    cut
        :class:`MillingCut`.
    speeds
        Spindle speeds [rpm], shape (S,), ascending.
    max_lobes
        Lobes k = 0..max_lobes−1 per eigenvalue family.

    Returns
    -------
    depth_m, chatter_freq_hz, lobe
        Each (C, S): limiting depth (NaN where no lobe covers a speed, as in the one-candidate
        envelope), chatter frequency and lobe number (−1 where none).
    """
    f = np.asarray(freq_hz, dtype=float)
    s = np.asarray(speeds, dtype=float)
    if phi.ndim != 4 or phi.shape[1:] != (f.size, 2, 2):
        raise InputError(f"phi must be (n_candidates, n_freq, 2, 2) = (C, {f.size}, 2, 2), got {phi.shape}")
    if np.any(np.diff(s) < 0):
        raise InputError("speeds must be sorted ascending")
    hbar = mean_directional_matrix(cut)
    ev = _track_branches_batch(np.linalg.eigvals(hbar[None] @ phi))  # (C, F, 2)
    n_c = phi.shape[0]
    # every (candidate, family, lobe) polyline's segments, in the one-candidate envelope's lobe order
    ns, a0s = [], []
    for fam in range(2):
        n, depth, _ = _lobe_curves(f, ev[:, :, fam], cut.n_teeth, max_lobes)
        ns.append(n)
        a0s.append(np.broadcast_to(depth[:, None, :], n.shape))
    n = np.concatenate(ns, axis=1)  # (C, 2L, F), lobe index = fam*L + k
    a = np.concatenate(a0s, axis=1)
    n0, n1, a0, a1 = n[..., :-1], n[..., 1:], a[..., :-1], a[..., 1:]
    fin = np.isfinite(n0) & np.isfinite(n1) & np.isfinite(a0) & np.isfinite(a1)
    fin &= np.abs(n1 - n0) <= 0.25 * np.maximum(np.abs(n0), np.abs(n1))
    c_idx, l_idx, seg = np.nonzero(fin)
    n0v, n1v = n0[c_idx, l_idx, seg], n1[c_idx, l_idx, seg]
    lo, hi = np.minimum(n0v, n1v), np.maximum(n0v, n1v)
    i0 = np.searchsorted(s, lo, side="left")
    i1 = np.searchsorted(s, hi, side="right")
    counts = np.maximum(i1 - i0, 0)
    rep = np.repeat(np.arange(counts.size), counts)
    col = np.repeat(i0, counts) + (np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts))
    a0v, a1v = a0[c_idx, l_idx, seg], a1[c_idx, l_idx, seg]  # gather per segment, then repeat per speed
    p0, dn = n0v[rep], (n1v - n0v)[rep]
    t = np.where(dn != 0, (s[col] - p0) / np.where(dn != 0, dn, 1.0), 0.0)
    a_lo, s_r = a0v[rep], seg[rep]
    aa = a_lo + t * (a1v[rep] - a_lo)
    ff = f[s_r] + t * (f[s_r + 1] - f[s_r])
    # per (candidate, speed) the smallest depth; the pairs come in (candidate, lobe, segment) order and the
    # sort is stable, so ties go to the earlier lobe, then the earlier segment (as in the one-tip envelope)
    flat = c_idx[rep] * s.size + col
    order = np.lexsort((aa, flat))
    first = np.ones(order.size, bool)
    first[1:] = flat[order][1:] != flat[order][:-1]
    pick = order[first]
    l_r = l_idx[rep[pick]]
    depth = np.full(n_c * s.size, np.nan)
    fc = np.full(n_c * s.size, np.nan)
    lobe = np.full(n_c * s.size, -1)
    depth[flat[pick]] = aa[pick]
    fc[flat[pick]] = ff[pick]
    lobe[flat[pick]] = l_r % max_lobes
    shape = (n_c, s.size)
    depth = depth.reshape(shape)
    depth[~np.isfinite(depth)] = np.nan
    return depth, fc.reshape(shape), lobe.reshape(shape)
