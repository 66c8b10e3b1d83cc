"""Time-domain simulation of regenerative milling on a tool-tip modal model (docs/theory.md §5).

The tool tip is the real state space of a modal model, ``ẏ = A y + B F``, ``q = C y``
(q: tip x/y displacements; the modes of :func:`jointdb.modal.fit_tool_tip`, the same
model semi-discretization uses). Tooth j of N sits at angle ``φ_j(t) = 2πnt/60 + 2πj/N``
from the y axis, x is the feed. The chip of tooth j is cut against the *surface the
previous passes left*: per angular position ``φ`` the workpiece remembers the radial
position ``w(φ)`` of the last tooth that cut there, in the fixed frame, so::

    h_j = (p(t)·n_j + r_j) − w(φ_j),   p(t) = (f_z N n t / 60, 0) + q(t),   n_j = (sin φ_j, cos φ_j)

with r_j the radial runout of tooth j. While ``h_j > 0`` and ``φ_st < φ_j < φ_ex``
the tooth cuts, ``F = −a Σ_j g_j h_j (K_t cos φ_j + K_r sin φ_j, −K_t sin φ_j + K_r cos φ_j)``
(the force law of :mod:`jointdb.stability._cutting`) and the surface becomes
``w(φ_j) = p·n_j + r_j``; when the tool jumps out (``h_j ≤ 0``) it cuts nothing and
the surface stays — the nonlinearity that bounds chatter (Tlusty & Ismail 1981;
Schmitz & Smith, *Machining Dynamics*, 2nd ed., Springer 2019, ch. 4).

Integration: fixed steps ``Δt = τ/m`` (τ the tooth period); between steps the state
advances exactly for a force linear in time (first-order hold: ``Φ0, Φ1, Φ2`` of
Van Loan 1978, as in semi-discretization) with a predictor–corrector for the force
at the end of the step. A batch of (speed, depth) cases runs in one loop.

Chatter is judged on the once-per-period samples of the tip (Schmitz, Medicus,
Dutterer, "Exploring once-per-revolution audio signal variance as a chatter
indicator", Mach. Sci. Tech. 6 (2002) 215–233): a stable cut is periodic in the
tooth period (in the revolution with runout), so the samples settle to one value;
their change from one sample to the next, relative to the vibration, is the
statistic. The period is one tooth period without runout (so period doubling, which
is revolution-periodic for two teeth, is seen) and one revolution with runout.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from jointdb.errors import InputError
from jointdb.modal._model import ModalModel
from jointdb.stability._cutting import MillingCut
from jointdb.stability._sd import sd_system

__all__ = ["SimulationResult", "simulate_milling", "CHATTER_THRESHOLD", "SUSTAINED_GROWTH"]

#: Once-per-period statistic above which a cut may chatter (relative change per period, see module doc).
CHATTER_THRESHOLD = 0.02
#: ... and it chatters only if that change is not dying out: last quarter / second quarter above this.
SUSTAINED_GROWTH = 0.7


@dataclass(frozen=True, eq=False)
class SimulationResult:
    """One simulated cut.

    Attributes
    ----------
    spindle_speed_rpm, depth_m
        The cut.
    chatter
        Verdict: the once-per-period statistic exceeds :data:`CHATTER_THRESHOLD` and is not dying out
        (``growth`` > :data:`SUSTAINED_GROWTH`; a stable cut's change decays geometrically, chatter's
        grows or, once the tool leaves the cut, stays).
    statistic
        RMS change of the once-per-period tip samples over the last quarter divided by the
        RMS of the tip vibration there (dimensionless; → 0 for a stable cut).
    growth
        RMS once-per-period change over the last quarter / over the second quarter
        (> 1: growing, < 1: decaying).
    chatter_freq_hz
        Strongest vibration frequency that is not a tooth-passing harmonic (last half); NaN if none.
    time_s, displacement_m, force_n
        Time samples (n_t,), tip displacement (n_t, 2) and cutting force on the tool (n_t, 2), x/y.
    once_per_period
        Indices into ``time_s`` of the once-per-period samples.
    max_force_n, vibration_pp_m
        Largest resultant force and the peak-to-peak x/y tip vibration (2,) over the last quarter.
    surface_location_error_m
        Mean tip displacement along the wall normal when a tooth passes the surface-generating
        angle (φ = π down-milling, 0 up-milling) over the last quarter; positive = overcut.
        NaN for slotting.
    """

    spindle_speed_rpm: float
    depth_m: float
    chatter: bool
    statistic: float
    growth: float
    chatter_freq_hz: float
    time_s: np.ndarray
    displacement_m: np.ndarray
    force_n: np.ndarray
    once_per_period: np.ndarray
    max_force_n: float
    vibration_pp_m: np.ndarray
    surface_location_error_m: float

    def summary(self) -> dict:
        """Scalars for tables and JSON (SI units).

        Returns
        -------
        dict
            ``spindle_speed_rpm`` [rpm], ``depth_m`` [m], ``chatter`` (bool), ``statistic`` and
            ``growth`` (dimensionless), ``chatter_freq_hz`` [Hz] (NaN if none), ``max_force_n`` [N],
            ``vibration_pp_x_m`` and ``vibration_pp_y_m`` (peak-to-peak tip vibration [m]) and
            ``surface_location_error_m`` [m] (NaN for slotting); the attributes of the same names.
        """
        return {
            "spindle_speed_rpm": self.spindle_speed_rpm, "depth_m": self.depth_m, "chatter": self.chatter,
            "statistic": self.statistic, "growth": self.growth, "chatter_freq_hz": self.chatter_freq_hz,
            "max_force_n": self.max_force_n, "vibration_pp_x_m": float(self.vibration_pp_m[0]),
            "vibration_pp_y_m": float(self.vibration_pp_m[1]),
            "surface_location_error_m": self.surface_location_error_m,
        }


def _hold_matrices(a: np.ndarray, dts: np.ndarray):
    """Φ0 = e^{AΔt}, Φ1 = ∫₀^Δt e^{As} ds, Φ2 = (1/Δt)∫₀^Δt e^{A(Δt−s)} s ds per step (B, n, n) (Van Loan)."""
    n = a.shape[0]
    big = np.zeros((dts.size, 3 * n, 3 * n))
    big[:, :n, :n] = a[None] * dts[:, None, None]
    big[:, :n, n:2 * n] = np.eye(n) * dts[:, None, None]
    big[:, n:2 * n, 2 * n:] = np.eye(n) * dts[:, None, None]
    e = scipy.linalg.expm(big)
    return e[:, :n, :n], e[:, :n, n:2 * n], e[:, :n, 2 * n:] / dts[:, None, None]


def _window_fraction(cut: MillingCut, centres: np.ndarray, width: float) -> np.ndarray:
    """Fraction of ``[φ − w/2, φ + w/2]`` inside the cutting window (exact for the entry and exit)."""
    st, ex = cut.angles
    lo, hi = centres - width / 2, centres + width / 2
    total = np.zeros_like(centres)
    for shift in (-2 * np.pi, 0.0, 2 * np.pi):
        total += np.clip(np.minimum(hi, ex + shift) - np.maximum(lo, st + shift), 0, None)
    return total / width


class _Workpiece:
    """The tool's teeth against the surface memory of a batch of cuts (see module doc)."""

    def __init__(self, cut: MillingCut, m: int, depths: np.ndarray, feed: float, runout: np.ndarray):
        n_teeth = cut.n_teeth
        self.m, self.nbins, self.feed = m, n_teeth * m, feed
        dphi = 2 * np.pi / self.nbins
        phi = np.arange(self.nbins) * dphi
        s, c = np.sin(phi), np.cos(phi)
        self.normal = np.stack([s, c], axis=1)  # (nbins, 2)
        self.vdir = np.stack([cut.kt * c + cut.kr * s, -cut.kt * s + cut.kr * c], axis=1)
        self.gate = _window_fraction(cut, phi, dphi)
        self.depths = depths
        self.runout = runout
        self.offsets = np.arange(n_teeth) * m
        # surface as an ideal tool left it one tooth period before each bin is first reached
        first = np.arange(self.nbins) % m
        w0 = self.normal[:, 0] * feed * (first - m) / m + runout[np.arange(self.nbins) // m]
        self.surface = np.tile(w0, (depths.size, 1))

    def force(self, step: int, q: np.ndarray, commit: bool) -> np.ndarray:
        """Cutting force on the tool (B, 2) at ``step`` for tip displacements ``q`` (B, 2)."""
        bins = (step + self.offsets) % self.nbins
        pos = q.copy()
        pos[:, 0] += self.feed * step / self.m
        proj = pos @ self.normal[bins].T + self.runout[None]  # (B, N)
        chip = proj - self.surface[:, bins]
        gate = self.gate[bins][None]
        cutting = (chip > 0) & (gate > 0)
        load = np.where(cutting, chip, 0.0) * gate  # (B, N)
        if commit:
            self.surface[:, bins] = np.where(cutting, proj, self.surface[:, bins])
        return -self.depths[:, None] * (load @ self.vdir[bins])


def _check(cut, speeds, depths, feed, revolutions, steps_per_tooth, runout):
    if not isinstance(cut, MillingCut):
        raise InputError(f"cut must be a MillingCut, got {type(cut).__name__}")
    speeds = np.atleast_1d(np.asarray(speeds, dtype=float))
    depths = np.atleast_1d(np.asarray(depths, dtype=float))
    if speeds.shape != depths.shape or speeds.ndim != 1:
        raise InputError(f"give one depth per speed: {speeds.shape} speeds, {depths.shape} depths")
    if np.any(~np.isfinite(speeds)) or np.any(speeds <= 0):
        raise InputError("spindle speeds must be finite and > 0 rpm")
    if np.any(~np.isfinite(depths)) or np.any(depths < 0):
        raise InputError("depths of cut must be finite and >= 0 m")
    if not (np.isfinite(feed) and feed > 0):
        raise InputError(f"feed per tooth must be > 0 m, got {feed}")
    if not (revolutions >= 8):
        raise InputError(f"revolutions must be >= 8 (the statistic compares quarters), got {revolutions}")
    if steps_per_tooth is not None and steps_per_tooth < 16:
        raise InputError(f"steps_per_tooth must be >= 16, got {steps_per_tooth}")
    r = np.zeros(cut.n_teeth) if runout is None else np.asarray(runout, dtype=float).ravel()
    if r.shape != (cut.n_teeth,) or np.any(~np.isfinite(r)):
        raise InputError(f"runout needs one finite radial offset [m] per tooth ({cut.n_teeth}), got {runout!r}")
    return speeds, depths, r


def _steps_per_tooth(model_freqs: np.ndarray, tau_max: float, requested: int | None) -> int:
    """Steps per tooth period: ≥ 64 and ≥ 40 per period of the highest mode at the slowest speed."""
    if requested is not None:
        return int(requested)
    need = int(np.ceil(40 * float(np.max(model_freqs)) * tau_max))
    return int(min(max(64, need), 4000))


def simulate_milling(
    model: ModalModel,
    cut: MillingCut,
    spindle_speed_rpm: Sequence[float] | np.ndarray | float,
    depth_m: Sequence[float] | np.ndarray | float,
    *,
    feed_per_tooth_m: float = 1e-4,
    revolutions: int = 200,
    steps_per_tooth: int | None = None,
    runout_m: Sequence[float] | None = None,
) -> list[SimulationResult]:
    """Simulate milling cuts in the time domain; one result per (speed, depth) pair.

    Parameters
    ----------
    model
        Tool-tip :class:`~jointdb.modal.ModalModel` with x and/or y driving points (a missing
        direction is rigid; residual terms have no dynamics and are left out).
    cut
        :class:`MillingCut` (teeth, K_t, K_r [N/m²], a_e/D, up/down).
    spindle_speed_rpm, depth_m
        Speeds [rpm] and axial depths [m], equal shapes ``(B,)`` (scalars for one cut).
    feed_per_tooth_m
        Feed per tooth f_z [m].
    revolutions
        Simulated spindle revolutions (≥ 8); the statistics use the last quarter.
    steps_per_tooth
        Integration steps per tooth period (default: ≥ 64 and ≥ 40 per period of the
        highest mode at the slowest speed).
    runout_m
        Radial runout of each tooth [m], shape ``(N,)`` (default none).

    Returns
    -------
    list of SimulationResult
        One per case, in the order given.

    Raises
    ------
    InputError
        Bad shapes or values, or a model without x/y tip modes.
    """
    speeds, depths, runout = _check(cut, spindle_speed_rpm, depth_m, feed_per_tooth_m, revolutions,
                                    steps_per_tooth, runout_m)
    sys = sd_system(model, cut)
    nq = sys.n
    b2 = np.zeros((nq, 2))
    c2 = np.zeros((2, nq))
    b2[:, list(sys.dirs)] = sys.b
    c2[list(sys.dirs)] = sys.c
    taus = cut.tooth_period(speeds)
    m = _steps_per_tooth(np.abs(np.linalg.eigvals(sys.a)) / (2 * np.pi), float(taus.max()), steps_per_tooth)
    phi0, phi1, phi2 = _hold_matrices(sys.a, taus / m)
    g0 = np.einsum("bij,jk->bik", phi1 - phi2, b2)
    g1 = np.einsum("bij,jk->bik", phi2, b2)
    work = _Workpiece(cut, m, depths, float(feed_per_tooth_m), runout)
    n_steps = int(revolutions) * work.nbins
    y = np.zeros((speeds.size, nq))
    q_hist = np.zeros((n_steps + 1, speeds.size, 2))
    f_hist = np.zeros_like(q_hist)
    f_now = work.force(0, np.zeros((speeds.size, 2)), commit=True)
    f_hist[0] = f_now
    for k in range(n_steps):
        base = np.einsum("bij,bj->bi", phi0, y) + np.einsum("bij,bj->bi", g0, f_now)
        y_pred = base + np.einsum("bij,bj->bi", g1, f_now)  # force held over the step
        f_pred = work.force(k + 1, y_pred @ c2.T, commit=False)
        y = base + np.einsum("bij,bj->bi", g1, f_pred)
        q = y @ c2.T
        f_now = work.force(k + 1, q, commit=True)
        q_hist[k + 1], f_hist[k + 1] = q, f_now
    period = work.nbins if np.any(runout) else m
    return [_assess(speeds[i], depths[i], taus[i] / m, m, period, cut, q_hist[:, i], f_hist[:, i])
            for i in range(speeds.size)]


def _assess(speed, depth, dt, m, period, cut, q, f) -> SimulationResult:
    """Once-per-period statistic, chatter frequency, forces, vibration and SLE of one simulated cut."""
    n = q.shape[0]
    t = np.arange(n) * dt
    idx = np.arange(0, n, period)
    samples = q[idx]
    d = np.linalg.norm(np.diff(samples, axis=0), axis=1)
    nd = d.size
    last = d[3 * nd // 4:]
    second = d[nd // 4: nd // 2]
    tail = q[3 * (n - 1) // 4:]
    spread = float(np.sqrt(np.mean(np.sum((tail - tail.mean(axis=0)) ** 2, axis=1))))
    rms_last = float(np.sqrt(np.mean(last**2)))
    stat = rms_last / spread if spread > 0 else 0.0
    growth = rms_last / float(np.sqrt(np.mean(second**2))) if np.any(second) else 0.0
    chatter = bool(stat > CHATTER_THRESHOLD and growth > SUSTAINED_GROWTH)
    fc = _chatter_frequency(q[n // 2:], dt, cut.n_teeth * speed / 60.0) if chatter else float("nan")
    ftail = f[3 * (n - 1) // 4:]
    sle = float("nan")
    if cut.radial_immersion < 1:  # the wall is generated at φ = π (down-milling) or 0 (up-milling)
        wall = np.pi if cut.down_milling else 0.0
        wall_bin = int(round(wall / (2 * np.pi) * cut.n_teeth * m)) % m
        steps = np.arange(3 * (n - 1) // 4, n)
        at_wall = steps[steps % m == wall_bin]
        normal = np.array([np.sin(wall), np.cos(wall)])
        sle = float(np.mean(q[at_wall] @ normal)) if at_wall.size else sle
    return SimulationResult(
        float(speed), float(depth), chatter, float(stat), float(growth), fc, t, q, f, idx,
        float(np.max(np.linalg.norm(ftail, axis=1))), np.ptp(tail, axis=0), sle)


def _chatter_frequency(q: np.ndarray, dt: float, f_tooth: float) -> float:
    """Strongest spectral peak of ``q`` (n, 2) away from the tooth-passing harmonics [Hz]."""
    q = q - q.mean(axis=0)
    n = q.shape[0]
    win = np.hanning(n)[:, None]
    spec = np.sum(np.abs(np.fft.rfft(q * win, axis=0)) ** 2, axis=1)
    freq = np.fft.rfftfreq(n, dt)
    df = freq[1]
    harmonic = np.abs(freq / f_tooth - np.round(freq / f_tooth)) * f_tooth < 3 * df
    spec = np.where(harmonic | (freq == 0), 0.0, spec)
    k = int(np.argmax(spec))
    if spec[k] <= 0:
        return float("nan")
    if 0 < k < spec.size - 1 and spec[k - 1] > 0 and spec[k + 1] > 0:
        a, b, c = np.log(spec[k - 1: k + 2])
        den = a - 2 * b + c
        if den < 0:
            return float((k + 0.5 * (a - c) / den) * df)
    return float(freq[k])
