"""Equivalent stiffness and damping of an identified joint, constant (k, c) band fit."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from jointdb.coupling._common import as_receptance
from jointdb.errors import InputError
from jointdb.frf import FRF, Dof

__all__ = ["equivalent_stiffness_damping", "fit_constant_kc", "KCFit"]


def equivalent_stiffness_damping(joint_frf: FRF, full: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Frequency-dependent ``k(ω)`` and ``c(ω)`` with ``k + iωc = 1/h`` (docs/theory.md §2a).

    Parameters
    ----------
    joint_frf
        Joint receptance (square; converted to receptance).
    full
        False: per diagonal term, ``1/h_ii`` → arrays ``(n_freq, n)``.
        True: the dynamic stiffness matrix ``Z = H⁻¹`` → ``(n_freq, n, n)``.

    Returns
    -------
    k, c
        Stiffness (N/m, N·m/rad) and damping (N·s/m, N·m·s/rad). ``c`` is NaN
        at 0 Hz.

    Raises
    ------
    InputError
        If ``joint_frf`` is not an FRF, not square, or a diagonal term is zero.
    """
    h = as_receptance("joint", joint_frf)
    if h.outputs != h.inputs:
        raise InputError("equivalent_stiffness_damping needs a square joint FRF (outputs == inputs)")
    w = h.omega
    if full:
        z = np.linalg.inv(h.values)
        wv = w[:, None, None]
    else:
        diag = np.diagonal(h.values, axis1=1, axis2=2)
        if np.any(diag == 0):
            raise InputError("a diagonal joint term is zero (rigid); no equivalent stiffness")
        z = 1.0 / diag
        wv = w[:, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        c = np.where(wv > 0, z.imag / np.where(wv > 0, wv, 1.0), np.nan)
    return z.real, c


@dataclass(frozen=True, eq=False)
class KCFit:
    """Constant spring–damper fitted to a joint FRF over a band.

    Attributes
    ----------
    dofs
        The joint's DOFs, one per diagonal term.
    k
        Stiffness per DOF ``(n,)`` [N/m or N·m/rad].
    c
        Viscous damping per DOF ``(n,)`` [N·s/m or N·m·s/rad].
    error
        Relative RMS misfit ``‖h − 1/(k + iωc)‖ / ‖h‖`` of the receptance over the band, ``(n,)``.
    band_hz
        ``(f_min, f_max)`` [Hz] of the lines used.
    """

    dofs: tuple[Dof, ...]
    k: np.ndarray
    c: np.ndarray
    error: np.ndarray
    band_hz: tuple[float, float]

    def __iter__(self):  # allows ``k, c, err = fit_constant_kc(...)``
        return iter((self.k, self.c, self.error))


def fit_constant_kc(
    joint_frf: FRF,
    band: tuple[float, float] | None = None,
    *,
    method: str = "median",
    mask: np.ndarray | None = None,
) -> KCFit:
    """Constant ``(k, c)`` per diagonal joint term over a band.

    Fits ``Z(ω) = 1/h(ω) ≈ k + iωc``. ``method="lsq"``: ``k`` = mean of
    ``Re Z``, ``c = Σ ω Im Z / Σ ω²`` (linear least squares);
    ``method="median"`` (default): ``k`` = median of ``Re Z``, ``c`` = median
    of ``Im Z / ω`` — robust against the spikes that noise produces at a few
    lines. Reports the relative misfit of the receptance over the band.

    Parameters
    ----------
    joint_frf
        Joint receptance FRF, square ``(n_freq, n, n)`` (converted to receptance).
    band
        ``(f_min, f_max)`` in Hz; default: all lines.
    method
        ``"median"`` or ``"lsq"``.
    mask
        Optional boolean ``(n_freq,)`` over the full grid: lines to use (e.g.
        ``~result.unreliable``); ignored if it leaves fewer than 3 lines.

    Returns
    -------
    KCFit
        ``k`` (N/m, N·m/rad), ``c`` (N·s/m, N·m·s/rad) and relative misfit per
        diagonal DOF, each ``(n,)``; unpacks as ``k, c, err``.

    Raises
    ------
    InputError
        Empty band, non-square FRF, unknown method, mask not of shape ``(n_freq,)``.
    """
    if method not in ("median", "lsq"):
        raise InputError(f"fit_constant_kc method {method!r}: expected median or lsq")
    h = as_receptance("joint", joint_frf)
    if mask is not None and np.shape(mask) != (h.n_freq,):
        raise InputError(f"fit_constant_kc mask has shape {np.shape(mask)}; expected ({h.n_freq},), one per line")
    use = np.ones(h.n_freq, dtype=bool)
    if band is not None:
        use &= (h.freq >= band[0]) & (h.freq <= band[1])
        if not use.any():
            raise InputError(f"no frequency lines in [{band[0]}, {band[1]}] Hz")
    if mask is not None and np.count_nonzero(use & np.asarray(mask, bool)) >= 3:
        use &= np.asarray(mask, bool)
    h = h.replace(freq=h.freq[use], values=h.values[use])
    if h.outputs != h.inputs:
        raise InputError("fit_constant_kc needs a square joint FRF (outputs == inputs)")
    diag = np.diagonal(h.values, axis1=1, axis2=2)
    if np.any(diag == 0):
        raise InputError("a diagonal joint term is zero (rigid); nothing to fit")
    z = 1.0 / diag
    w = h.omega[:, None]
    if method == "lsq":
        k = z.real.mean(axis=0)
        denom = np.sum(w**2, axis=0)
        c = np.sum(w * z.imag, axis=0) / np.where(denom > 0, denom, 1.0)
    else:
        k = np.median(z.real, axis=0)
        pos = w[:, 0] > 0
        c = np.median(z.imag[pos] / w[pos], axis=0) if pos.any() else np.zeros(z.shape[1])
    model = 1.0 / (k[None, :] + 1j * w * c[None, :])
    err = np.linalg.norm(diag - model, axis=0) / np.linalg.norm(diag, axis=0)
    return KCFit(h.outputs, k, c, err, (float(h.freq[0]), float(h.freq[-1])))
