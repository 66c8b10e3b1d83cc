"""Amplitude dependence read from the recordings alone: a local modal fit per mode and level.

A joint that micro-slips softens and gains damping as the vibration grows.
Whether recordings at several excitation levels show that is a question about
the *data*, and must not depend on how well the beam model fits them (a model
with the wrong form shifts every nearest-line peak comparison). So each
recorded resonance is fitted on its own, at every level, by a local modal
model in a band around it,

    H_e(ω) = Σ_p A_e,p / (ω_p² − ω² + 2i ζ_p ω_p ω) + L_e (ω_c/ω)² + U_e,

with one pole (ω_p, ζ_p) shared by all FRF entries ``e``, a complex modal
constant ``A_e,p`` per entry, and lower (``L``, mass-like) and upper (``U``,
stiffness-like) residual terms per entry for the modes outside the band. A
recorded neighbour peak inside the band gets its own pole. The poles are
found by variable projection: nonlinear least squares on (ω_p, ζ_p) only, the
linear coefficients solved exactly for each trial pole. The residual of entry
``e`` at a line is ``w / |H_recorded| · (H_fit − H_recorded)``: ``w = 1/σ`` of
``log H`` makes that the relative error in units of its noise.

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
#: Default band: this many half-power half-widths each side of the peak ...
BAND_HALFWIDTHS = 4.0
#: ... but at least this fraction of the frequency each side (and at most MAX_BAND).
MIN_BAND = 0.025
MAX_BAND = 0.15
#: Recorded peaks (6 dB prominence) at least this fraction of the strongest are
#: tracked. Receptance peaks fall like 1/ω², so a mode at 4× the frequency of
#: the first is ~16× lower at equal damping: the fraction is small on purpose.
STRONG_PEAK = 0.01
_MIN_LINES = 8
_ZETA_BOUNDS = (1e-5, 0.3)


@dataclass(frozen=True, eq=False)
class ModalFit:
    """One local modal fit (see the module docstring).

    Attributes
    ----------
    freq_hz, zeta
        Natural frequency [Hz] and damping ratio of the fitted mode (the pole
        ``ω_r = 2π f``, ``ζ``).
    sigma_freq_hz, sigma_zeta
        Their 1-σ statistical uncertainties: ``(JᵀJ)⁻¹`` of the projected
        residual scaled by the reduced χ² (nothing for model-form error).
    peak
        Largest ``|H_fit(f_r)|`` over the FRF entries used (receptance units of
        the input, e.g. m/N).
    peak_entries
        ``(n_out, n_in)`` ``|H_fit(f_r)|`` per entry (0 for entries not used).
    residues
        ``(n_out, n_in)`` complex modal constants ``A`` [1/kg for receptance]
        of the fitted mode.
    band
        ``(f_lo, f_hi)`` [Hz] of the lines used.
    n_lines
        Recorded lines in the band with non-zero weight (per entry, summed).
    chi2_red
        Reduced χ² of the fit (≈ 0.5 for complex noise of the stated σ split
        evenly between real and imaginary parts; ≫ 1 = the local model or the
        stated σ is off).
    neighbours
        ``((f_hz, ζ), ...)`` of other recorded peaks in the band fitted along.
    """

    freq_hz: float
    zeta: float
    sigma_freq_hz: float
    sigma_zeta: float
    peak: float
    peak_entries: np.ndarray
    residues: np.ndarray
    band: tuple[float, float]
    n_lines: int
    chi2_red: float
    neighbours: tuple = ()


def _half_power(freq: np.ndarray, ind: np.ndarray, i: int) -> float:
    """Half of the half-power bandwidth [Hz] of indicator peak ``i`` (one-sided when cut by the grid)."""
    half = ind[i] / np.sqrt(2.0)
    below = np.where(ind[:i] <= half)[0]
    above = np.where(ind[i + 1:] <= half)[0]
    fl = fh = None
    if below.size:
        k = below[-1]
        fl = np.interp(half, [ind[k], ind[k + 1]], [freq[k], freq[k + 1]])
    if above.size:
        k = i + 1 + above[0]
        fh = np.interp(half, [ind[k], ind[k - 1]], [freq[k], freq[k - 1]])
    if fl is not None and fh is not None:
        return float(fh - fl) / 2.0
    if fl is not None:
        return float(freq[i] - fl)
    if fh is not None:
        return float(fh - freq[i])
    return float(freq[-1] - freq[0]) / 2.0


def _basis(omega: np.ndarray, poles: np.ndarray, omega_c: float) -> np.ndarray:
    """``(n_line, n_pole + 3)``: one column per pole, then the out-of-band terms
    (ω_c/ω)² (modes below), 1 (modes above) and ω/ω_c − 1 (their curvature)."""
    wr, z = poles[:, 0], poles[:, 1]
    cols = 1.0 / (wr[None] ** 2 - omega[:, None] ** 2 + 2j * z[None] * wr[None] * omega[:, None])
    r = omega / omega_c
    return np.concatenate([cols, np.column_stack([r**-2, np.ones_like(r), r - 1.0]) + 0j], 1)


def _project(phi: np.ndarray, y: np.ndarray, s: np.ndarray):
    """Weighted complex least squares per FRF entry with a shared basis.

    ``phi`` ``(n, k)``, ``y`` and ``s`` ``(n, n_e)`` (``s`` = residual weights,
    0 = unused line). Returns the coefficients ``(n_e, k)`` and the weighted
    residual ``(n, n_e)``. Columns are normalised before the SVD solve, so
    the pole columns (large near resonance) and the residual terms are
    resolved alike.
    """
    n_e = y.shape[1]
    coef = np.zeros((n_e, phi.shape[1]), complex)
    res = np.zeros(y.shape, complex)
    for e in range(n_e):  # a few FRF entries; the lines are batched
        a = s[:, e, None] * phi
        b = s[:, e] * y[:, e]
        scale = np.linalg.norm(a, axis=0)
        scale[scale == 0] = 1.0
        c, *_ = np.linalg.lstsq(a / scale, b, rcond=None)
        coef[e] = c / scale
        res[:, e] = a @ coef[e] - b
    return coef, res


def local_modal_fit(freq: np.ndarray, values: np.ndarray, weight: np.ndarray | None, f_centre: float, *,
                    search: float = 0.01, band_halfwidths: float = BAND_HALFWIDTHS, min_band: float = MIN_BAND,
                    max_band: float = MAX_BAND) -> ModalFit:
    """Fit one mode (common pole for all FRF entries) in a band around a recorded resonance.

    Parameters
    ----------
    freq
        ``(n_freq,)`` [Hz], increasing, > 0.
    values
        ``(n_freq, n_out, n_in)`` complex receptances (any consistent FRF).
    weight
        ``(n_freq, n_out, n_in)`` ``1/σ`` of ``log H`` per line and entry (0 =
        unusable line), or None for equal weights.
    f_centre
        Where to look [Hz]: the peak of the CMIF-like indicator within
        ``± search · f_centre`` is the centre of the band and the start of
        the pole.
    search
        Relative half-width of the peak search (0 = take ``f_centre`` as is).
    band_halfwidths, min_band, max_band
        Band half-width: ``band_halfwidths`` half-power half-widths, at least
        ``min_band`` and at most ``max_band`` of the peak frequency.

    Returns
    -------
    ModalFit

    Raises
    ------
    InputError
        Shapes that do not match; ``f_centre`` outside the recorded lines;
        fewer than 8 usable lines in the band.
    """
    import scipy.optimize

    freq = np.asarray(freq, dtype=float)
    values = np.asarray(values)
    if values.ndim != 3 or values.shape[0] != freq.size:
        raise InputError(f"local modal fit: values have shape {values.shape}, expected ({freq.size}, n_out, n_in)")
    ok = np.isfinite(values) & (np.abs(values) > 0)
    if weight is None:
        weight = np.ones(values.shape)
    weight = np.where(ok, np.asarray(weight, dtype=float), 0.0)
    if weight.shape != values.shape:
        raise InputError(f"local modal fit: weight has shape {weight.shape}, values {values.shape}")
    if not freq[0] <= f_centre <= freq[-1]:
        raise InputError(f"local modal fit: {f_centre:g} Hz is outside the recorded {freq[0]:g}–{freq[-1]:g} Hz")
    vals = np.where(ok, values, 0.0)
    ind = indicator(vals, weight)
    win = np.where(np.abs(freq - f_centre) <= search * f_centre)[0]
    i = int(win[np.argmax(ind[win])]) if win.size else int(np.argmin(np.abs(freq - f_centre)))
    f_pk = float(freq[i])
    hw = max(_half_power(freq, ind, i), 0.5 * float(np.median(np.diff(freq))) if freq.size > 1 else 0.0)
    half = min(max(band_halfwidths * hw, min_band * f_pk), max_band * f_pk)
    sel = (freq >= f_pk - half) & (freq <= f_pk + half)
    f_b, y, w = freq[sel], vals[sel], weight[sel]
    n_out, n_in = values.shape[1:]
    y = y.reshape(f_b.size, -1)
    s = w.reshape(f_b.size, -1) / np.where(np.abs(y) > 0, np.abs(y), 1.0)
    used = (s > 0).sum(axis=0) >= _MIN_LINES
    if not used.any():
        raise InputError(f"local modal fit at {f_pk:.4g} Hz: fewer than {_MIN_LINES} usable lines in "
                         f"{f_b[0] if f_b.size else f_pk:.4g}–{f_b[-1] if f_b.size else f_pk:.4g} Hz; "
                         "record a finer frequency grid or a wider band")
    y, s = y[:, used], s[:, used]
    omega = 2 * np.pi * f_b
    w_c = 2 * np.pi * f_pk
    n_e = int(used.sum())
    n_res = 2 * int((s > 0).sum())

    def solve(starts):
        n_p = len(starts)

        def poles_of(x):
            x = x.reshape(n_p, 2)
            return np.column_stack([w_c * x[:, 0], np.exp(x[:, 1])])

        def resid(x):
            _, r = _project(_basis(omega, poles_of(x), w_c), y, s)
            return np.concatenate([r.real.ravel(), r.imag.ravel()])

        x0 = np.array([[f / f_pk, np.log(np.clip(z, *_ZETA_BOUNDS))] for f, z in starts]).ravel()
        lo = np.tile([f_b[0] / f_pk * 0.98, np.log(_ZETA_BOUNDS[0])], n_p)
        hi = np.tile([f_b[-1] / f_pk * 1.02, np.log(_ZETA_BOUNDS[1])], n_p)
        x0 = np.clip(x0, lo + 1e-12, hi - 1e-12)
        sol = scipy.optimize.least_squares(resid, x0, bounds=(lo, hi), x_scale=np.tile([1e-3, 0.1], n_p),
                                           xtol=1e-14, ftol=1e-14, gtol=1e-14, max_nfev=400)
        r = resid(sol.x)
        n_par = sol.x.size + 2 * (n_p + 3) * n_e
        return sol.x, r, poles_of, resid, n_par

    # a neighbouring recorded peak in the band is fitted along as a pole of its own when it earns
    # its parameters (BIC); candidates: local maxima of the smoothed indicator 10 % above their saddles
    import scipy.signal

    sm = np.convolve(np.log(np.maximum(ind[sel], 1e-300)), np.ones(3) / 3, mode="same")
    cand, props = scipy.signal.find_peaks(sm, prominence=0.1)
    cand = [int(k) for k in cand[np.argsort(-props["prominences"])] if abs(int(k) + np.argmax(sel) - i) > 2]
    starts = [(f_pk, max(hw / f_pk, 2e-4))]
    x, r, poles_of, resid, n_par = solve(starts)

    def bic(r, n_par):
        return n_res * np.log(max(float(r @ r), 1e-300) / n_res) + n_par * np.log(n_res)

    for k in cand[:2]:
        kk = k + int(np.argmax(sel))
        trial = starts + [(float(freq[kk]), max(_half_power(freq, ind, kk) / freq[kk], 2e-4))]
        x2, r2, p2, res2, n2 = solve(trial)
        if bic(r2, n2) <= bic(r, n_par) - 10.0 and abs(p2(x2)[0, 0] - p2(x2)[1, 0]) > 2 * np.pi * 1e-3 * f_pk:
            starts, x, r, poles_of, resid, n_par = trial, x2, r2, p2, res2, n2
    # central-difference Jacobian at the solution (more accurate than the solver's forward one)
    jac = np.empty((r.size, x.size))
    for k in range(x.size):
        h = 1e-6 if k % 2 == 0 else 1e-5
        dx = np.zeros_like(x)
        dx[k] = h
        jac[:, k] = (resid(x + dx) - resid(x - dx)) / (2 * h)
    chi2_red = float(r @ r) / max(r.size - n_par, 1)
    cov = np.linalg.pinv(jac.T @ jac) * chi2_red
    poles = poles_of(x)
    f_r, z_r = poles[0, 0] / (2 * np.pi), poles[0, 1]
    sig_f = f_pk * float(np.sqrt(max(cov[0, 0], 0.0)))
    sig_z = z_r * float(np.sqrt(max(cov[1, 1], 0.0)))
    coef, _ = _project(_basis(omega, poles, w_c), y, s)
    h_at = _basis(np.array([poles[0, 0]]), poles, w_c)[0] @ coef.T
    peaks = np.zeros(n_out * n_in)
    peaks[used] = np.abs(h_at)
    res = np.zeros(n_out * n_in, complex)
    res[used] = coef[:, 0]
    return ModalFit(
        freq_hz=float(f_r), zeta=float(z_r), sigma_freq_hz=sig_f, sigma_zeta=sig_z,
        peak=float(peaks.max()), peak_entries=peaks.reshape(n_out, n_in), residues=res.reshape(n_out, n_in),
        band=(float(f_b[0]), float(f_b[-1])), n_lines=int((s > 0).sum()), chi2_red=chi2_red,
        neighbours=tuple((float(p[0] / (2 * np.pi)), float(p[1])) for p in poles[1:]),
    )


@dataclass(frozen=True, eq=False)
class ModeTrack:
    """One recorded mode followed across the excitation levels.

    Arrays are ``(n_level,)`` in the order the levels were given.

    Attributes
    ----------
    mode
        1-based order of the mode among the tracked ones (by frequency).
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

    @property
    def differs(self) -> bool:
        """True if frequency or damping changes with level beyond noise and the practical floor."""
        return self.differs_freq or self.differs_zeta


def _fmt(v: float, s: float) -> str:
    """``v ± s`` with as many decimals as the first significant digit of ``s`` needs."""
    if not (np.isfinite(s) and s > 0):
        return f"{v:.6g}"
    d = max(0, int(-np.floor(np.log10(s))))
    return f"{v:.{d}f} ± {s:.{d}f}"


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
    """

    tracks: tuple
    levels: tuple
    order: tuple

    @property
    def differs(self) -> bool:
        """True if any tracked mode changes with level beyond noise and the practical floor."""
        return any(t.differs for t in self.tracks)

    def summary(self) -> str:
        """One line per mode, levels from lowest to highest, e.g.
        ``mode 1: 2305 ± 1 → 2260 ± 1 → 2185 ± 2 Hz, ζ 1.10 → 1.40 → 2.00 % (changes with level)``."""
        lines = []
        o = list(self.order)
        for t in self.tracks:
            f = " → ".join(_fmt(t.freq_hz[k], t.sigma_freq_hz[k]) for k in o)
            z = " → ".join(f"{100 * t.zeta[k]:.3g}" for k in o)
            if len(o) < 2:
                verdict = ""
            elif t.differs:
                parts = ([f"frequency {100 * t.freq_change:+.2f} %"] if t.differs_freq else []) + \
                        ([f"damping ×{t.zeta_ratio:.2f}"] if t.differs_zeta else [])
                verdict = " (changes with level: " + ", ".join(parts) + ")"
            else:
                verdict = " (same at every level within noise)"
            lines.append(f"mode {t.mode}: {f} Hz, ζ {z} %{verdict}")
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-ready dict (lists of floats, levels in the order given)."""
        return {
            "differs": self.differs,
            "levels": [None if v is None else float(v) for v in self.levels],
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
                "band_hz": [list(fi.band) for fi in t.fits],
            } for t in self.tracks],
        }


def _chi2(x: np.ndarray, s: np.ndarray) -> tuple[float, float]:
    """χ² of ``x`` about its inverse-variance mean and the p-value (n − 1 degrees of freedom)."""
    import scipy.stats

    if x.size < 2:
        return 0.0, 1.0
    w = 1.0 / np.maximum(s, 1e-300) ** 2
    mean = float((w * x).sum() / w.sum())
    c = float((w * (x - mean) ** 2).sum())
    return c, float(scipy.stats.chi2.sf(c, x.size - 1))


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
    inds = [indicator(vals[lv], weight[lv]) for lv in range(n_lv)]
    first = order[0]
    if centres is None:
        idx = peak_indices(freq, vals[first], weight[first])
        top = max((inds[first][k] for k in idx), default=0.0)
        centres = [float(freq[k]) for k in idx if inds[first][k] >= STRONG_PEAK * top]
    centres = sorted(float(c) for c in centres if freq[0] <= c <= freq[-1])
    tracks = []
    for m, fc in enumerate(centres):
        lo = np.sqrt(centres[m - 1] * fc) if m > 0 else freq[0]
        hi = np.sqrt(centres[m + 1] * fc) if m + 1 < len(centres) else freq[-1]
        fits: list = [None] * n_lv
        prev = fc
        try:
            for lv in order:
                # this level's own peak, near the previous level's, inside this mode's share of the axis
                reach = max(0.06 * prev, 4 * (fits[order[0]].zeta * prev if fits[order[0]] else 0.0))
                win = np.where((np.abs(freq - prev) <= reach) & (freq > lo) & (freq < hi))[0]
                f_pk = float(freq[win[np.argmax(inds[lv][win])]]) if win.size else prev
                fits[lv] = local_modal_fit(freq, vals[lv], weight[lv], f_pk, search=0.0,
                                           band_halfwidths=band_halfwidths, min_band=min_band)
                prev = fits[lv].freq_hz
        except InputError:
            continue  # too few lines around this peak at some level: not tracked
        f = np.array([fi.freq_hz for fi in fits])
        sf = np.array([fi.sigma_freq_hz for fi in fits])
        z = np.array([fi.zeta for fi in fits])
        sz = np.array([fi.sigma_zeta for fi in fits])
        e = np.unravel_index(int(np.argmax(fits[first].peak_entries)), fits[first].peak_entries.shape)
        peak = np.array([fi.peak_entries[e] for fi in fits])
        amp = peak * np.array([float(v) for v in levels]) if known else peak
        c_f, p_f = _chi2(f, sf)
        c_z, p_z = _chi2(np.log(z), sz / z)
        spread_f = float(f.max() / f.min() - 1)
        spread_z = float(z.max() / z.min())
        tracks.append(ModeTrack(
            mode=len(tracks) + 1, freq_hz=f, sigma_freq_hz=sf, zeta=z, sigma_zeta=sz, peak=peak, amplitude=amp,
            amplitude_unit="m" if known else "m/N", entry=(int(e[0]), int(e[1])),
            chi2_freq=c_f, p_freq=p_f, chi2_zeta=c_z, p_zeta=p_z,
            freq_change=float(f[order[-1]] / f[order[0]] - 1), zeta_ratio=float(z[order[-1]] / z[order[0]]),
            spread_freq=spread_f, spread_zeta=spread_z,
            differs_freq=bool(n_lv > 1 and p_f < P_LEVELS and spread_f > FREQ_FLOOR),
            differs_zeta=bool(n_lv > 1 and p_z < P_LEVELS and spread_z > ZETA_FLOOR),
            fits=tuple(fits)))
    return LevelAnalysis(tracks=tuple(tracks), levels=tuple(levels), order=order)
