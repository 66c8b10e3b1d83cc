"""Milling stability by first-order semi-discretization (Insperger & Stépán).

Tool-tip dynamics from a modal model as a real state space ``ẏ = A y + B F``,
``q = C y`` (q: tool-tip x/y displacements; ``ModalModel.state_space``), and the
regenerative cutting force ``F = −a H(t) (q(t) − q(t−τ))`` (``_cutting``)::

    ẏ(t) = (A − a B H(t) C) y(t) + a B H(t) C y(t − τ)

The tooth period τ is split into m intervals Δt = τ/m; on interval i, H(t) is
replaced by its exact mean H_i and the delayed term by the linear interpolation
of q_{i−m} and q_{i−m+1} (first-order SD: Insperger & Stépán, "Updated
semi-discretization method for periodic delay-differential equations with
discrete delay", Int. J. Numer. Meth. Eng. 61 (2004) 117–141; zero-order
original: Insperger & Stépán, Proc. R. Soc. A 458 (2002) / Int. J. Numer.
Meth. Eng. 55 (2002) 503–518). Then::

    y_{i+1} = Φ0_i y_i + (Φ1_i − Φ2_i) a B H_i q_{i−m} + Φ2_i a B H_i q_{i−m+1}

with ``Φ0 = e^{A_i Δt}``, ``Φ1 = ∫₀^Δt e^{A_i s} ds``, ``Φ2 = (1/Δt)∫₀^Δt e^{A_i(Δt−s)} s ds``
from one block matrix exponential (Van Loan 1978). The discrete state
``z_i = (y_i, q_{i−1}, …, q_{i−m})`` (dimension n + m·n_q) maps over one
period by the Floquet transition (monodromy) matrix; the cut is stable when
its spectral radius ρ < 1.

The critical depth at a spindle speed is found directly: a geometric bracket
from below the absolute floor, then Brent's method on ``log ρ(a) = 0``
(~12–20 monodromy evaluations instead of a dense depth grid). The critical
multiplier classifies the boundary: a complex pair → secondary Hopf, −1 →
flip (period doubling). The chatter frequency comes from the critical
eigenvector's history samples (dominant harmonic of the periodic part).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence

import numpy as np
import scipy.linalg
import scipy.optimize

from jointdb.errors import InputError, NumericalError
from jointdb.modal._model import ModalModel
from jointdb.stability._cutting import MillingCut, interval_directional_matrices, mean_directional_matrix
from jointdb.stability._results import LobeResult, spindle_speeds

log = logging.getLogger(__name__)

__all__ = ["SDSystem", "sd_system", "monodromy", "spectral_radius", "critical_depth", "milling_lobes_sd", "milling_lobes_sd_grid"]


class SDSystem:
    """Tool-tip state space restricted to the x/y DOFs of a modal model, and the cut."""

    def __init__(self, a: np.ndarray, b: np.ndarray, c: np.ndarray, dirs: tuple[int, ...], cut: MillingCut):
        self.a, self.b, self.c = a, b, c
        self.dirs = dirs  # indices into (x, y) of the modelled directions
        self.cut = cut
        self.n = a.shape[0]
        self.nq = c.shape[0]

    def directional(self, n_intervals: int) -> np.ndarray:
        """Interval means H_i restricted to the modelled directions, (m, n_q, n_q)."""
        h = interval_directional_matrices(self.cut, n_intervals)
        return h[:, self.dirs][:, :, self.dirs]


def sd_system(model: ModalModel, cut: MillingCut) -> SDSystem:
    """Build the SD system from a tool-tip modal model (x and/or y driving DOFs).

    The model's outputs/inputs must include DOFs with direction ``x`` and/or ``y``
    (same node); residual terms are ignored (no dynamics).

    Parameters
    ----------
    model
        Tool-tip :class:`~jointdb.modal.ModalModel` (receptance residues, m/N·rad/s).
    cut
        :class:`MillingCut`.

    Returns
    -------
    SDSystem
        Real state space ``(A, B, C)`` of the x/y driving-point block and the cut.

    Raises
    ------
    InputError
        If ``model``/``cut`` have the wrong type, or the model has no x or y DOF
        that is both output and input, or no mode with a non-zero residue there.
    """
    if not isinstance(model, ModalModel):
        raise InputError(
            f"semi-discretization needs a ModalModel (fit one with jointdb.modal.fit_modes), got {type(model).__name__}"
        )
    if not isinstance(cut, MillingCut):
        raise InputError(f"cut must be a MillingCut, got {type(cut).__name__}")
    dirs, labels = [], []
    for k, name in enumerate(("x", "y")):
        for d in model.outputs:
            if d.direction == name and d in model.inputs:
                dirs.append(k)
                labels.append(d)
                break
    if not dirs:
        raise InputError(
            "the modal model has no x or y driving-point DOF; semi-discretization needs the tool-tip x/y modes"
        )
    sub = model.select(labels, labels)
    a, b, c = sub.state_space()
    if a.shape[0] == 0:
        raise InputError("the modal model has no modes with non-zero residues at the tool tip")
    return SDSystem(a, b, c, tuple(dirs), cut)


def _exp_integrals(ai: np.ndarray, dt: float):
    """Φ0 = e^{AΔt}, Φ1 = ∫₀^Δt e^{As} ds, Φ2 = (1/Δt)∫₀^Δt e^{A(Δt−s)} s ds for a batch (m, n, n).

    Batched eigendecomposition ``A = V Λ V⁻¹`` (the scalar functions applied to Λ);
    intervals whose eigenvectors are ill-conditioned fall back to the block matrix
    exponential of Van Loan (1978): ``expm([[A, I, 0], [0, 0, I], [0, 0, 0]]·Δt)``.
    """
    m, n, _ = ai.shape
    lam, v = np.linalg.eig(ai)
    x = lam * dt
    ex = np.exp(x)
    # f1 = (eˣ − 1)/x and f2 = (eˣ − 1 − x)/x² lose ε/|x| and ε/|x|² to cancellation: below |x| = 0.1 their
    # Taylor series Σ xᵏ/(k+1)! and Σ xᵏ/(k+2)! are used instead (12 terms: truncation < 1e-20)
    small = np.abs(x) < 0.1
    xs = np.where(small, 1.0, x)
    s1, s2 = np.zeros_like(x), np.zeros_like(x)
    for k in range(11, -1, -1):  # Horner
        s1 = s1 * x + 1.0 / math.factorial(k + 1)
        s2 = s2 * x + 1.0 / math.factorial(k + 2)
    f1 = np.where(small, s1, (ex - 1) / xs) * dt
    f2 = np.where(small, s2, (ex - 1 - x) / xs**2) * dt
    vinv = np.linalg.inv(v)
    # V diag(f(λ)) V⁻¹ for the three functions at once: one batched matrix product
    scaled = v[None] * np.stack([ex, f1, f2])[:, :, None, :]      # (3, m, n, n)
    phi0, phi1, phi2 = np.real(scaled @ vinv[None])
    # ill-conditioned eigenvectors (near-defective A): the 1-norm condition number from V and V⁻¹ already at
    # hand, without an SVD per interval; it is at least κ₂/n, so the threshold 1e8/n keeps every κ₂ > 1e8 out
    bad = np.abs(v).sum(axis=-2).max(axis=-1) * np.abs(vinv).sum(axis=-2).max(axis=-1) > 1e8 / n
    if np.any(bad):
        big = np.zeros((int(bad.sum()), 3 * n, 3 * n))
        big[:, :n, :n] = ai[bad] * dt
        big[:, :n, n : 2 * n] = np.eye(n) * dt
        big[:, n : 2 * n, 2 * n :] = np.eye(n) * dt
        e = scipy.linalg.expm(big)
        phi0[bad], phi1[bad], phi2[bad] = e[:, :n, :n], e[:, :n, n : 2 * n], e[:, :n, 2 * n :] / dt
    return phi0, phi1, phi2


def _step_matrices(sys: SDSystem, depth: float, h: np.ndarray, dt: float):
    """Φ0 (m,n,n) and the delayed-term gains P = (Φ1−Φ2)aBH_i, Q = Φ2 aBH_i (m,n,n_q)."""
    bh = depth * np.einsum("ij,mjk->mik", sys.b, h)  # (m, n, nq)
    ai = sys.a[None] - np.einsum("mik,kj->mij", bh, sys.c)
    phi0, phi1, phi2 = _exp_integrals(ai, dt)
    p = np.einsum("mij,mjk->mik", phi1 - phi2, bh)
    q = np.einsum("mij,mjk->mik", phi2, bh)
    return phi0, p, q


def monodromy(sys: SDSystem, spindle_speed_rpm: float, depth: float, n_intervals: int = 40) -> np.ndarray:
    """Floquet transition matrix over one tooth period (Insperger & Stépán 2004; docs/theory.md §5).

    Parameters
    ----------
    sys
        From :func:`sd_system`.
    spindle_speed_rpm
        Spindle speed [rpm]; the delay is the tooth period ``τ = 60/(N n)`` [s].
    depth
        Axial depth of cut a [m].
    n_intervals
        Intervals m per tooth period (first-order semi-discretization).

    Returns
    -------
    ndarray
        Shape ``(n + m·n_q, n + m·n_q)``, state ordering ``(y_i, q_{i−1}, …, q_{i−m})``
        (n states of the modal model, n_q measured directions).

    Raises
    ------
    InputError
        If ``n_intervals < 2``.
    """
    m = int(n_intervals)
    if m < 2:
        raise InputError(f"n_intervals must be >= 2, got {n_intervals}")
    tau = float(sys.cut.tooth_period(spindle_speed_rpm))
    dt = tau / m
    h = sys.directional(m)
    phi0, p, q = _step_matrices(sys, depth, h, dt)
    n, nq = sys.n, sys.nq
    dim = n + m * nq
    y = np.zeros((n, dim))
    y[:, :n] = np.eye(n)
    # the delayed outputs as a ring: q_{i-1-k} is in slot (head + k) mod m (no copy of the history per step)
    ring = np.zeros((m, nq, dim))
    for k in range(m):
        ring[k, :, n + k * nq : n + (k + 1) * nq] = np.eye(nq)
    head = 0
    for i in range(m):
        y_new = phi0[i] @ y + p[i] @ ring[(head + m - 1) % m] + q[i] @ ring[(head + m - 2) % m]
        head = (head - 1) % m
        ring[head] = sys.c @ y
        y = y_new
    hist = ring[(head + np.arange(m)) % m]  # hist[k] = q_{i-1-k}
    return np.concatenate([y, hist.reshape(m * nq, dim)], axis=0)


def spectral_radius(sys: SDSystem, spindle_speed_rpm: float, depth: float, n_intervals: int = 40) -> float:
    """Largest |Floquet multiplier| of :func:`monodromy`; the cut is stable when < 1.

    Parameters
    ----------
    sys
        From :func:`sd_system`.
    spindle_speed_rpm
        Spindle speed [rpm].
    depth
        Axial depth of cut a [m].
    n_intervals
        Intervals m per tooth period.

    Returns
    -------
    float
        Spectral radius ρ (dimensionless).

    Raises
    ------
    InputError
        If ``n_intervals < 2``.
    """
    return float(np.max(np.abs(np.linalg.eigvals(monodromy(sys, spindle_speed_rpm, depth, n_intervals)))))


def _classify(sys: SDSystem, speed: float, depth: float, m: int):
    mono = monodromy(sys, speed, depth, m)
    w, v = np.linalg.eig(mono)
    k = int(np.argmax(np.abs(w)))
    mu = w[k]
    theta = float(np.angle(mu))
    if abs(abs(theta) - np.pi) < 1e-3 * np.pi:
        kind = "flip"
        theta = np.pi
    elif abs(theta) < 1e-3 * np.pi:
        kind = "fold"
    else:
        kind = "hopf"
    # history samples q(0), q(−Δt), …, q(−(m−1)Δt); remove the Floquet factor μ^{t/τ}
    n, nq = sys.n, sys.nq
    vec = v[:, k]
    samples = np.concatenate([(sys.c @ vec[:n])[None], vec[n:].reshape(m, nq)[: m - 1]], axis=0)  # (m, nq)
    kk = np.arange(m)
    logmu = np.log(abs(mu)) + 1j * theta
    p = samples * np.exp(kk * logmu / m)[:, None]  # p(t_k), t_k = −kΔt
    harmonics = np.arange(-(m // 2), m - m // 2)
    basis = np.exp(1j * 2 * np.pi * np.outer(harmonics, kk) / m)  # e^{-i2πn t_k/τ}
    power = np.sum(np.abs(basis @ p) ** 2, axis=1)
    nbest = harmonics[int(np.argmax(power))]
    tau = float(sys.cut.tooth_period(speed))
    fc = abs(theta + 2 * np.pi * nbest) / (2 * np.pi * tau)
    return kind, fc, int(np.floor(fc * tau + 1e-9))


def _floor_estimate(sys: SDSystem) -> float:
    """ZOA-like absolute floor from the state space on a fine frequency grid (scale only)."""
    w_modes = np.abs(np.linalg.eigvals(sys.a))
    w = np.linspace(0.5 * w_modes.min(), 1.5 * w_modes.max(), 4000)
    phi = sys.c[None] @ np.linalg.solve(1j * w[:, None, None] * np.eye(sys.n)[None] - sys.a[None], np.broadcast_to(sys.b, (w.size,) + sys.b.shape))
    hbar = mean_directional_matrix(sys.cut)[np.ix_(sys.dirs, sys.dirs)]
    ev = np.linalg.eigvals(hbar[None] @ phi)
    neg = ev.real[ev.real < 0]
    if neg.size == 0:
        # mean force matrix does not destabilise on average (e.g. tiny immersion): use |ev|
        return float(1.0 / (2 * np.max(np.abs(ev))))
    return float(-1.0 / (2 * neg.min()))


def critical_depth(
    sys: SDSystem,
    spindle_speed_rpm: float,
    n_intervals: int = 40,
    *,
    start: float | None = None,
    rtol: float = 1e-4,
    growth: float = 1.5,
    depth_max: float | None = None,
) -> tuple[float, float, str, int, int]:
    """Smallest depth a with ρ(a) = 1 at one spindle speed, by bracketing and Brent's method.

    Returns ``(depth_m, chatter_freq_hz, kind, lobe, n_evaluations)``; depth ``inf``
    (kind ``""``) when still stable at ``depth_max`` (default 1000× the start).
    A narrow unstable island between two bracket steps (factor ``growth``) can
    be missed; lower ``growth`` to be safer.

    Parameters
    ----------
    sys, spindle_speed_rpm, n_intervals
        As for :func:`spectral_radius`: the system from :func:`sd_system`, the spindle speed [rpm]
        and the intervals per tooth period.
    start
        First trial depth [m] (default: half the ZOA-like floor of the model).
    rtol
        Relative tolerance of the depth.
    growth
        Bracketing factor (> 1).
    depth_max
        Search ceiling [m].

    Returns
    -------
    tuple
        ``(depth_m, chatter_freq_hz, kind, lobe, n_evaluations)``; depth ``inf`` and kind
        ``""`` when still stable at ``depth_max``.

    Raises
    ------
    NumericalError
        If the system is unstable even at vanishing depth (unstable tool-tip model).
    """
    a0 = start if start is not None else 0.5 * _floor_estimate(sys)
    top = depth_max if depth_max is not None else 1000 * a0
    calls = 0

    def g(a):
        nonlocal calls
        calls += 1
        return np.log(spectral_radius(sys, spindle_speed_rpm, a, n_intervals))

    lo = a0
    glo = g(lo)
    halvings = 0
    while glo >= 0:
        lo *= 0.5
        glo = g(lo)
        halvings += 1
        if halvings > 30:
            raise NumericalError(
                f"unstable even at depth {lo:.3g} m at {spindle_speed_rpm:g} rpm: the tool-tip model itself is unstable?"
            )
    hi = lo * growth
    ghi = g(hi)
    while ghi < 0:
        lo, glo = hi, ghi
        hi *= growth
        if hi > top:
            return float("inf"), float("nan"), "", -1, calls
        ghi = g(hi)
    root = scipy.optimize.brentq(g, lo, hi, rtol=rtol, xtol=1e-12)
    # classify just on the unstable side of the boundary
    kind, fc, lobe = _classify(sys, spindle_speed_rpm, root * (1 + 10 * rtol), n_intervals)
    return float(root), fc, kind, lobe, calls


def milling_lobes_sd(
    model: ModalModel,
    cut: MillingCut,
    spindle_speed_rpm: Sequence[float] | np.ndarray,
    *,
    n_intervals: int = 40,
    rtol: float = 1e-4,
    depth_max: float | None = None,
) -> LobeResult:
    """Milling stability lobes by first-order semi-discretization on a modal model.

    Parameters
    ----------
    model
        Tool-tip modal model with x and/or y driving-point DOFs (e.g.
        ``ModalModel.block_diagonal([fit_x.model, fit_y.model])``); a missing
        direction is rigid.
    cut
        :class:`MillingCut`.
    spindle_speed_rpm
        Spindle speeds [rpm].
    n_intervals
        Intervals m per tooth period (accuracy; 40 is usual).
    rtol
        Relative tolerance of the critical depth.
    depth_max
        Largest depth [m] searched per speed (default 1000× the starting depth); a speed
        still stable there has no limit (kind ``""``).

    Returns
    -------
    LobeResult
        ``method="milling-sd"``; per speed the critical depth, chatter frequency,
        lobe number and kind (``"hopf"``/``"flip"``); ``info["evaluations"]`` is
        the number of monodromy matrices computed.

    Raises
    ------
    InputError
        ``model`` not a :class:`~jointdb.modal.ModalModel` or without x/y driving
        DOFs, bad speeds (non-finite, <= 0 rpm), ``n_intervals < 2``.
    NumericalError
        If the model is unstable without cutting.

    Examples
    --------
    Slotting with four teeth on one mode per direction (k = 2·10⁷ N/m, ζ = 0.03, 800 Hz). In
    slotting the zero-order approximation is accurate, and the semi-discretization agrees with
    it to within 1 % at each speed:

    >>> import numpy as np
    >>> from jointdb.modal import ModalModel
    >>> from jointdb.stability import MillingCut, milling_lobes_sd, milling_lobes_zoa
    >>> model = ModalModel.block_diagonal([ModalModel.from_modal_parameters([800.0], [0.03], [2e7], dof)
    ...                                    for dof in ("1x", "1y")])
    >>> cut = MillingCut(n_teeth=4, kt=6e8, kr=1.8e8, radial_immersion=1.0)      # N/m²
    >>> speeds = np.array([5000.0, 5600.0, 6200.0, 6800.0])                      # rpm
    >>> sd = milling_lobes_sd(model, cut, speeds)
    >>> sd.kind.tolist()
    ['hopf', 'hopf', 'hopf', 'hopf']
    >>> zoa = milling_lobes_zoa(model.synthesize(np.linspace(700.0, 900.0, 2001)), cut, spindle_speed_rpm=speeds)
    >>> bool(np.all(np.abs(sd.depth_m / zoa.depth_m - 1) < 0.01))
    True
    """
    sys = sd_system(model, cut)
    speeds = spindle_speeds(spindle_speed_rpm)
    start = 0.5 * _floor_estimate(sys)
    rows = [critical_depth(sys, s, n_intervals, start=start, rtol=rtol, depth_max=depth_max) for s in speeds]
    depth, fc, kind, lobe, calls = (list(col) for col in zip(*rows))
    log.debug("SD lobes: %d speeds, %d monodromy matrices (m = %d)", speeds.size, sum(calls), n_intervals)
    return LobeResult(
        "milling-sd",
        speeds,
        depth,
        fc,
        lobe,
        kind,
        (),
        {"n_teeth": cut.n_teeth, "kt": cut.kt, "kr": cut.kr, "radial_immersion": cut.radial_immersion,
         "down_milling": cut.down_milling, "n_intervals": n_intervals, "evaluations": int(sum(calls))},
    )


def milling_lobes_sd_grid(
    model: ModalModel,
    cut: MillingCut,
    spindle_speed_rpm: Sequence[float] | np.ndarray,
    depths_m: Sequence[float] | np.ndarray,
    *,
    n_intervals: int = 40,
) -> LobeResult:
    """Reference: SD spectral radius on a dense (speed × depth) grid; per speed the first unstable depth.

    The classical way of drawing SD lobes (contour of ρ = 1); used to measure the
    cost of :func:`milling_lobes_sd` against it. Depth resolution is the grid's.

    Parameters
    ----------
    model, cut, spindle_speed_rpm, n_intervals
        As in :func:`milling_lobes_sd`.
    depths_m
        Depth grid [m].

    Returns
    -------
    LobeResult
        ``method="milling-sd-grid"``; per speed the first grid depth with ρ >= 1
        (``inf`` if none), chatter frequency NaN.

    Raises
    ------
    InputError
        As :func:`milling_lobes_sd`.
    """
    sys = sd_system(model, cut)
    speeds = spindle_speeds(spindle_speed_rpm)
    depths = np.sort(np.asarray(depths_m, dtype=float))
    out = np.full(speeds.size, np.inf)
    for i, s in enumerate(speeds):
        rho = np.array([spectral_radius(sys, s, a, n_intervals) for a in depths])
        bad = np.flatnonzero(rho >= 1)
        if bad.size:
            out[i] = depths[bad[0]]
    nan = np.full(speeds.size, np.nan)
    return LobeResult("milling-sd-grid", speeds, out, nan, np.full(speeds.size, -1), np.full(speeds.size, ""), (),
                      {"n_intervals": n_intervals, "evaluations": int(speeds.size * depths.size)})
