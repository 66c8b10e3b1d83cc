"""Is constant k, c an adequate joint model for this campaign? (model-adequacy check after the output-error fit)

The output-error fit of constant k, c is the better joint when the joint IS constant: it
averages the measurement noise over all lines, while the per-line IRC joint carries (and
amplifies) it. When the real joint is frequency dependent (e.g. a contact layer along an
insertion), a constant k, c cannot reproduce the measured assembly however good the data,
and the per-line joint is the better description.

The check compares the constant model's misfit with the noise the data show:

- misfit: robust scale (1.4826 · median |r|) of the relative residual
  ``r = (G_constant − G_measured) / |G_measured|`` over the fit band, real and imaginary parts
  pooled (the output-error fit's own weighting);
- noise: the same robust scale of the residual's second differences divided by √6 — white
  noise of standard deviation σ has second differences of standard deviation √6 σ, while a
  systematic misfit that varies smoothly from line to line nearly cancels in them.

With a model that fits, both measure the noise and their ratio is ≈ 1 (± a few per cent
for hundreds of lines). The constant model is rejected when the ratio exceeds
:data:`MISFIT_TO_NOISE_LIMIT`; the per-line joint is then kept only if it also reproduces the
measured dominant peaks better (frequency and amplitude errors in units of the verdict's
tolerances), so that a per-line joint spoiled by noise or smoothing is never preferred.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from jointdb.coupling._quality import PEAK_AMPLITUDE_TOL, PEAK_FREQUENCY_TOL

__all__ = ["Adequacy", "MISFIT_TO_NOISE_LIMIT", "noise_and_misfit", "peak_score", "assess_constant_model"]

#: misfit / noise above which constant k, c is rejected. Under the null (model fits, noise independent
#: from line to line) the ratio is 1 within ~10 % for ≥ 100 lines × 2 parts, and a systematic part of
#: the residual as large as the noise only brings it to about √2 — so 2 means a systematic misfit of
#: at least about √3 ≈ 1.7 times the noise. Noise correlated between neighbouring lines (overlapped,
#: windowed FFT averages) lowers the roughness estimate and can trip the check; the peak comparison
#: then still keeps the constant joint unless the per-line one reproduces the peaks better.
MISFIT_TO_NOISE_LIMIT = 2.0
_MAD = 1.4826  # median |x| → standard deviation for a Gaussian


@dataclass(frozen=True)
class Adequacy:
    """Outcome of the check (all JSON-able scalars).

    ``misfit`` and ``noise``: robust relative scales (per real/imaginary part); ``ratio`` = misfit / noise;
    ``constant_peak_score`` / ``per_line_peak_score``: worst dominant-peak error of the re-coupled
    identification assembly in units of the tolerances (≤ 1: reproduced); ``keep_per_line``: the decision.
    """

    misfit: float
    noise: float
    ratio: float
    constant_peak_score: float
    per_line_peak_score: float
    keep_per_line: bool

    def as_dict(self) -> dict:
        return {"misfit": self.misfit, "noise": self.noise, "misfit_to_noise": self.ratio,
                "misfit_to_noise_limit": MISFIT_TO_NOISE_LIMIT, "constant_peak_score": self.constant_peak_score,
                "per_line_peak_score": self.per_line_peak_score,
                "catalogued_joint": "per-line" if self.keep_per_line else "constant"}

    def verdict(self) -> str | None:
        """The ``verdict:`` sentence when constant k, c is rejected by the data (None when it is adequate)."""
        if self.ratio <= MISFIT_TO_NOISE_LIMIT:
            return None
        what = (f"constant k, c misfits the measured assembly {self.ratio:.1f}× beyond its noise "
                f"(residual {self.misfit:.2%} vs noise {self.noise:.2%} per line)")
        peaks = (f"dominant peaks {self.constant_peak_score:.2f} vs {self.per_line_peak_score:.2f} of the "
                 f"tolerance with the per-line joint")
        if self.keep_per_line:
            return (f"constant k, c cannot represent this joint: {what}; {peaks}; the per-line joint is kept "
                    "(output-error k, c stored as information only)")
        return (f"constant k, c is only approximate: {what}, but the per-line joint does not reproduce the "
                f"dominant peaks better ({peaks}); the output-error joint is kept")


def noise_and_misfit(measured: np.ndarray, model: np.ndarray) -> tuple[float, float]:
    """Robust noise and misfit scales of ``model`` against ``measured``.

    Parameters
    ----------
    measured, model
        Complex FRFs ``(n_freq, n_out, n_in)`` on the same lines (only the lines to judge,
        on an evenly spaced grid). Entries or lines with ``|measured| = 0`` or non-finite
        values are dropped.

    Returns
    -------
    (noise, misfit)
        Relative standard deviations per real/imaginary part.
    """
    meas = np.asarray(measured)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = (np.asarray(model) - meas) / np.abs(meas)
    r = r.reshape(r.shape[0], -1)
    parts, diffs = [], []
    for col in r.T:
        col = col[np.isfinite(col)]
        if col.size < 5:
            continue
        for p in (col.real, col.imag):
            parts.append(p)
            diffs.append(p[:-2] - 2 * p[1:-1] + p[2:])
    if not parts:
        return float("nan"), float("nan")
    misfit = _MAD * float(np.median(np.abs(np.concatenate(parts))))
    noise = _MAD * float(np.median(np.abs(np.concatenate(diffs)))) / np.sqrt(6.0)
    return noise, misfit


def peak_score(peaks: Sequence[dict]) -> float:
    """Worst dominant-peak error in units of the verdict's tolerances (frequency 2 %, amplitude 25 %)."""
    worst = 0.0
    for p in peaks:
        ratio = float(p["amplitude_ratio"])
        amp = abs(np.log(ratio)) / np.log1p(PEAK_AMPLITUDE_TOL) if ratio > 0 and np.isfinite(ratio) else np.inf
        worst = max(worst, abs(float(p["frequency_error"])) / PEAK_FREQUENCY_TOL, amp)
    return float(worst)


def assess_constant_model(measured: np.ndarray, constant: np.ndarray, constant_peaks: Sequence[dict],
                          per_line_peaks: Sequence[dict]) -> Adequacy:
    """Decide between the constant (output-error) and the per-line joint.

    Parameters
    ----------
    measured, constant
        Measured assembly and its re-coupling with the constant joint, ``(n_freq, n_out, n_in)``
        over the fit band.
    constant_peaks, per_line_peaks
        :func:`jointdb.coupling._quality.peak_errors` rows of the identification assembly
        re-coupled with the constant and with the per-line joint.
    """
    noise, misfit = noise_and_misfit(measured, constant)
    ratio = misfit / noise if noise > 0 else (np.inf if misfit > 0 else 1.0)
    s_const, s_line = peak_score(constant_peaks), peak_score(per_line_peaks)
    keep = bool(np.isfinite(ratio) and ratio > MISFIT_TO_NOISE_LIMIT and s_line < s_const) or bool(
        not np.isfinite(ratio) and s_line < s_const)
    return Adequacy(float(misfit), float(noise), float(ratio), s_const, s_line, keep)
