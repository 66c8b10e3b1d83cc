"""Batched linear algebra for identification: regularised pseudo-inverses, smoothing.

All functions take frequency-first stacks ``(n_freq, m, n)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from jointdb.errors import InputError

__all__ = ["Regularisation", "pinv", "condition", "savgol_smooth"]


@dataclass(frozen=True)
class Regularisation:
    """How to invert the (possibly ill-conditioned) model matrices in IRC.

    Parameters
    ----------
    method
        ``"none"`` (Moore–Penrose pseudo-inverse, exact when well posed),
        ``"tsvd"`` (truncated SVD: singular values below ``rel * s_max`` are
        dropped) or ``"tikhonov"`` (filter factors ``s²/(s² + (rel·s_max)²)``).
    rel
        Relative threshold / regularisation parameter, per frequency line.
    """

    method: str = "none"
    rel: float = 0.0

    def __post_init__(self) -> None:
        if self.method not in ("none", "tsvd", "tikhonov"):
            raise InputError(f"regularisation method {self.method!r}: expected none, tsvd or tikhonov")
        if not (np.isfinite(self.rel) and 0.0 <= self.rel < 1.0):
            raise InputError(f"regularisation parameter {self.rel!r} must be in [0, 1)")

    @classmethod
    def parse(cls, value: "Regularisation | str | None | tuple") -> "Regularisation":
        if value is None:
            return cls()
        if isinstance(value, Regularisation):
            return value
        if isinstance(value, str):
            name, _, rel = value.partition(":")
            try:
                rel_value = float(rel) if rel else (0.0 if name.strip().lower() == "none" else 1e-3)
            except ValueError:
                raise InputError(
                    f"regularisation {value!r}: {rel!r} is not a number; use e.g. 'tikhonov:1e-3' or 'tsvd:1e-4'"
                ) from None
            return cls(name.strip().lower(), rel_value)
        if isinstance(value, tuple) and len(value) == 2:
            return cls(str(value[0]), float(value[1]))
        raise InputError(f"cannot read a regularisation from {value!r}; use e.g. 'tikhonov:1e-3' or 'tsvd:1e-4'")


def pinv(a: np.ndarray, reg: Regularisation = Regularisation()) -> np.ndarray:
    """Batched (regularised) pseudo-inverse of ``a`` with shape ``(n_freq, m, n)`` → ``(n_freq, n, m)``."""
    u, s, vh = np.linalg.svd(a, full_matrices=False)
    smax = s[:, :1]
    if reg.method == "tikhonov" and reg.rel > 0:
        mu = reg.rel * smax
        inv_s = s / (s**2 + mu**2)
    else:
        tol = (reg.rel if reg.method == "tsvd" else 0.0) * smax
        tol = np.maximum(tol, np.finfo(float).eps * max(a.shape[1:]) * smax)
        with np.errstate(divide="ignore"):
            inv_s = np.where(s > tol, 1.0 / np.where(s > 0, s, 1.0), 0.0)
    return np.conj(np.swapaxes(vh, 1, 2)) @ (inv_s[:, :, None] * np.conj(np.swapaxes(u, 1, 2)))


def condition(a: np.ndarray) -> np.ndarray:
    """2-norm condition number per line, ``(n_freq,)`` (inf for rank deficiency)."""
    s = np.linalg.svd(a, compute_uv=False)
    with np.errstate(divide="ignore"):
        return np.where(s[:, -1] > 0, s[:, 0] / np.where(s[:, -1] > 0, s[:, -1], 1.0), np.inf)


def savgol_smooth(values: np.ndarray, window: int, order: int = 4) -> np.ndarray:
    """Savitzky–Golay smoothing along frequency of real and imaginary parts (thesis §6.3: 4th order).

    Raises
    ------
    InputError
        If the window is even, not larger than the order, or longer than the data.
    """
    from scipy.signal import savgol_filter

    n = values.shape[0]
    if window % 2 == 0 or window <= order or window > n:
        raise InputError(
            f"Savitzky–Golay window {window} must be odd, > order {order} and <= the {n} frequency lines"
        )
    re = savgol_filter(values.real, window, order, axis=0, mode="interp")
    im = savgol_filter(values.imag, window, order, axis=0, mode="interp")
    return re + 1j * im
