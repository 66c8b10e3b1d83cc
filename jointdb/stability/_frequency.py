"""Frequency-domain stability: turning (Tlusty) and milling zero-order approximation.

Both work straight from a measured or predicted FRF (docs/theory.md §5).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from jointdb.errors import InputError
from jointdb.frf import FRF, Dof
from jointdb.stability._cutting import MillingCut, mean_directional_matrix
from jointdb.stability._results import LobeResult, check_max_lobes, envelope, lobes_from_transfer, spindle_speeds

__all__ = ["oriented_frf", "tlusty_limit", "turning_lobes", "milling_lobes_zoa", "tool_tip_matrix"]


def _receptance(frf: FRF) -> FRF:
    if frf.freq[0] == 0:
        frf = frf.replace(freq=frf.freq[1:], values=frf.values[1:])
    return frf.to("receptance")


def oriented_frf(frf: FRF, orientation: Sequence[float] | np.ndarray | None = None) -> np.ndarray:
    """Oriented receptance ``G_o(ω) = Σ_ij μ_ij H_ij(ω)`` (docs/theory.md §5), shape ``(n_freq,)``.

    Parameters
    ----------
    frf
        Tool-tip FRF (any quantity; converted to receptance, a 0 Hz line dropped).
    orientation
        Directional factors: a 1-D sequence ``μ_k`` applied to the driving-point
        entries of the square FRF (``μ_k = cos β_k cos(β_k − θ)`` for a mode
        direction at β_k to the force, θ the cut normal), or a full
        ``(n_out, n_in)`` matrix of factors. Default: 1 on the diagonal.

    Returns
    -------
    ndarray, complex, shape (n_freq,)
        G_o [m/N] on the FRF's lines above 0 Hz.

    Raises
    ------
    InputError
        If the orientation does not match the FRF's shape, or if it weights a
        rotational DOF (a rad/(N·m) term cannot be added to m/N receptances).
    """
    h = _receptance(frf).values
    n_o, n_i = h.shape[1:]
    if orientation is None:
        orientation = np.ones(min(n_o, n_i))
    mu = np.asarray(orientation, dtype=float)
    if mu.ndim == 1:
        if n_o != n_i or mu.size != n_o:
            raise InputError(
                f"orientation has {mu.size} factors; the FRF has {n_o}×{n_i} entries "
                "(give one factor per driving point of a square FRF, or a full matrix)"
            )
        mu = np.diag(mu)
    if mu.shape != (n_o, n_i):
        raise InputError(f"orientation matrix has shape {mu.shape}, the FRF is {n_o}×{n_i}")
    rot_out = np.array([d.is_rotation for d in frf.outputs])
    rot_in = np.array([d.is_rotation for d in frf.inputs])
    weighted = mu != 0
    if np.any(weighted & (rot_out[:, None] | rot_in[None, :])):
        rotational = [str(d) for d in (*frf.outputs, *frf.inputs) if d.is_rotation]
        raise InputError(
            "the oriented FRF would add rotational terms (" + ", ".join(dict.fromkeys(rotational))
            + ") to translational receptances; select the translational DOFs first, "
            "e.g. frf.select(['1x', '1y'], ['1x', '1y'])"
        )
    return np.einsum("fij,ij->f", h, mu)


def _refine_min(f, y):
    """Minimum of sampled y(f) with parabolic refinement around the lowest line."""
    k = int(np.argmin(y))
    if 0 < k < y.size - 1:
        f0, f1, f2 = f[k - 1 : k + 2]
        y0, y1, y2 = y[k - 1 : k + 2]
        den = (f0 - f1) * (f0 - f2) * (f1 - f2)
        a = (f2 * (y1 - y0) + f1 * (y0 - y2) + f0 * (y2 - y1)) / den
        b = (f2**2 * (y0 - y1) + f1**2 * (y2 - y0) + f0**2 * (y1 - y2)) / den
        if a > 0:
            fv = -b / (2 * a)
            c = y1 - a * f1**2 - b * f1
            return float(fv), float(a * fv**2 + b * fv + c)
    return float(f[k]), float(y[k])


def tlusty_limit(frf: FRF, kf: float, orientation=None) -> tuple[float, float]:
    """Absolute (speed-independent) turning limit ``b_lim = −1/(2 K_f min Re G_o)``.

    Returns ``(depth_m, chatter_freq_hz)``; the minimum of ``Re G_o`` is refined by
    a parabola through the three lowest lines. For one mode this is
    ``2kζ(1+ζ)/K_f`` at ``f_n√(1+2ζ)`` (docs/theory.md §5).

    Parameters
    ----------
    frf
        Tool-tip FRF (any quantity; converted to receptance, m/N).
    kf
        Cutting-force coefficient K_f [N/m²].
    orientation
        Directional factors (see :func:`oriented_frf`).

    Returns
    -------
    depth_m : float
        The limit [m].
    chatter_freq_hz : float
        Where ``Re G_o`` is lowest [Hz].

    Raises
    ------
    InputError
        If ``kf <= 0`` or ``Re G_o`` is never negative.
    """
    if not kf > 0:
        raise InputError(f"kf must be > 0 N/m², got {kf}")
    rec = _receptance(frf)
    g = oriented_frf(rec, orientation)
    if not np.any(g.real < 0):
        raise InputError("the oriented FRF has no negative real part: no chatter limit exists in this band")
    fc, gmin = _refine_min(rec.freq, g.real)
    return -1.0 / (2 * kf * gmin), fc


def _default_speeds(lobes, n_teeth, n=400):
    f_lo = min(float(lb.chatter_freq_hz.min()) for lb in lobes)
    f_hi = max(float(lb.chatter_freq_hz.max()) for lb in lobes)
    k_max = max(lb.number for lb in lobes)
    lo = 60 * f_lo / (n_teeth * (k_max + 1))
    hi = 60 * f_hi / n_teeth * 1.2
    return np.linspace(lo, hi, n)


def turning_lobes(
    frf: FRF,
    kf: float,
    orientation=None,
    spindle_speed_rpm: Sequence[float] | np.ndarray | None = None,
    max_lobes: int = 30,
) -> LobeResult:
    """Turning stability lobes (Tlusty): depth of cut [m] against spindle speed [rpm].

    ``1 + K_f b (1 − e^{−iωT}) G_o(iω) = 0`` with T one spindle revolution; on lines
    with ``Re G_o < 0``: ``b = −1/(2 K_f Re G_o)``, ``n = 60/T`` for each lobe k.

    Parameters
    ----------
    frf
        Tool-tip FRF (receptance, mobility or accelerance).
    kf
        Cutting-force coefficient K_f [N/m²] (force per unit chip area).
    orientation
        Directional factors (see :func:`oriented_frf`).
    spindle_speed_rpm
        Speeds for the envelope; default: 400 speeds over the lobes' range.
    max_lobes
        Number of lobes k = 0..max_lobes−1.

    Returns
    -------
    LobeResult
        ``method="turning"``; depth [m], chatter frequency [Hz], lobe number per speed.

    Raises
    ------
    InputError
        ``kf <= 0``, ``Re G_o`` never negative, bad speeds or ``max_lobes`` < 1.

    Examples
    --------
    A single mode (k = 2·10⁷ N/m, ζ = 0.03, 800 Hz): the lowest point of the lobes is the
    absolute limit ``2 k ζ (1 + ζ) / K_f``:

    >>> import numpy as np
    >>> from jointdb import FRF
    >>> from jointdb.stability import turning_lobes
    >>> k, zeta, fn = 2e7, 0.03, 800.0                              # N/m, -, Hz
    >>> m = k / (2 * np.pi * fn) ** 2
    >>> freq = np.linspace(700.0, 900.0, 2001)
    >>> w = 2 * np.pi * freq
    >>> tip = FRF(freq, 1 / (k - m * w**2 + 2j * zeta * np.sqrt(k * m) * w), ["1x"], ["1x"])
    >>> result = turning_lobes(tip, kf=1e9, spindle_speed_rpm=np.linspace(1000, 5000, 200))
    >>> result.depth_m.shape                                        # one limit per speed, m
    (200,)
    >>> round(result.min_depth_m * 1e3, 3), round(2 * k * zeta * (1 + zeta) / 1e9 * 1e3, 3)   # mm
    (1.236, 1.236)
    """
    max_lobes = check_max_lobes(max_lobes)
    lim, fc = tlusty_limit(frf, kf, orientation)
    rec = _receptance(frf)
    g = kf * oriented_frf(rec, orientation)
    lobes = lobes_from_transfer(rec.freq, g, 1, max_lobes)
    speeds = _default_speeds(lobes, 1) if spindle_speed_rpm is None else spindle_speeds(spindle_speed_rpm)
    return _hopf_envelope("turning", lobes, speeds, {
        "kf": kf, "orientation": None if orientation is None else np.asarray(orientation).tolist(),
        "absolute_limit_m": lim, "absolute_limit_freq_hz": fc})


def _hopf_envelope(method: str, lobes, speeds: np.ndarray, info: dict) -> LobeResult:
    """The envelope of frequency-domain ``lobes`` at ``speeds`` (every limit a Hopf one) as a result."""
    depth, freq, num = envelope(lobes, speeds)
    kind = np.where(np.isfinite(depth), "hopf", "")
    return LobeResult(method, speeds, depth, freq, num, kind, lobes, info)


def tool_tip_matrix(frf: FRF, frf_y: FRF | None = None, cross_terms: bool = False) -> tuple[np.ndarray, np.ndarray, tuple[bool, bool]]:
    """Tool-tip receptance matrix Φ (n_freq, 2, 2) in (x, y) from FRF container(s).

    A missing direction is rigid (zero).

    Parameters
    ----------
    frf
        The x driving point (and optionally y and cross terms) as DOFs with directions
        ``x``/``y`` at one node; any quantity (converted to receptance).
    frf_y
        The y driving point given separately (resampled onto ``frf``'s grid when needed).
    cross_terms
        Use the cross terms Φ_xy, Φ_yx when present (otherwise they are zero).

    Returns
    -------
    freq_hz : ndarray, shape (n_freq,)
        Frequency lines [Hz].
    phi : ndarray, shape (n_freq, 2, 2)
        Receptance [m/N] in (x, y).
    present : tuple of bool
        ``(has_x, has_y)``.

    Raises
    ------
    InputError
        If neither an x nor a y driving point is present.
    """
    rec = _receptance(frf)
    phi = np.zeros((rec.n_freq, 2, 2), dtype=complex)

    def driving(f: FRF, direction: str) -> Dof | None:
        for d in f.outputs:
            if d.direction == direction and d in f.inputs:
                return d
        return None

    dx, dy = driving(rec, "x"), driving(rec, "y")
    if dx is not None:
        phi[:, 0, 0] = rec.entry(dx, dx)
    if dy is not None:
        phi[:, 1, 1] = rec.entry(dy, dy)
    if cross_terms and dx is not None and dy is not None:
        phi[:, 0, 1] = rec.entry(dx, dy)
        phi[:, 1, 0] = rec.entry(dy, dx)
    if frf_y is not None:
        ry = _receptance(frf_y)
        d = driving(ry, "y") or driving(ry, "x")
        if d is None:
            raise InputError("the y-direction FRF has no driving-point entry (same output and input DOF)")
        if not np.array_equal(ry.freq, rec.freq):
            ry = ry.resample(rec.freq[(rec.freq >= ry.freq[0]) & (rec.freq <= ry.freq[-1])])
            keep = (rec.freq >= ry.freq[0]) & (rec.freq <= ry.freq[-1])
            rec_freq = rec.freq[keep]
            phi = phi[keep]
        else:
            rec_freq = rec.freq
        phi[:, 1, 1] = ry.entry(d, d)
        dy = d
    else:
        rec_freq = rec.freq
    if dx is None and dy is None:
        raise InputError(
            f"no x or y driving-point FRF found (outputs {' '.join(map(str, rec.outputs))}, "
            f"inputs {' '.join(map(str, rec.inputs))}); the tool-tip FRF needs e.g. 1x/1x"
        )
    return rec_freq, phi, (dx is not None, dy is not None)


def _track_branches(ev: np.ndarray) -> np.ndarray:
    """Order the two eigenvalues of each line so that each column varies continuously."""
    if ev.shape[0] < 2:
        return ev
    same = np.abs(ev[1:, 0] - ev[:-1, 0]) + np.abs(ev[1:, 1] - ev[:-1, 1])
    swap = np.abs(ev[1:, 0] - ev[:-1, 1]) + np.abs(ev[1:, 1] - ev[:-1, 0])
    parity = np.concatenate([[0], np.cumsum(swap < same) % 2]).astype(bool)
    out = ev.copy()
    out[parity] = ev[parity][:, ::-1]
    return out


def milling_lobes_zoa(
    frf: FRF,
    cut: MillingCut,
    frf_y: FRF | None = None,
    *,
    cross_terms: bool = False,
    spindle_speed_rpm: Sequence[float] | np.ndarray | None = None,
    max_lobes: int = 30,
) -> LobeResult:
    """Milling stability lobes by the zero-order approximation (Altintas & Budak 1995).

    Characteristic equation ``det[I + a (1 − e^{−iωτ}) H̄ Φ(iω)] = 0`` with the
    tooth-period mean directional matrix ``H̄ = −(N K_t/4π)[α₀]``; for each
    eigenvalue ``g`` of ``H̄ Φ`` with ``Re g < 0``: ``a_lim = −1/(2 Re g)`` (equal
    to Altintas's ``−2πΛ_R(1+κ²)/(N K_t)``) and ``ωτ = ε + 2kπ``, ``n = 60/(Nτ)``.

    Parameters
    ----------
    frf, frf_y
        Tool-tip FRF(s), see :func:`tool_tip_matrix`.
    cut
        :class:`MillingCut` (teeth, K_t, K_r in N/m², a_e/D, up/down).
    cross_terms
        Use measured cross FRFs Φ_xy, Φ_yx when present.
    spindle_speed_rpm
        Envelope speeds (default: 400 over the lobes' range).
    max_lobes
        Lobes k = 0..max_lobes−1.

    Returns
    -------
    LobeResult
        ``method="milling-zoa"``, kind ``"hopf"`` (ZOA cannot see flip lobes).

    Raises
    ------
    InputError
        No x/y driving point, no negative real eigenvalue part in the band, bad
        speeds (non-finite or <= 0 rpm) or ``max_lobes`` < 1.

    Examples
    --------
    Slotting with four teeth on a tool tip with the same single mode in x and y. For this
    symmetric case the eigenvalues of ``H̄ Φ`` are ``(N K_t / 4)(K_r/K_t ∓ i) G(ω)``, so the
    lowest limit is ``−2 / (N K_t min(K_r/K_t Re G + Im G))``; doubling K_t halves it:

    >>> import numpy as np
    >>> from jointdb import FRF
    >>> from jointdb.stability import MillingCut, milling_lobes_zoa
    >>> k, zeta, fn = 2e7, 0.03, 800.0                              # N/m, -, Hz
    >>> m = k / (2 * np.pi * fn) ** 2
    >>> freq = np.linspace(700.0, 900.0, 2001)
    >>> w = 2 * np.pi * freq
    >>> g = 1 / (k - m * w**2 + 2j * zeta * np.sqrt(k * m) * w)
    >>> tip = FRF(freq, np.einsum("f,ij->fij", g, np.eye(2)), ["1x", "1y"], ["1x", "1y"])
    >>> speeds = np.linspace(2000, 12000, 300)                      # rpm
    >>> cut = MillingCut(n_teeth=4, kt=6e8, kr=1.8e8, radial_immersion=1.0)   # N/m²
    >>> result = milling_lobes_zoa(tip, cut, spindle_speed_rpm=speeds)
    >>> closed_form = float(-2 / (4 * 6e8 * np.min(0.3 * g.real + g.imag)))
    >>> round(result.min_depth_m * 1e3, 3), round(closed_form * 1e3, 3)          # mm
    (0.983, 0.983)
    >>> harder = milling_lobes_zoa(tip, MillingCut(4, kt=1.2e9, kr=3.6e8), spindle_speed_rpm=speeds)
    >>> round(harder.min_depth_m / result.min_depth_m, 6)
    0.5
    """
    if not isinstance(cut, MillingCut):
        raise InputError(f"cut must be a MillingCut, got {type(cut).__name__}")
    max_lobes = check_max_lobes(max_lobes)
    freq, phi, _ = tool_tip_matrix(frf, frf_y, cross_terms)
    hbar = mean_directional_matrix(cut)
    ev = _track_branches(np.linalg.eigvals(hbar[None] @ phi))  # (n_f, 2)
    lobes = []
    for fam in range(2):
        lobes.extend(lobes_from_transfer(freq, ev[:, fam], cut.n_teeth, max_lobes, family=fam))
    if not lobes:
        raise InputError("no eigenvalue of the oriented FRF has a negative real part: no chatter limit in this band")
    speeds = (
        _default_speeds(lobes, cut.n_teeth) if spindle_speed_rpm is None else spindle_speeds(spindle_speed_rpm)
    )
    return _hopf_envelope("milling-zoa", tuple(lobes), speeds, {
        "n_teeth": cut.n_teeth, "kt": cut.kt, "kr": cut.kr, "radial_immersion": cut.radial_immersion,
        "down_milling": cut.down_milling, "cross_terms": cross_terms, "mean_directional_matrix": hbar.tolist()})
