"""Compare and locate: where do model and recording disagree, and how.

- overall and per-band mismatch (weighted RMS of ``|log(H_m/H_r)|``), RMS
  magnitude error [dB] and phase error [deg], FRAC per FRF
  (``|H_mᴴH_r|² / (H_mᴴH_m · H_rᴴH_r)``, Heylen's frequency response assurance
  criterion);
- peaks of a CMIF-like indicator, with frequency (log-parabolic
  interpolation), damping (half-power width) and height, in model and
  recording; modes paired by nearest log-frequency;
- a signature: per-mode frequency shift pattern, damping / peak height
  ratios, a constant magnitude offset, a phase drift ∝ frequency (delay),
  extra / missing peaks, and level dependence across recordings.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from jointdb.diagnose._data import indicator, peak_indices

__all__ = ["Peak", "ModePair", "Signature", "find_peaks", "pair_modes", "signature"]


@dataclass(frozen=True)
class Peak:
    """A resonance peak of an FRF set (:func:`find_peaks`).

    Attributes
    ----------
    freq_hz
        Peak frequency [Hz] (parabolic interpolation between lines).
    zeta
        Damping ratio from the half-power bandwidth.
    height
        Height of the peak indicator (relative).
    index
        The frequency line nearest to the peak.
    """

    freq_hz: float
    zeta: float
    height: float           # indicator height (relative)
    index: int


@dataclass(frozen=True)
class ModePair:
    """A model mode paired with a recorded one (:func:`signature`).

    Attributes
    ----------
    mode
        The mode's 1-based order in the model.
    model, recorded
        The two :class:`Peak` s.
    shift
        ``(f_rec − f_model) / f_model``.
    damping_ratio
        ``ζ_rec / ζ_model``.
    height_db
        Recorded − model peak height at the recorded DOFs [dB].
    mismatch
        The band's mismatch (weighted RMS |log ratio|).
    dofs
        The recorded DOFs that show the mismatch most.
    """

    mode: int                # 1-based order in the model
    model: Peak
    recorded: Peak
    shift: float             # (f_rec − f_model)/f_model
    damping_ratio: float     # ζ_rec / ζ_model
    height_db: float         # recorded − model peak height at the recorded DOFs [dB]
    mismatch: float          # band mismatch (weighted RMS |log ratio|)
    dofs: tuple[str, ...]    # recorded DOFs that show the mismatch most


@dataclass
class Signature:
    """Where and how a model and a recording disagree (:func:`signature`).

    Attributes
    ----------
    overall
        Mismatch: weighted RMS of ``|log(H_model / H_recorded)|`` over all lines.
    magnitude_db, phase_deg
        Weighted RMS magnitude [dB] and phase [deg] errors.
    frac
        FRAC per recorded entry (``"out:dir/in:dir"`` → 0..1).
    pairs
        The :class:`ModePair` s.
    extra_peaks, missing_peaks
        Strong recorded peaks without a model partner, and model peaks without a recorded
        one [Hz].
    gain_db
        Median magnitude offset recorded / model away from the peaks [dB].
    delay_s, delay_r2
        Phase drift as a time delay [s] (positive: the recording lags) and the r² of its slope.
    level_shifts
        Per mode, the relative frequency shift from the first to the last excitation level.
    affected_mode
        The mode whose frequency depends on the level most, or None.
    bands
        Per paired mode: ``band_hz``, ``mode`` and ``mismatch``.
    """

    overall: float
    magnitude_db: float
    phase_deg: float
    frac: dict
    pairs: list
    extra_peaks: list        # recorded peaks without a model partner [Hz]
    missing_peaks: list      # model peaks without a recorded partner [Hz]
    gain_db: float           # median magnitude offset recorded/model
    delay_s: float           # phase-drift slope as a delay (positive = recording lags)
    delay_r2: float
    level_shifts: list = field(default_factory=list)   # per mode: relative shift from first to last level
    affected_mode: int | None = None
    bands: list = field(default_factory=list)




def find_peaks(freq, values, weight) -> list[Peak]:
    """Resonance peaks of a FRF set.

    Parameters
    ----------
    freq, values
        Frequency lines [Hz] ``(n_freq,)`` and the complex FRF ``(n_freq, n_out, n_in)``.
    weight
        Weight of each value (0: ignored), same shape as ``values``.

    Returns
    -------
    list of Peak
    """
    ind = np.maximum(indicator(values, weight), 1e-300)
    out = []
    for i in peak_indices(freq, values, weight):
        f0 = freq[i]
        if 0 < i < freq.size - 1:
            y = np.log(ind[i - 1 : i + 2])
            den = y[0] - 2 * y[1] + y[2]
            off = 0.5 * (y[0] - y[2]) / den if den < 0 else 0.0
            f0 = freq[i] + np.clip(off, -1, 1) * 0.5 * (freq[i + 1] - freq[i - 1])
        half = ind[i] / np.sqrt(2)
        lo = i
        while lo > 0 and ind[lo] > half:
            lo -= 1
        hi = i
        while hi < freq.size - 1 and ind[hi] > half:
            hi += 1
        fl = np.interp(half, [ind[lo], ind[lo + 1]], [freq[lo], freq[lo + 1]]) if lo < i else freq[lo]
        fh = np.interp(half, [ind[hi], ind[hi - 1]], [freq[hi], freq[hi - 1]]) if hi > i else freq[hi]
        out.append(Peak(float(f0), float(max(fh - fl, 1e-9) / (2 * f0)), float(ind[i]), int(i)))
    return out


#: Two peaks are the same mode only if their deflection shapes at the recorded points agree this well (MAC).
MIN_MAC = 0.5


def mac(a: np.ndarray, b: np.ndarray) -> float:
    """Modal assurance criterion ``|aᴴb|² / (|a|² |b|²)`` of two complex shapes (1 for parallel, 0 orthogonal)."""
    den = float(np.vdot(a, a).real * np.vdot(b, b).real)
    return float(abs(np.vdot(a, b)) ** 2 / den) if den > 0 else 0.0


def pair_modes(model_peaks, rec_peaks, max_ratio=1.35, model_shapes=None, rec_shapes=None):
    """Greedy pairing by frequency and shape; returns (pairs, extra, missing).

    Candidates within ``max_ratio`` in frequency are paired closest first; with
    shapes (the FRF entries at each peak's line, one vector per peak) a pair
    also needs a MAC ≥ :data:`MIN_MAC`, and the distance is
    ``|ln(f_r/f_m)| + 0.1 (1 − MAC)`` (so of two recorded peaks at similar
    distance the one with the model's shape wins).

    Parameters
    ----------
    model_peaks, rec_peaks
        :class:`Peak` s of the model and of the recording.
    max_ratio
        Peaks further apart than this frequency ratio are not paired.
    model_shapes, rec_shapes
        Optional: one shape vector per peak (the FRF entries at its line); with both,
        a pair also needs a MAC of at least :data:`MIN_MAC`.

    Returns
    -------
    pairs : list of (int, int)
        Indices ``(model, recorded)``, by model order.
    extra : list of float
        Strong unpaired recorded peaks [Hz] (>= 10 % of the strongest).
    missing : list of float
        Strong unpaired model peaks [Hz].
    """
    shaped = bool(model_shapes) and bool(rec_shapes) and np.size(model_shapes[0]) > 1
    cand = []
    for a, m in enumerate(model_peaks):
        for b, r in enumerate(rec_peaks):
            d = abs(np.log(r.freq_hz / m.freq_hz))
            if shaped:
                c = mac(np.ravel(model_shapes[a]), np.ravel(rec_shapes[b]))
                if c < MIN_MAC:
                    continue
                d += 0.1 * (1 - c)
            cand.append((d, a, b))
    cand.sort(key=lambda t: t[0])
    used_m, used_r, pairs = set(), set(), []
    for d, a, b in cand:
        if d > np.log(max_ratio) + (0.1 if shaped else 0.0) or a in used_m or b in used_r:
            continue
        used_m.add(a)
        used_r.add(b)
        pairs.append((a, b))
    pairs.sort()
    # unpaired peaks count only if they are strong (10 % of the strongest): weak
    # local maxima near antiresonances are noise
    top_r = max((r.height for r in rec_peaks), default=0.0)
    top_m = max((m.height for m in model_peaks), default=0.0)
    extra = [r.freq_hz for b, r in enumerate(rec_peaks) if b not in used_r and r.height >= 0.1 * top_r]
    missing = [m.freq_hz for a, m in enumerate(model_peaks) if a not in used_m and m.height >= 0.1 * top_m]
    return pairs, extra, missing


def _wrms(x, w):
    w2 = w**2
    s = w2.sum()
    return float(np.sqrt((w2 * np.abs(x) ** 2).sum() / s)) if s > 0 else float("nan")


def _gain_and_delay(freq: np.ndarray, lr: np.ndarray, w: np.ndarray, pairs: list) -> tuple[float, float, float]:
    """Magnitude offset [dB] and time delay [s] (with the r² of its phase slope), away from the paired peaks."""
    away = np.ones(freq.size, dtype=bool)
    for p in pairs:
        for f0 in (p.model.freq_hz, p.recorded.freq_hz):
            away &= np.abs(freq / f0 - 1) > 0.08
    wa = w[:, away]
    la = lr[:, away]
    gain_db = float(-20 / np.log(10) * np.median(la.real[wa > 0])) if np.any(wa > 0) else 0.0
    # phase drift: per FRF, the recorded-minus-model phase on trusted lines away
    # from the peaks, unwrapped along frequency; one pooled slope (own intercepts)
    num = den = ss = 0.0
    fa = freq[away]
    for lv in range(lr.shape[0]):
        for i in range(lr.shape[2]):
            for j in range(lr.shape[3]):
                wv = wa[lv, :, i, j]
                good = wv > 0.3 * wv.max() if wv.max() > 0 else wv > 0
                if good.sum() < 5:
                    continue
                x = fa[good]
                y = np.unwrap(-la[lv, good, i, j].imag)
                ww = wv[good] ** 2
                xm, ym = np.average(x, weights=ww), np.average(y, weights=ww)
                num += float((ww * (x - xm) * (y - ym)).sum())
                den += float((ww * (x - xm) ** 2).sum())
                ss += float((ww * (y - ym) ** 2).sum())
    if den > 0:
        slope = num / den
        resid = ss - slope * num
        r2 = 1 - resid / ss if ss > 0 else 0.0
        delay = float(-slope / (2 * np.pi))
    else:
        delay, r2 = 0.0, 0.0

    return gain_db, delay, r2


def _level_shifts(freq: np.ndarray, rec: np.ndarray, w: np.ndarray, pairs: list, affected):
    """Recorded modes that move between the first and the last excitation level (frequency shift,
    damping ratio), and the mode most affected (else ``affected`` unchanged)."""

    def strong(peaks):
        top = max((p.height for p in peaks), default=0.0)
        return [p for p in peaks if p.height >= 0.1 * top]

    first = strong(find_peaks(freq, rec[0], w[0]))
    last = strong(find_peaks(freq, rec[-1], w[-1]))
    lidx, _, _ = pair_modes(first, last, max_ratio=1.2)
    shifts = []
    for a, b in lidx:
        near = [p for p in pairs if abs(p.recorded.freq_hz / first[a].freq_hz - 1) < 0.05]
        if not near:
            continue
        shifts.append({"mode": near[0].mode, "f_first_hz": first[a].freq_hz, "f_last_hz": last[b].freq_hz,
                       "shift": last[b].freq_hz / first[a].freq_hz - 1,
                       "damping_ratio": last[b].zeta / first[a].zeta})
    if shifts:
        worst = max(shifts, key=lambda s: abs(s["shift"]) + 0.1 * abs(np.log(s["damping_ratio"])))
        affected = worst["mode"]
    return shifts, affected


def signature(ev, H_model: np.ndarray) -> Signature:
    """Locate and characterise the mismatch of ``H_model`` against the recordings.

    Parameters
    ----------
    ev
        A full-line :class:`jointdb.diagnose._fit.ModelEvaluator`.
    H_model
        ``(n_level, n_freq, n_out, n_in)`` model receptances at those lines.

    Returns
    -------
    Signature
    """
    obs = ev.obs
    freq, rec, w = ev.freq, ev.rec, ev.w
    lr = ev.log_ratio(H_model)
    overall = ev.mismatch(H_model)
    mag_db = _wrms(20 / np.log(10) * lr.real, w)
    ph_deg = _wrms(np.degrees(lr.imag), w)
    names = [f"{o}:{od}/{i}:{idir}" for o, od in zip(obs.out_points, obs.out_dirs)
             for i, idir in zip(obs.in_points, obs.in_dirs)]
    frac = {}
    for k, name in enumerate(names):
        a, b = divmod(k, len(obs.in_points))
        hm, hr, ww = H_model[0, :, a, b], rec[0, :, a, b], w[0, :, a, b] > 0
        hm, hr = hm[ww], hr[ww]
        den = float(np.vdot(hm, hm).real * np.vdot(hr, hr).real)
        frac[name] = float(np.abs(np.vdot(hm, hr)) ** 2 / den) if den > 0 else float("nan")

    mpk = find_peaks(freq, H_model[0], np.ones_like(w[0]))
    rpk = find_peaks(freq, rec[0], w[0])
    idx, extra, missing = pair_modes(mpk, rpk, model_shapes=[H_model[0, p.index] for p in mpk],
                                     rec_shapes=[rec[0, p.index] for p in rpk])
    pairs = []
    for order, (a, b) in enumerate(idx):
        m, r = mpk[a], rpk[b]
        lo, hi = min(m.freq_hz, r.freq_hz) * 0.94, max(m.freq_hz, r.freq_hz) * 1.06
        band = (freq >= lo) & (freq <= hi)
        per_dof = np.array([_wrms(lr[:, band, i, j], w[:, band, i, j])
                            for i in range(lr.shape[2]) for j in range(lr.shape[3])])
        top = np.argsort(-np.nan_to_num(per_dof))[: max(1, len(names) // 2)]
        pairs.append(ModePair(
            mode=a + 1, model=m, recorded=r, shift=r.freq_hz / m.freq_hz - 1,
            damping_ratio=r.zeta / m.zeta if m.zeta > 0 else float("nan"),
            height_db=float(20 * np.log10(np.abs(rec[0, r.index]).max() / np.abs(H_model[0, m.index]).max())),
            mismatch=_wrms(lr[:, band], w[:, band]), dofs=tuple(names[t] for t in top)))

    gain_db, delay, r2 = _gain_and_delay(freq, lr, w, pairs)

    sig = Signature(overall, mag_db, ph_deg, frac, pairs, extra, missing, gain_db, delay, r2)
    sig.bands = [{"band_hz": (round(p.recorded.freq_hz * 0.94), round(p.recorded.freq_hz * 1.06)),
                  "mode": p.mode, "mismatch": p.mismatch} for p in pairs]
    if rec.shape[0] > 1:
        sig.level_shifts, sig.affected_mode = _level_shifts(freq, rec, w, pairs, sig.affected_mode)
    return sig
