"""The spindle's own uncertainty when it is estimated from extension-bar taps (issue 22 item 1).

A measured spindle whose (x, θ) receptance at the nose was estimated by the extension method
(:func:`jointdb.coupling.rotations_by_extension`: a modelled bar fixed to the nose, translations tapped at
two points on it) is as uncertain as the taps and the estimate's noise amplification make it. The band
samples it as the identification samples a joint's fit: the taps are perturbed with relative complex
noise of their own level ``ε`` (stated, or estimated from the taps, :func:`tap_noise_level`), the estimate
is redone for every sample (batched over samples and lines), and each sample's change of the estimate is
added to the spindle receptance the prediction uses — a parametric bootstrap around the estimate. With
noise-free taps (``ε = 0``) every sample is the nominal spindle: the term is 0.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from jointdb.errors import InputError
from jointdb.frf import FRF, Dof

__all__ = ["SpindleEstimate", "tap_noise_level", "spindle_deviations"]

#: Median absolute deviation to standard deviation of a normal variable.
_MAD = 1.4826


@dataclass(frozen=True, eq=False)
class SpindleEstimate:
    """How a measured spindle's receptance was estimated: extension-bar taps and the bar's model.

    Parameters
    ----------
    taps
        The assembly's (spindle + bar) measured translational receptances among the two bar points
        (``G_11, G_12, G_22``; a missing one is completed by reciprocity), m/N.
    extension
        The bar's free receptance over its joint point (translation and rotation) and the two points
        (translation), e.g. ``BeamModel.frf``; on the taps' lines or a grid covering them.
    e_joint
        The bar's node fixed to the spindle nose.
    e_points
        The bar's two tapped nodes.
    noise
        Relative complex noise level ε of the taps (RMS of ``|ΔG / G|``, e.g. 0.0075); None: estimated
        from the taps (:func:`tap_noise_level`).
    translation, rotation
        The bending plane's directions (default ``x``, ``ry``).
    """

    taps: FRF
    extension: FRF
    e_joint: int
    e_points: tuple[int, int]
    noise: float | None = None
    translation: str = "x"
    rotation: str = "ry"

    def noise_level(self) -> tuple[float, str]:
        """``(ε, source)``: the taps' relative noise level and ``"stated"`` or ``"estimated from the taps"``."""
        if self.noise is not None:
            eps = float(self.noise)
            if not (np.isfinite(eps) and 0 <= eps < 1):
                raise InputError(f"spindle estimate: noise must be a relative level in [0, 1), got {self.noise!r}")
            return eps, "stated"
        return tap_noise_level(self.taps), "estimated from the taps"


def tap_noise_level(taps: FRF) -> float:
    """Relative complex noise level ε of measured FRFs, from their own scatter between adjacent lines.

    A smooth FRF on a fine grid has small fourth differences ``Δ⁴G = G₋₂ − 4G₋₁ + 6G₀ − 4G₁ + G₂``;
    independent relative noise of level ε (each of the real and imaginary parts ε/√2 of |G|) gives them a
    standard deviation ``ε √35 |G|`` per part. ``ε = √(2/70) · 1.4826 · median |Δ⁴G / G|`` over the parts,
    lines and entries (the median keeps the few lines near sharp resonances, where the FRF itself curves, from
    counting; second differences would leave a curvature bias of ~25 % at 0.2 % noise).

    Parameters
    ----------
    taps
        Measured FRFs ``(n_freq, n_out, n_in)``, evenly and finely spaced lines (at least 5).

    Returns
    -------
    float
        ε (0 for a smooth, noise-free FRF on a fine grid, up to its own curvature).

    Raises
    ------
    InputError
        Fewer than 5 lines or no finite non-zero entry.
    """
    v = np.asarray(taps.values).reshape(taps.n_freq, -1)
    if v.shape[0] < 5:
        raise InputError(f"the noise level of the taps needs at least 5 lines, got {v.shape[0]}")
    with np.errstate(divide="ignore", invalid="ignore"):
        d4 = (v[:-4] - 4 * v[1:-3] + 6 * v[2:-2] - 4 * v[3:-1] + v[4:]) / np.abs(v[2:-2])
    parts = np.concatenate([d4.real.ravel(), d4.imag.ravel()])
    parts = parts[np.isfinite(parts)]
    if parts.size == 0:
        raise InputError("the taps have no finite non-zero entry to estimate their noise from")
    return float(np.sqrt(2.0 / 70.0) * _MAD * np.median(np.abs(parts)))


def _blocks(est: SpindleEstimate, freq: np.ndarray):
    """``(h00, e, he, g)`` of the extension equations on ``freq`` (``(n_freq, 2, 2)`` each)."""
    from jointdb.coupling._common import fetch

    def on(frf: FRF, what: str) -> FRF:
        frf = frf.to("receptance")
        if frf.n_freq == freq.size and np.allclose(frf.freq, freq, rtol=1e-12, atol=0):
            return frf
        try:
            return frf.resample(freq)
        except InputError as exc:
            raise InputError(f"spindle estimate: the {what} {exc}") from None

    t, r = est.translation, est.rotation
    p1, p2 = est.e_points
    if p1 == p2:
        raise InputError("spindle estimate: the two tapped points on the extension must differ")
    E, G = on(est.extension, "extension's model"), on(est.taps, "taps")
    j = [Dof(est.e_joint, t), Dof(est.e_joint, r)]
    pts = [Dof(p1, t), Dof(p2, t)]
    return (fetch("extension", E, j, j, "the joint point incl. rotation"), fetch("extension", E, j, pts),
            fetch("extension", E, pts, pts), fetch("spindle estimate taps", G, pts, pts))


def spindle_deviations(est: SpindleEstimate, freq, n: int, rng: np.random.Generator) -> np.ndarray:
    """Sampled changes of the spindle's (x, θ) receptance estimate under the taps' noise.

    Parameters
    ----------
    est
        The estimate (taps, bar model, noise level).
    freq : ndarray, shape (n_freq,)
        Lines [Hz] of the prediction (the taps and bar model are resampled onto them).
    n
        Number of samples.
    rng
        Random generator.

    Returns
    -------
    ndarray ``(n, n_freq, 2, 2)``
        ``Ĥ(G (1 + ε z_s)) − Ĥ(G)`` per sample s (``z`` complex standard normal per line and tap, the
        reciprocal tap ``G_21`` equal to ``G_12``), to add to the spindle receptance over (x, θ); zeros when ε = 0.

    Raises
    ------
    InputError
        Missing DOFs, a grid the taps do not cover, or a singular extension system.
    """
    from jointdb.coupling.rotational import extension_receptance

    f = np.asarray(freq, float)
    eps, _ = est.noise_level()
    if eps == 0:
        return np.zeros((int(n), f.size, 2, 2), dtype=complex)
    h00, e, he, g = _blocks(est, f)
    # the reciprocal part of the taps: the samples set G_21 = G_12, so the nominal estimate must too, or every
    # sample would differ from it by (G_12 − G_21) / 2 carried through the algebra (an offset, not noise)
    g = 0.5 * (g + np.swapaxes(g, -1, -2))
    z = (rng.standard_normal((int(n), f.size, 3)) + 1j * rng.standard_normal((int(n), f.size, 3))) / np.sqrt(2)
    gs = np.broadcast_to(g, (int(n),) + g.shape).copy()
    gs[..., 0, 0] *= 1 + eps * z[..., 0]
    gs[..., 1, 1] *= 1 + eps * z[..., 2]
    gs[..., 0, 1] *= 1 + eps * z[..., 1]
    gs[..., 1, 0] = gs[..., 0, 1]
    try:
        nominal = extension_receptance(h00, e, he, g)
        sampled = extension_receptance(h00[None], e[None], he[None], gs)
    except np.linalg.LinAlgError:
        raise InputError("spindle estimate: the extension equations are singular at some line; "
                         "choose tapped points at other distances from the joint") from None
    return sampled - nominal[None]
