"""Residues by least squares in the frequency domain (LSFD) and fit quality.

With the poles fixed (from pLSCF), every FRF entry is linear in the real and
imaginary parts of the residues and in the real residual terms (module doc of
``_model``); one real least-squares problem with one right-hand side per entry
solves all entries at once (Peeters et al. 2004, §3; Ewins, *Modal Testing*,
§4.4). Quality per entry: normalised mean-square error
``NMSE = ‖H − Ĥ‖² / ‖H‖²`` and the FRF assurance criterion
``FRAC = |Hᴴ Ĥ|² / (‖H‖² ‖Ĥ‖²)`` (Heylen & Lammens 1996).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from jointdb.errors import InputError
from jointdb.frf import FRF, Dof, Quantity
from jointdb.modal._lscf import StabilisationCriteria, StabilisationDiagram, select_poles, stabilisation_diagram
from jointdb.modal._model import ModalModel

__all__ = ["FitQuality", "ModalFit", "fit_modes", "fit_residues", "fit_quality"]


@dataclass(frozen=True, eq=False)
class FitQuality:
    """How well a modal model reproduces the FRF it was fitted to, in the fitted band.

    Attributes
    ----------
    nmse
        Normalised mean square error ``‖H − Ĥ‖² / ‖H‖²`` per entry, ``(n_out, n_in)``.
    frac
        Frequency response assurance criterion per entry (1 = same shape), ``(n_out, n_in)``.
    nmse_total
        ``‖H − Ĥ‖² / ‖H‖²`` over all entries.
    frac_min
        The smallest FRAC.
    """

    nmse: np.ndarray
    frac: np.ndarray
    nmse_total: float
    frac_min: float


@dataclass(frozen=True, eq=False)
class ModalFit:
    """Result of :func:`fit_modes`: the model, the stabilisation diagram and the quality.

    Attributes
    ----------
    model
        The fitted :class:`ModalModel` (receptance residues).
    diagram
        The :class:`StabilisationDiagram` the poles were selected from.
    quality
        :class:`FitQuality` in the band, in the FRF's own quantity.
    band
        ``(f_min, f_max)`` [Hz] fitted.
    quantity
        The quantity of the fitted FRF.
    """

    model: ModalModel
    diagram: StabilisationDiagram
    quality: FitQuality
    band: tuple[float, float]
    quantity: Quantity

    @property
    def freq_hz(self) -> np.ndarray:
        return self.model.freq_hz

    @property
    def zeta(self) -> np.ndarray:
        return self.model.zeta

    @property
    def residues(self) -> np.ndarray:
        return self.model.residues

    def table(self) -> list[dict]:
        """One row per mode: frequency, damping and the largest residue magnitude.

        Returns
        -------
        list of dict
            ``mode``, ``freq_hz``, ``zeta``, ``max_abs_residue``.
        """
        return [
            {
                "mode": k + 1,
                "freq_hz": float(self.model.freq_hz[k]),
                "zeta": float(self.model.zeta[k]),
                "max_abs_residue": float(np.max(np.abs(self.model.residues[k]))),
            }
            for k in range(self.model.n_modes)
        ]


def fit_quality(measured: np.ndarray, fitted: np.ndarray) -> FitQuality:
    """NMSE and FRAC per entry of two FRF arrays.

    Parameters
    ----------
    measured
        Reference FRF values, complex ``(n_f, n_out, n_in)``.
    fitted
        Model FRF values on the same lines, same shape and quantity.

    Returns
    -------
    FitQuality
    """
    h, g = np.asarray(measured), np.asarray(fitted)
    e2 = np.sum(np.abs(h - g) ** 2, axis=0)
    h2 = np.sum(np.abs(h) ** 2, axis=0)
    g2 = np.sum(np.abs(g) ** 2, axis=0)
    safe = np.where(h2 > 0, h2, 1.0)
    nmse = e2 / safe
    frac = np.abs(np.sum(h.conj() * g, axis=0)) ** 2 / (safe * np.where(g2 > 0, g2, 1.0))
    return FitQuality(nmse=nmse, frac=frac, nmse_total=float(e2.sum() / max(h2.sum(), 1e-300)), frac_min=float(frac.min()))


def fit_residues(
    freq: np.ndarray,
    h: np.ndarray,
    poles: np.ndarray,
    quantity: "str | Quantity" = "receptance",
    upper: bool = True,
    lower: bool = True,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """LSFD: receptance residues and residual terms for fixed poles.

    Parameters
    ----------
    freq
        Hz, shape ``(n_f,)``, > 0 when ``lower`` is used.
    h
        FRF values ``(n_f, n_out, n_in)`` in ``quantity``.
    poles
        Poles in rad/s with positive imaginary parts, shape ``(n_modes,)``.
    quantity
        The quantity of ``h`` (receptance, mobility, accelerance).
    upper
        Fit an upper residual (constant: flexibility of modes above the band).
    lower
        Fit a lower residual (``1/(iω)²``: modes below the band).

    Returns
    -------
    residues : ndarray, complex, shape (n_modes, n_out, n_in)
        Receptance residues [m/N].
    upper : ndarray, shape (n_out, n_in)
        Upper residual [m/N] (zero when not fitted).
    lower : ndarray, shape (n_out, n_in)
        Lower residual [m/(N·s²)] (zero when not fitted).
    """
    freq = np.asarray(freq, dtype=float)
    h = np.asarray(h, dtype=complex)
    q = Quantity.parse(quantity)
    if lower and freq[0] <= 0:
        raise InputError("the lower residual needs frequencies > 0 Hz; start the band above 0 Hz")
    iw = 1j * 2 * np.pi * freq
    lam = np.asarray(poles, dtype=complex)
    g = 1.0 / (iw[:, None] - lam[None, :])
    gc = 1.0 / (iw[:, None] - lam.conj()[None, :])
    cols = [g + gc, 1j * (g - gc)]  # residue = a + ib  ->  a(g+gc) + b·i(g−gc)
    basis = np.concatenate(cols, axis=1)
    if upper:
        basis = np.concatenate([basis, np.ones((freq.size, 1))], axis=1)
    if lower:
        basis = np.concatenate([basis, (1.0 / iw**2)[:, None]], axis=1)
    basis = basis * (iw**q.power)[:, None]
    a = np.concatenate([basis.real, basis.imag], axis=0)
    n_f, n_o, n_i = h.shape
    rhs = h.reshape(n_f, n_o * n_i)
    b = np.concatenate([rhs.real, rhs.imag], axis=0)
    colscale = np.linalg.norm(a, axis=0)
    colscale = np.where(colscale > 0, colscale, 1.0)
    x, *_ = np.linalg.lstsq(a / colscale, b, rcond=None)
    x = x / colscale[:, None]
    n = lam.size
    res = (x[:n] + 1j * x[n : 2 * n]).reshape(n, n_o, n_i)
    k = 2 * n
    up = np.zeros((n_o, n_i))
    lo = np.zeros((n_o, n_i))
    if upper:
        up = x[k].reshape(n_o, n_i)
        k += 1
    if lower:
        lo = x[k].reshape(n_o, n_i)
    return res, up, lo


def _as_frf(frf) -> FRF:
    if isinstance(frf, FRF):
        return frf
    if isinstance(frf, tuple) and len(frf) == 2:
        f, h = frf
        return FRF(np.asarray(f), np.asarray(h).reshape(len(f), 1, 1), (Dof(1, "x"),), (Dof(1, "x"),))
    raise InputError("fit_modes needs an FRF or a (freq_hz, values) tuple")


def fit_modes(
    frf: "FRF | tuple[np.ndarray, np.ndarray]",
    n_modes: int | None = None,
    band: Sequence[float] | None = None,
    *,
    max_order: int = 30,
    residuals: bool = True,
    criteria: StabilisationCriteria = StabilisationCriteria(),
    min_count: int = 3,
) -> ModalFit:
    """Fit a modal model to an FRF: pLSCF poles, automatic selection, LSFD residues.

    Parameters
    ----------
    frf
        Receptance, mobility or accelerance (``jointdb.frf.FRF``), or a
        ``(freq_hz, values)`` tuple read as a driving-point receptance.
    n_modes
        Number of modes to keep (the best-stabilised clusters in the band);
        ``None`` keeps every pole stable over ``min_count`` orders.
    band
        ``(fmin, fmax)`` in Hz (default: all lines above 0 Hz).
    max_order
        Highest pLSCF model order of the stabilisation diagram.
    residuals
        Fit upper and lower residual terms (out-of-band modes).
    criteria
        :class:`StabilisationCriteria` of the stabilisation diagram.
    min_count
        Without ``n_modes``: the number of model orders a pole must be stable over.

    Returns
    -------
    ModalFit
        ``model`` (receptance residues), ``diagram``, ``quality`` (NMSE and FRAC
        per entry in the band, in the FRF's own quantity).

    Raises
    ------
    InputError
        On an empty band or too few lines.
    NumericalError
        If fewer stable poles exist than ``n_modes``.
    """
    frf = _as_frf(frf)
    lo, hi = (None, None) if band is None else (float(band[0]), float(band[1]))
    if band is not None and not (0 <= lo < hi):
        raise InputError(f"band must be (fmin, fmax) with 0 <= fmin < fmax, got {tuple(band)}")
    part = frf.band(lo, hi)
    if part.freq[0] == 0:
        part = part.replace(freq=part.freq[1:], values=part.values[1:])
    if n_modes is not None and n_modes < 1:
        raise InputError(f"n_modes must be >= 1, got {n_modes}")
    diagram = stabilisation_diagram(part.freq, part.values, max_order=max_order, criteria=criteria)
    poles = select_poles(diagram, n_modes=n_modes, freq_tol=criteria.freq_tol, min_count=min_count)
    res, up, low = fit_residues(part.freq, part.values, poles, part.quantity, upper=residuals, lower=residuals)
    wn = np.abs(poles)
    model = ModalModel(wn / (2 * np.pi), -poles.real / wn, res, frf.outputs, frf.inputs, up, low)
    fitted = model.synthesize(part.freq, part.quantity).values
    quality = fit_quality(part.values, fitted)
    return ModalFit(model, diagram, quality, (float(part.freq[0]), float(part.freq[-1])), part.quantity)
