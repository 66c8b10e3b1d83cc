"""Amplitude dependence read from the recordings alone: each mode followed across levels.

A joint that micro-slips softens and gains damping as the vibration grows.
Whether recordings at several excitation levels show that is a question about
the *data*, and must not depend on how well the beam model fits them (a model
with the wrong form shifts every nearest-line peak comparison). So each
recorded resonance is fitted on its own, at every level, by a local modal
model in a band around it (:func:`jointdb.diagnose._modalfit.local_modal_fit`:
a pole shared by all FRF entries, modal constants and out-of-band terms per
entry, variable projection).

Then per mode the levels are compared: the frequencies (and, separately, the
damping ratios) of all levels are tested against a common value with their
1-σ uncertainties (χ², ``p < P_LEVELS``) *and* must differ by more than a
practical floor (:data:`FREQ_FLOOR`, :data:`ZETA_FLOOR`) that no noise model
covers: a linear structure recorded twice does not give the same frequency
and damping to better than that (see the constants).

>>> a = track_modes(obs.full_freq, obs.full_values, obs.full_weight, obs.levels)  # doctest: +SKIP
>>> a.differs, print(a.summary())                                                   # doctest: +SKIP
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from jointdb.diagnose._data import indicator, peak_indices
from jointdb.diagnose._modalfit import BAND_HALFWIDTHS, MIN_BAND, ModalFit, local_modal_fit
from jointdb.errors import InputError

__all__ = ["ModalFit", "ModeTrack", "LevelAnalysis", "local_modal_fit", "track_modes",
           "FREQ_FLOOR", "ZETA_FLOOR", "P_LEVELS"]

#: Significance of the χ² test that the levels share one frequency (or one ζ).
P_LEVELS = 1e-3
#: Practical floor on the spread of a mode's frequency across levels, relative.
#: A linear structure recorded twice moves by this much without any joint
#: physics: steel's modulus falls by about 2.5e-4 per kelvin, so a frequency by
#: ~1.3e-4 per kelvin, and a few kelvin between runs (shaker and amplifier
#: warm up, a hand on the tool) give ~5e-4; re-seating a sensor or the stinger
#: adds the same order. Twice that is the floor.
FREQ_FLOOR = 1e-3
#: Practical floor on the ratio of the largest to the smallest damping ratio of
#: a mode across levels. Damping is the least repeatable modal parameter:
#: repeated tests of one linear structure scatter by 5–10 % (leakage, window,
#: stinger and suspension losses), and a local fit with residual terms has a
#: model-form error of a few per cent on ζ when neighbours are close; 15 % is
#: beyond both.
ZETA_FLOOR = 1.15
#: Recorded peaks (6 dB prominence) at least this fraction of the strongest are
#: tracked. Receptance peaks fall like 1/ω², so a mode at 4× the frequency of
#: the first is ~16× lower at equal damping: the fraction is small on purpose.
STRONG_PEAK = 0.01


@dataclass(frozen=True, eq=False)
class ModeTrack:
    """One recorded mode followed across the excitation levels.

    Arrays are ``(n_level,)`` in the order the levels were given.

    Attributes
    ----------
    mode
        1-based order of the mode among the recorded peaks (or the given
        centres) by frequency; a peak that cannot be fitted leaves a gap.
    freq_hz, sigma_freq_hz, zeta, sigma_zeta
        Local-fit frequency [Hz] and damping ratio per level, with 1-σ.
    peak
        ``|H_fit(f_r)|`` per level at the FRF entry ``entry`` (e.g. m/N).
    amplitude
        Response amplitude per level: ``peak × level`` when the levels are
        known (force [N] → metres for receptance), else ``peak``.
    amplitude_unit
        ``"m"`` or ``"m/N"`` (``"m"`` assumes force levels and receptance).
    entry
        ``(output, input)`` index of the FRF entry with the largest peak at
        the lowest level (the amplitude is read there at every level).
    chi2_freq, p_freq, chi2_zeta, p_zeta
        χ² of the per-level frequencies (of ``ln ζ``) about their weighted
        mean with ``n_level − 1`` degrees of freedom, and its p-value.
    freq_change
        ``f(highest level)/f(lowest level) − 1``.
    zeta_ratio
        ``ζ(highest level)/ζ(lowest level)``.
    spread_freq, spread_zeta
        ``(max f − min f)/min f`` and ``max ζ / min ζ`` over the levels.
    differs_freq, differs_zeta
        ``p < P_LEVELS`` and the spread beyond ``FREQ_FLOOR`` (``ZETA_FLOOR``).
    fits
        The :class:`ModalFit` per level.
    outliers
        Indices of levels whose local fit is off the trend of its neighbouring levels (a spike, see
        :func:`level_outliers`): left out of the level-dependence test and reported.
    """

    mode: int
    freq_hz: np.ndarray
    sigma_freq_hz: np.ndarray
    zeta: np.ndarray
    sigma_zeta: np.ndarray
    peak: np.ndarray
    amplitude: np.ndarray
    amplitude_unit: str
    entry: tuple[int, int]
    chi2_freq: float
    p_freq: float
    chi2_zeta: float
    p_zeta: float
    freq_change: float
    zeta_ratio: float
    spread_freq: float
    spread_zeta: float
    differs_freq: bool
    differs_zeta: bool
    fits: tuple = ()
    #: indices of levels whose local fit is off the trend of its neighbouring levels (a spike, see
    #: :func:`level_outliers`): left out of the level-dependence test and reported
    outliers: tuple = ()

    @property
    def differs(self) -> bool:
        """True if frequency or damping changes with level beyond noise and the practical floor."""
        return self.differs_freq or self.differs_zeta


def _fmt(v: float, s: float) -> str:
    """``v ± s`` with as many decimals as the first significant digit of ``s`` needs."""
    if not (np.isfinite(s) and s > 0):
        return f"{v:.6g}"
    if s < 1e-8 * abs(v):  # a noise-free model: no uncertainty worth printing
        return f"{v:.6g}"
    d = min(max(0, int(-np.floor(np.log10(s)))), 8)
    return f"{v:.{d}f} ± {s:.{d}f}"


def _pct(z: float) -> str:
    """A damping ratio in per cent with two significant digits (1.1, 0.42, 0.063)."""
    p = 100 * z
    return f"{p:.1f}" if p >= 1 else f"{p:.2f}" if p >= 0.1 else f"{p:.3f}"


@dataclass(frozen=True, eq=False)
class LevelAnalysis:
    """Modes tracked across excitation levels (:func:`track_modes`).

    Attributes
    ----------
    tracks
        One :class:`ModeTrack` per recorded mode, by frequency.
    levels
        The excitation levels as given (None = unknown).
    order
        Indices of the levels from lowest to highest (as given when unknown).
    skipped
        Centres [Hz] that could not be fitted at some level (too few lines).
    """

    tracks: tuple
    levels: tuple
    order: tuple
    skipped: tuple = ()     # centres [Hz] that could not be fitted at some level (too few lines)

    @property
    def differs(self) -> bool:
        """True if any tracked mode changes with level beyond noise and the practical floor."""
        return any(t.differs for t in self.tracks)

    @property
    def damping_grows(self) -> bool:
        """True if some tracked mode's damping changes with level beyond noise and grows (lowest → highest)."""
        return any(t.differs_zeta and t.zeta_ratio > 1 for t in self.tracks)

    def summary(self) -> str:
        """One line per mode, levels from lowest to highest, e.g.
        ``the 2305 Hz mode: 2305 ± 1 → 2260 ± 1 → 2185 ± 2 Hz, ζ 1.1 → 1.4 → 2.0 % (changes with level:
        …)``.

        Returns
        -------
        str
        """
        lines = []
        o = list(self.order)
        for t in self.tracks:
            f = " → ".join(_fmt(t.freq_hz[k], t.sigma_freq_hz[k]) for k in o)
            z = " → ".join(_pct(t.zeta[k]) for k in o)
            if len(o) < 2:
                verdict = ""
            elif t.differs:
                parts = ([f"frequency {100 * t.freq_change:+.2f} %"] if t.differs_freq else []) + \
                        ([f"damping ×{t.zeta_ratio:.2f}"] if t.differs_zeta else [])
                verdict = " (changes with level: " + ", ".join(parts) + ")"
            else:
                verdict = " (same at every level within noise)"
            lines.append(f"the {t.freq_hz[o[0]]:.4g} Hz mode: {f} Hz, ζ {z} %{verdict}")
            for k in t.outliers:
                name = self.levels[k] if self.levels[k] is not None else f"#{k + 1}"
                lines.append(f"  level {name}: {t.freq_hz[k]:.5g} Hz, ζ {_pct(t.zeta[k])} % is off the trend of "
                             "its neighbouring levels (an outlier of that recording): left out of the test")
        if self.skipped:
            lines.append("not followed (too few recorded lines around the peak at some level): "
                         + ", ".join(f"{f:.0f}" for f in self.skipped) + " Hz")
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-ready dict (lists of floats, levels in the order given).

        Returns
        -------
        dict
        """
        return {
            "differs": self.differs,
            "levels": [None if v is None else float(v) for v in self.levels],
            "not_followed_hz": [float(f) for f in self.skipped],
            "criterion": (f"per mode: chi2 of the per-level frequencies (ln zeta) about their mean, p < {P_LEVELS:g}, "
                          f"and a spread > {100 * FREQ_FLOOR:g} % in frequency (damping ratio max/min > "
                          f"{ZETA_FLOOR:g})"),
            "modes": [{
                "mode": t.mode, "freq_hz": t.freq_hz.tolist(), "sigma_freq_hz": t.sigma_freq_hz.tolist(),
                "zeta": t.zeta.tolist(), "sigma_zeta": t.sigma_zeta.tolist(), "peak": t.peak.tolist(),
                "amplitude": t.amplitude.tolist(), "amplitude_unit": t.amplitude_unit,
                "entry": list(t.entry), "p_freq": t.p_freq, "p_zeta": t.p_zeta,
                "freq_change": t.freq_change, "zeta_ratio": t.zeta_ratio,
                "differs": t.differs, "differs_freq": t.differs_freq, "differs_zeta": t.differs_zeta,
                "band_hz": [list(fi.band) for fi in t.fits], "outlier_levels": list(t.outliers),
            } for t in self.tracks],
        }


#: A level is an outlier when its frequency departs from both neighbouring levels, in the same direction,
#: by more than OUTLIER_SIGMAS combined σ and more than OUTLIER_STEP × the step between those neighbours.
OUTLIER_SIGMAS = 4.0
OUTLIER_STEP = 3.0


def level_outliers(f: np.ndarray, sf: np.ndarray, order: Sequence[int]) -> tuple[int, ...]:
    """Indices of levels whose frequency is a spike off its neighbours' trend (interior levels, ≥ 4 levels).

    A real amplitude dependence is a trend: each level lies between (or near) its neighbours. A level that
    lies above both neighbours (or below both) by more than ``OUTLIER_SIGMAS`` σ and by more than
    ``OUTLIER_STEP`` × the neighbours' own difference is a fault of that recording (a leaked line, a
    double hit), not physics.
    """
    o = list(order)
    if len(o) < 4:
        return ()
    out = []
    for j in range(1, len(o) - 1):
        a, k, b = o[j - 1], o[j], o[j + 1]
        up, down = f[k] - max(f[a], f[b]), min(f[a], f[b]) - f[k]
        dev = max(up, down)
        s = float(np.sqrt(sf[k] ** 2 + max(sf[a], sf[b]) ** 2))
        if dev > OUTLIER_SIGMAS * s and dev > OUTLIER_STEP * abs(f[a] - f[b]):
            out.append(k)
    return tuple(out)


def _chi2(x: np.ndarray, s: np.ndarray) -> tuple[float, float]:
    """χ² of ``x`` about its inverse-variance mean and the p-value (n − 1 degrees of freedom)."""
    import scipy.stats

    if x.size < 2:
        return 0.0, 1.0
    w = 1.0 / np.maximum(s, 1e-300) ** 2
    mean = float((w * x).sum() / w.sum())
    c = float((w * (x - mean) ** 2).sum())
    return c, float(scipy.stats.chi2.sf(c, x.size - 1))


#: A tracked mode is a resonance only if every level's local fit has 1e-4 < ζ < MAX_ZETA, lies inside its
#: band, is determined to 1 % in frequency, and stays within MAX_DRIFT of the lowest level's frequency.
MAX_ZETA = 0.2
MAX_DRIFT = 0.10


def _credible(f, sf, z, fits, first) -> bool:
    """True if the per-level local fits describe one resonance (see ``MAX_ZETA``, ``MAX_DRIFT``)."""
    inside = all(fi.band[0] <= fi.freq_hz <= fi.band[1] for fi in fits)
    return bool(inside and np.all((z > 1e-4) & (z < MAX_ZETA)) and np.all(sf < 0.01 * f)
                and np.all(np.abs(f / f[first] - 1) < MAX_DRIFT))


def track_modes(freq: np.ndarray, values: np.ndarray, weight: np.ndarray | None,
                levels: Sequence[float | None], centres: Sequence[float] | None = None, *,
                band_halfwidths: float = BAND_HALFWIDTHS, min_band: float = MIN_BAND) -> LevelAnalysis:
    """Follow each recorded mode across excitation levels with a local modal fit per level.

    Parameters
    ----------
    freq
        ``(n_freq,)`` [Hz].
    values
        ``(n_level, n_freq, n_out, n_in)`` complex receptances, one set per level.
    weight
        Same shape, ``1/σ`` of ``log H`` (0 = unusable line), or None.
    levels
        ``n_level`` excitation amplitudes (force [N]) or None each.
    centres
        Frequencies [Hz] of the modes to follow; default: the recorded peaks
        of the lowest level at least ``STRONG_PEAK`` of the strongest.
    band_halfwidths, min_band
        Fit band: this many half-power half-widths each side of the peak, but at least
        ``min_band`` × the frequency each side.

    Returns
    -------
    LevelAnalysis
        Modes in increasing frequency. The band is re-centred on each level's
        own peak, searched from the previous level's frequency (lowest level
        first) no further than half way to the neighbouring tracked modes, so
        a shift of several per cent is followed.

    Raises
    ------
    InputError
        Shapes that do not match, or ``len(levels) != n_level``.
    """
    freq, vals, weight, known, order = _checked(freq, values, weight, levels)
    n_lv = vals.shape[0]
    inds = [indicator(vals[lv], weight[lv]) for lv in range(n_lv)]
    first = order[0]
    if centres is None:
        idx = peak_indices(freq, vals[first], weight[first])
        top = max((inds[first][k] for k in idx), default=0.0)
        centres = [float(freq[k]) for k in idx if inds[first][k] >= STRONG_PEAK * top]
    centres = sorted(float(c) for c in centres if freq[0] <= c <= freq[-1])
    tracks, skipped = [], []
    for m, fc in enumerate(centres):
        lo = np.sqrt(centres[m - 1] * fc) if m > 0 else freq[0]
        hi = np.sqrt(centres[m + 1] * fc) if m + 1 < len(centres) else freq[-1]
        try:
            fits = _follow(freq, vals, weight, inds, order, fc, (lo, hi), band_halfwidths, min_band)
        except InputError:
            skipped.append(fc)  # too few lines around this peak at some level: not tracked, and said so
            continue
        track = _track(m + 1, fits, levels if known else None, order)
        if track is None:
            skipped.append(fc)  # no resonance to follow here (a weak local maximum, a tail): not a mode
            continue
        tracks.append(track)
    return LevelAnalysis(tracks=tuple(tracks), levels=tuple(levels), order=order, skipped=tuple(skipped))


def _checked(freq, values, weight, levels):
    """The inputs of :func:`track_modes` as arrays (unusable lines at zero weight), and the level order
    (increasing force when every level is known, else as given)."""
    freq = np.asarray(freq, dtype=float)
    values = np.asarray(values)
    if values.ndim != 4 or values.shape[1] != freq.size:
        raise InputError(f"track_modes: values have shape {values.shape}, expected (n_level, {freq.size}, n_out, n_in)")
    n_lv = values.shape[0]
    if len(levels) != n_lv:
        raise InputError(f"track_modes: {len(levels)} levels for {n_lv} recordings")
    ok = np.isfinite(values) & (np.abs(values) > 0)
    weight = np.ones(values.shape) if weight is None else np.asarray(weight, dtype=float)
    if weight.shape != values.shape:
        raise InputError(f"track_modes: weight has shape {weight.shape}, values {values.shape}")
    weight = np.where(ok, weight, 0.0)
    vals = np.where(ok, values, 0.0)
    known = all(v is not None for v in levels)
    order = tuple(int(k) for k in (np.argsort(np.asarray(levels, dtype=float), kind="stable") if known
                                   else range(n_lv)))
    return freq, vals, weight, known, order


def _follow(freq, vals, weight, inds, order, fc: float, share: tuple, band_halfwidths: float, min_band: float):
    """Local modal fits of one mode at every level, lowest level first, each band re-centred on the
    level's own peak near the previous level's frequency inside the mode's ``share`` of the axis."""
    lo, hi = share
    fits: list = [None] * vals.shape[0]
    prev = fc
    for lv in order:
        # this level's own peak, near the previous level's, inside this mode's share of the axis
        reach = max(0.06 * prev, 4 * (fits[order[0]].zeta * prev if fits[order[0]] else 0.0))
        win = np.where((np.abs(freq - prev) <= reach) & (freq > lo) & (freq < hi))[0]
        f_pk = float(freq[win[np.argmax(inds[lv][win])]]) if win.size else prev
        fits[lv] = local_modal_fit(freq, vals[lv], weight[lv], f_pk, search=0.0,
                                   band_halfwidths=band_halfwidths, min_band=min_band)
        prev = fits[lv].freq_hz
    return fits


def _track(mode: int, fits: list, levels, order) -> ModeTrack | None:
    """One mode's trend across levels from its local fits (None if there is no resonance to follow);
    ``levels`` None when the forces are not all known (amplitudes then per unit force)."""
    n_lv = len(fits)
    f = np.array([fi.freq_hz for fi in fits])
    sf = np.array([fi.sigma_freq_hz for fi in fits])
    z = np.array([fi.zeta for fi in fits])
    sz = np.array([fi.sigma_zeta for fi in fits])
    if not _credible(f, sf, z, fits, order[0]):
        return None
    e = np.unravel_index(int(np.argmax(fits[order[0]].peak_entries)), fits[order[0]].peak_entries.shape)
    peak = np.array([fi.peak_entries[e] for fi in fits])
    amp = peak * np.array([float(v) for v in levels]) if levels is not None else peak
    bad = level_outliers(f, sf, order)
    keep = np.array([k not in bad for k in range(n_lv)])
    c_f, p_f = _chi2(f[keep], sf[keep])
    c_z, p_z = _chi2(np.log(z[keep]), (sz / z)[keep])
    spread_f = float(f[keep].max() / f[keep].min() - 1)
    spread_z = float(z[keep].max() / z[keep].min())
    return ModeTrack(
        mode=mode, freq_hz=f, sigma_freq_hz=sf, zeta=z, sigma_zeta=sz, peak=peak, amplitude=amp,
        amplitude_unit="m" if levels is not None else "m/N", entry=(int(e[0]), int(e[1])),
        chi2_freq=c_f, p_freq=p_f, chi2_zeta=c_z, p_zeta=p_z,
        freq_change=float(f[order[-1]] / f[order[0]] - 1), zeta_ratio=float(z[order[-1]] / z[order[0]]),
        spread_freq=spread_f, spread_zeta=spread_z,
        differs_freq=bool(n_lv > 1 and p_f < P_LEVELS and spread_f > FREQ_FLOOR),
        differs_zeta=bool(n_lv > 1 and p_z < P_LEVELS and spread_z > ZETA_FLOOR),
        fits=tuple(fits), outliers=bad)
