"""Milling cutting conditions and the directional (specific force) matrices.

Tool with N equally spaced teeth rotating at Ω; tooth j at angle
``φ_j(t) = 2πΩt/60 + 2π j/N`` measured from the y axis, x the feed direction.
Linear cutting force law ``F_t = K_t a h``, ``F_r = K_r a h`` with chip thickness
``h = f_z sin φ`` plus its dynamic part ``(q(t) − q(t−τ))·(sin φ, cos φ)``.
The dynamic forces on the tool are ``F = −a H(t) (q(t) − q(t−τ))`` with
(Insperger, Mann, Stépán, Bayly, "Stability of up-milling and down-milling,
part 1", Int. J. Mach. Tools Manuf. 43 (2003) 25–34)::

    H(t) = Σ_j g_j(t) [[ s(K_t c + K_r s),  c(K_t c + K_r s)],
                       [ s(−K_t s + K_r c), c(−K_t s + K_r c)]],   s = sin φ_j, c = cos φ_j

``g_j = 1`` while tooth j is in the cut (``φ_st < φ_j mod 2π < φ_ex``). Down-milling:
``φ_st = arccos(2a_e/D − 1)``, ``φ_ex = π``; up-milling: ``φ_st = 0``,
``φ_ex = arccos(1 − 2a_e/D)``. The mean over a tooth period is the zero-order
directional matrix ``H̄ = (N/2π) ∫ H dφ = −(N K_t/4π) [α₀]`` of Altintas & Budak
(CIRP Annals 44/1, 1995).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from jointdb.errors import InputError

__all__ = ["MillingCut", "directional_integral", "mean_directional_matrix", "interval_directional_matrices"]


@dataclass(frozen=True)
class MillingCut:
    """Milling conditions for stability.

    Parameters
    ----------
    n_teeth
        Number of (equally spaced) teeth N, >= 1.
    kt, kr
        Tangential and radial (normal) cutting-force coefficients in N/m²
        (``F_t = kt·a·h``, ``F_r = kr·a·h``).
    radial_immersion
        Radial depth over tool diameter, ``a_e/D`` in (0, 1].
    down_milling
        True for down- (climb) milling, False for up-milling.

    Raises
    ------
    InputError
        On non-positive teeth or coefficients, or immersion outside (0, 1].
    """

    n_teeth: int
    kt: float
    kr: float
    radial_immersion: float = 1.0
    down_milling: bool = True

    def __post_init__(self) -> None:
        for name in ("n_teeth", "kt", "kr", "radial_immersion"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
                raise InputError(f"{name} must be a number, got {value!r}")
            if not np.isfinite(value):
                raise InputError(f"{name} must be finite, got {value}")
        if int(self.n_teeth) != self.n_teeth or self.n_teeth < 1:
            raise InputError(f"n_teeth must be a whole number >= 1, got {self.n_teeth}")
        if not (self.kt > 0) or not np.isfinite(self.kt):
            raise InputError(f"kt must be > 0 N/m², got {self.kt}")
        if not (self.kr >= 0) or not np.isfinite(self.kr):
            raise InputError(f"kr must be >= 0 N/m², got {self.kr}")
        if not (0 < self.radial_immersion <= 1):
            raise InputError(f"radial_immersion (a_e/D) must be in (0, 1], got {self.radial_immersion}")

    @property
    def angles(self) -> tuple[float, float]:
        """Entry and exit angles ``(φ_st, φ_ex)`` in rad."""
        r = self.radial_immersion
        if self.down_milling:
            return float(np.arccos(np.clip(2 * r - 1, -1, 1))), float(np.pi)
        return 0.0, float(np.arccos(np.clip(1 - 2 * r, -1, 1)))

    def tooth_period(self, spindle_speed_rpm) -> np.ndarray:
        """Tooth-passing period ``τ = 60/(N n)`` in s.

        Parameters
        ----------
        spindle_speed_rpm
            Spindle speed(s) n [rpm], scalar or array.

        Returns
        -------
        ndarray
            τ [s], the shape of ``spindle_speed_rpm``.
        """
        return 60.0 / (self.n_teeth * np.asarray(spindle_speed_rpm, dtype=float))


def directional_integral(phi, kt: float, kr: float) -> np.ndarray:
    """Antiderivative ``∫ H(φ) dφ`` of one tooth's matrix, shape ``phi.shape + (2, 2)``."""
    phi = np.asarray(phi, dtype=float)
    sc = np.sin(phi) ** 2 / 2
    ss = phi / 2 - np.sin(2 * phi) / 4
    cc = phi / 2 + np.sin(2 * phi) / 4
    out = np.empty(phi.shape + (2, 2))
    out[..., 0, 0] = kt * sc + kr * ss
    out[..., 0, 1] = kt * cc + kr * sc
    out[..., 1, 0] = -kt * ss + kr * sc
    out[..., 1, 1] = -kt * sc + kr * cc
    return out


def mean_directional_matrix(cut: MillingCut) -> np.ndarray:
    """Tooth-period mean ``H̄ = (N/2π) ∫_{φst}^{φex} H dφ`` (N/m²), shape (2, 2).

    Equals ``−(N K_t/4π)[α₀]`` of Altintas & Budak (1995); for slotting
    ``H̄_xx = N K_r/4`` (docs/theory.md §5).

    Parameters
    ----------
    cut
        :class:`MillingCut` (teeth, K_t, K_r, immersion, up/down).

    Returns
    -------
    ndarray
        ``(2, 2)`` in (x, y), N/m².
    """
    a, b = cut.angles
    return cut.n_teeth / (2 * np.pi) * (directional_integral(b, cut.kt, cut.kr) - directional_integral(a, cut.kt, cut.kr))


def interval_directional_matrices(cut: MillingCut, n_intervals: int) -> np.ndarray:
    """Exact averages of ``H(t)`` over the m equal sub-intervals of one tooth period.

    Returns shape ``(m, 2, 2)`` (N/m²). The tooth angles advance by ``2π/(N m)``
    per interval; the cutting window is intersected exactly.

    Parameters
    ----------
    cut
        :class:`MillingCut`.
    n_intervals
        Number m of intervals per tooth period (>= 1).

    Returns
    -------
    ndarray, shape (m, 2, 2)
        N/m².
    """
    m = int(n_intervals)
    st, ex = cut.angles
    dphi = 2 * np.pi / (cut.n_teeth * m)
    total = np.zeros((m, 2, 2))
    base = np.arange(m) * dphi
    for j in range(cut.n_teeth):
        a = np.mod(base + 2 * np.pi * j / cut.n_teeth, 2 * np.pi)
        b = a + dphi
        for shift in (0.0, 2 * np.pi):
            lo = np.maximum(a, st + shift)
            hi = np.minimum(b, ex + shift)
            ok = hi > lo
            if np.any(ok):
                val = directional_integral(hi[ok], cut.kt, cut.kr) - directional_integral(lo[ok], cut.kt, cut.kr)
                total[ok] += val
    return total / dphi
