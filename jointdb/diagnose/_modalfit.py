"""A local modal fit around one recorded resonance, robust to everything outside its band.

In a band around the resonance the FRF entries ``e`` are fitted by

    H_e(ω) = Σ_p A_e,p / (ω_p² − ω² + 2i ζ_p ω_p ω) + L_e (ω_c/ω)² + U_e + S_e (ω/ω_c − 1),

with one pole (ω_p, ζ_p) shared by all entries, a complex modal constant
``A_e,p`` per entry, and per entry the out-of-band terms: a lower residual
``L`` (modes below, mass-like), an upper residual ``U`` (modes above,
stiffness-like) and a slope ``S`` (their curvature across the band). A
recorded neighbour peak inside the band gets a pole of its own when it earns
its parameters (BIC). The poles are found by variable projection: nonlinear
least squares on (ω_p, ζ_p) only, the linear coefficients solved exactly for
each trial pole. The residual of entry ``e`` at a line is
``w / |H_recorded| · (H_fit − H_recorded)``: with ``w = 1/σ`` of ``log H``
that is the relative error in units of its noise. Used by
:mod:`jointdb.diagnose._levels` to follow modes across excitation levels.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from jointdb.diagnose._data import indicator
from jointdb.errors import InputError

__all__ = ["ModalFit", "local_modal_fit", "BAND_HALFWIDTHS", "MIN_BAND", "MAX_BAND"]

#: Default band: this many half-power half-widths each side of the peak ...
BAND_HALFWIDTHS = 4.0
#: ... but at least this fraction of the frequency each side (and at most MAX_BAND).
MIN_BAND = 0.025
MAX_BAND = 0.15
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
    i, hw, sel = _band(freq, ind, f_centre, search, band_halfwidths, min_band, max_band)
    f_pk = float(freq[i])
    f_b, y, w = freq[sel], vals[sel], weight[sel]
    n_out, n_in = values.shape[1:]
    y = y.reshape(f_b.size, -1)
    s = w.reshape(f_b.size, -1) / np.where(np.abs(y) > 0, np.abs(y), 1.0)
    used = (s > 0).sum(axis=0) >= _MIN_LINES
    if not used.any():
        raise InputError(f"local modal fit at {f_pk:.4g} Hz: fewer than {_MIN_LINES} usable lines in "
                         f"{f_b[0] if f_b.size else f_pk:.4g}–{f_b[-1] if f_b.size else f_pk:.4g} Hz; "
                         "record a finer frequency grid or a wider band")
    fit = _BandFit(f_b, y[:, used], s[:, used], f_pk)
    x, r, n_par = _with_neighbours(fit, freq, ind, sel, i, [(f_pk, max(hw / f_pk, 2e-4))])
    cov, chi2_red = fit.covariance(x, r, n_par)
    poles = fit.poles(x)
    f_r, z_r = poles[0, 0] / (2 * np.pi), poles[0, 1]
    sig_f = f_pk * float(np.sqrt(max(cov[0, 0], 0.0)))
    sig_z = z_r * float(np.sqrt(max(cov[1, 1], 0.0)))
    coef, _ = _project(_basis(fit.omega, poles, fit.w_c), fit.y, fit.s)
    h_at = _basis(np.array([poles[0, 0]]), poles, fit.w_c)[0] @ coef.T
    peaks = np.zeros(n_out * n_in)
    peaks[used] = np.abs(h_at)
    res = np.zeros(n_out * n_in, complex)
    res[used] = coef[:, 0]
    return ModalFit(
        freq_hz=float(f_r), zeta=float(z_r), sigma_freq_hz=sig_f, sigma_zeta=sig_z,
        peak=float(peaks.max()), peak_entries=peaks.reshape(n_out, n_in), residues=res.reshape(n_out, n_in),
        band=(float(f_b[0]), float(f_b[-1])), n_lines=int((fit.s > 0).sum()), chi2_red=chi2_red,
        neighbours=tuple((float(p[0] / (2 * np.pi)), float(p[1])) for p in poles[1:]),
    )


def _band(freq: np.ndarray, ind: np.ndarray, f_centre: float, search: float, band_halfwidths: float,
          min_band: float, max_band: float):
    """The recorded peak's line (the indicator's maximum within ``± search · f_centre``), its half-power
    half-width [Hz] and the lines of the band around it."""
    win = np.where(np.abs(freq - f_centre) <= search * f_centre)[0]
    i = int(win[np.argmax(ind[win])]) if win.size else int(np.argmin(np.abs(freq - f_centre)))
    f_pk = float(freq[i])
    hw = max(_half_power(freq, ind, i), 0.5 * float(np.median(np.diff(freq))) if freq.size > 1 else 0.0)
    half = min(max(band_halfwidths * hw, min_band * f_pk), max_band * f_pk)
    sel = (freq >= f_pk - half) & (freq <= f_pk + half)
    return i, hw, sel


class _BandFit:
    """The least-squares problem of one band: poles ``(ω_r, ζ)`` as unknowns ``x`` (per pole ω_r/ω_c and
    log ζ), the residues and out-of-band terms projected out per entry (:func:`_project`).

    ``f_b`` the band's lines [Hz], ``y``/``s`` ``(n, n_e)`` the used entries and their weights,
    ``f_pk`` the recorded peak [Hz] (ω_c = 2π f_pk).
    """

    def __init__(self, f_b: np.ndarray, y: np.ndarray, s: np.ndarray, f_pk: float) -> None:
        self.f_b, self.y, self.s, self.f_pk = f_b, y, s, f_pk
        self.omega = 2 * np.pi * f_b
        self.w_c = 2 * np.pi * f_pk
        self.n_e = y.shape[1]
        self.n_res = 2 * int((s > 0).sum())

    def poles(self, x: np.ndarray) -> np.ndarray:
        x = x.reshape(-1, 2)
        return np.column_stack([self.w_c * x[:, 0], np.exp(x[:, 1])])

    def resid(self, x: np.ndarray) -> np.ndarray:
        _, r = _project(_basis(self.omega, self.poles(x), self.w_c), self.y, self.s)
        return np.concatenate([r.real.ravel(), r.imag.ravel()])

    def solve(self, starts):
        """Poles from ``starts`` [(Hz, ζ)]: the unknowns, the residual and the number of parameters."""
        import scipy.optimize

        n_p, f_pk, f_b = len(starts), self.f_pk, self.f_b
        x0 = np.array([[f / f_pk, np.log(np.clip(z, *_ZETA_BOUNDS))] for f, z in starts]).ravel()
        lo = np.tile([f_b[0] / f_pk * 0.98, np.log(_ZETA_BOUNDS[0])], n_p)
        hi = np.tile([f_b[-1] / f_pk * 1.02, np.log(_ZETA_BOUNDS[1])], n_p)
        x0 = np.clip(x0, lo + 1e-12, hi - 1e-12)
        sol = scipy.optimize.least_squares(self.resid, x0, bounds=(lo, hi), x_scale=np.tile([1e-3, 0.1], n_p),
                                           xtol=1e-14, ftol=1e-14, gtol=1e-14, max_nfev=400)
        r = self.resid(sol.x)
        n_par = sol.x.size + 2 * (n_p + 3) * self.n_e
        return sol.x, r, n_par

    def bic(self, r: np.ndarray, n_par: int) -> float:
        return self.n_res * np.log(max(float(r @ r), 1e-300) / self.n_res) + n_par * np.log(self.n_res)

    def covariance(self, x: np.ndarray, r: np.ndarray, n_par: int):
        """Covariance of ``x`` (central-difference Jacobian at the solution: more accurate than the
        solver's forward one) and the reduced χ²."""
        jac = np.empty((r.size, x.size))
        for k in range(x.size):
            h = 1e-6 if k % 2 == 0 else 1e-5
            dx = np.zeros_like(x)
            dx[k] = h
            jac[:, k] = (self.resid(x + dx) - self.resid(x - dx)) / (2 * h)
        chi2_red = float(r @ r) / max(r.size - n_par, 1)
        return np.linalg.pinv(jac.T @ jac) * chi2_red, chi2_red


def _with_neighbours(fit: _BandFit, freq: np.ndarray, ind: np.ndarray, sel: np.ndarray, i: int, starts):
    """The fit from ``starts``, with a neighbouring recorded peak in the band fitted along as a pole of
    its own when it earns its parameters (BIC); candidates: local maxima of the smoothed indicator
    10 % above their saddles. Returns the unknowns, the residual and the number of parameters."""
    import scipy.signal

    sm = np.convolve(np.log(np.maximum(ind[sel], 1e-300)), np.ones(3) / 3, mode="same")
    cand, props = scipy.signal.find_peaks(sm, prominence=0.1)
    cand = [int(k) for k in cand[np.argsort(-props["prominences"])] if abs(int(k) + np.argmax(sel) - i) > 2]
    x, r, n_par = fit.solve(starts)
    for k in cand[:2]:
        kk = k + int(np.argmax(sel))
        trial = starts + [(float(freq[kk]), max(_half_power(freq, ind, kk) / freq[kk], 2e-4))]
        x2, r2, n2 = fit.solve(trial)
        p2 = fit.poles(x2)
        if fit.bic(r2, n2) <= fit.bic(r, n_par) - 10.0 and abs(p2[0, 0] - p2[1, 0]) > 2 * np.pi * 1e-3 * fit.f_pk:
            starts, x, r, n_par = trial, x2, r2, n2
    return x, r, n_par
