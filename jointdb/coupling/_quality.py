"""Honest quality measures for coupled or identified assemblies: dominant-peak errors and a plain verdict.

A mean relative deviation over all lines is dominated by the many off-resonance lines;
it can read 0.04 while the dominant resonance is 3× off. The peak errors compare the
dominant modes of the measurement with the prediction's nearest peak.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = ["dominant_peaks", "peak_errors", "peak_verdicts", "parameter_verdicts", "PEAK_AMPLITUDE_TOL"]

PEAK_AMPLITUDE_TOL = 0.25  # a peak off by more than 25 % in amplitude is "missed"
PEAK_FREQUENCY_TOL = 0.02  # … or by more than 2 % (or 1.5 lines) in frequency


def dominant_peaks(freq: np.ndarray, mag: np.ndarray, n: int = 3, min_prominence: float = 0.3) -> np.ndarray:
    """Indices of the ``n`` highest resonance peaks of ``|H|`` (nf,), highest first.

    A peak must stand out of its surroundings by ``min_prominence`` decades of log10|H|
    (0.3 = a factor 2), so that noise ripples are not taken for modes.
    """
    from scipy.signal import find_peaks

    m = np.log10(np.maximum(np.asarray(mag, float), 1e-300))
    idx, props = find_peaks(m, prominence=min_prominence)
    if idx.size == 0:
        return np.array([int(np.argmax(m))])
    order = np.argsort(-m[idx])
    return idx[order][:n]


def peak_errors(freq: np.ndarray, predicted: np.ndarray, measured: np.ndarray, n: int = 3) -> list[dict]:
    """Frequency and amplitude errors of the measured dominant peaks (one entry of the FRF).

    Parameters
    ----------
    freq
        Lines in Hz (nf,).
    predicted, measured
        Complex FRF entries (nf,).
    n
        Number of dominant measured peaks compared.

    Returns
    -------
    list of dict
        Per peak: ``f_measured_hz``, ``f_predicted_hz`` (highest predicted line within ±15 %
        of the measured peak frequency), ``frequency_error`` (relative), ``amplitude_measured``,
        ``amplitude_predicted``, ``amplitude_ratio`` (predicted / measured) and ``missed`` (bool).
    """
    freq = np.asarray(freq, float)
    a_m, a_p = np.abs(measured), np.abs(predicted)
    df = np.median(np.diff(freq)) if freq.size > 1 else 0.0
    out = []
    for i in dominant_peaks(freq, a_m, n):
        win = np.flatnonzero(np.abs(freq - freq[i]) <= 0.15 * freq[i])
        j = win[np.argmax(a_p[win])]
        ferr = (freq[j] - freq[i]) / freq[i] if freq[i] > 0 else 0.0
        ratio = a_p[j] / a_m[i] if a_m[i] > 0 else np.inf
        ftol = max(PEAK_FREQUENCY_TOL, 1.5 * df / freq[i]) if freq[i] > 0 else PEAK_FREQUENCY_TOL
        missed = bool(abs(ferr) > ftol or not (1 / (1 + PEAK_AMPLITUDE_TOL) <= ratio <= 1 + PEAK_AMPLITUDE_TOL))
        out.append({"f_measured_hz": float(freq[i]), "f_predicted_hz": float(freq[j]),
                    "frequency_error": float(ferr), "amplitude_measured": float(a_m[i]),
                    "amplitude_predicted": float(a_p[j]), "amplitude_ratio": float(ratio), "missed": missed})
    return out


def peak_verdicts(peaks: Sequence[dict], what: str, mean_deviation: float | None = None) -> list[str]:
    """Plain sentences for missed peaks (empty when every dominant peak is reproduced)."""
    lines = []
    for p in peaks:
        if p["missed"]:
            hide = f"; the mean deviation {mean_deviation:.3g} hides this" if mean_deviation is not None else ""
            lines.append(
                f"{what}: the peak at {p['f_measured_hz']:.4g} Hz is missed — predicted {p['amplitude_predicted']:.3g} "
                f"at {p['f_predicted_hz']:.4g} Hz vs measured {p['amplitude_measured']:.3g} "
                f"({p['amplitude_ratio']:.2f}×, {p['frequency_error']:+.1%} in frequency){hide}")
    return lines


def parameter_verdicts(names: Sequence[str], rel_se: np.ndarray, correlation: np.ndarray,
                       rel_limit: float = 0.10, corr_limit: float = 0.95) -> list[str]:
    """Sentences for parameters with a relative standard error above ``rel_limit`` or strongly correlated pairs."""
    lines = []
    for n, r in zip(names, rel_se):
        if not np.isfinite(r) or r > rel_limit:
            lines.append(f"{n} is poorly determined (standard error {r:.0%} of its value); "
                         "more averages or other measurement points are needed before trusting it")
    c = np.abs(np.triu(correlation, 1))
    for i, j in zip(*np.nonzero(c > corr_limit)):
        lines.append(f"{names[i]} and {names[j]} are correlated {correlation[i, j]:+.2f}: the data barely separate them")
    return lines
