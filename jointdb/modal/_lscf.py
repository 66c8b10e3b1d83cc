"""Poly-reference least-squares complex-frequency estimator (pLSCF / "PolyMAX").

Right matrix-fraction model in the z-domain, ``Ω_f = exp(iω_f Δt)`` with
``Δt = 1/(2 f_max)``, for each output row ``o``::

    H_o(ω) = β_o(Ω) α(Ω)⁻¹,   α(Ω) = Σ_{r=0..p} Ω^r α_r  (n_in × n_in),  α_p = I

Linear least squares on ``β_o(Ω) − H_o α(Ω) ≈ 0`` over all lines; the β_o are
eliminated through the reduced normal equations ``M = 2 Σ_o (T_o − S_oᵀ R_o⁻¹ S_o)``
and the α_r follow from ``M`` with the constraint ``α_p = I``. Poles are the
eigenvalues ``z`` of the block companion matrix of α, ``λ = ln(z)/Δt``; the
eigenvectors give the modal participation vectors used for the "vector"
stability check. References: Guillaume, Verboven, Vanlanduit, Van der Auweraer,
Peeters, "A poly-reference implementation of the least-squares complex
frequency-domain estimator", IMAC XXI (2003); Peeters, Van der Auweraer,
Guillaume, Leuridan, "The PolyMAX frequency-domain method: a new standard for
modal parameter estimation?", Shock and Vibration 11 (2004) 395–409.

``R, S, T`` are computed once for the highest order; the matrices of every lower
order are their leading sub-blocks (the basis is ``Ω^0..Ω^p``), so the whole
stabilisation diagram costs one pass over the data.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from jointdb.errors import InputError, NumericalError

__all__ = ["StabilisationCriteria", "StabilisationDiagram", "stabilisation_diagram", "lscf_poles"]


@dataclass(frozen=True)
class StabilisationCriteria:
    """Tolerances for calling a pole stable between consecutive model orders.

    Parameters
    ----------
    freq_tol
        Largest relative frequency change (default 1 %).
    damping_tol
        Largest relative damping change (5 %).
    mac_min
        Smallest participation-vector MAC (0.98; multi-input only).
    max_damping
        Poles with a larger ζ (or ζ ≤ 0) are discarded as non-physical (0.3).
    """

    freq_tol: float = 0.01
    damping_tol: float = 0.05
    mac_min: float = 0.98
    max_damping: float = 0.3


@dataclass(frozen=True, eq=False)
class StabilisationDiagram:
    """All physical poles found at each model order, with their stability status.

    Attributes
    ----------
    order
        Model order of each pole, ``(n_poles,)``.
    freq_hz
        Natural frequency [Hz] of each pole, ``(n_poles,)``.
    zeta
        Damping ratio of each pole, ``(n_poles,)``.
    status
        ``'o'`` new, ``'f'`` frequency stable, ``'d'`` frequency and damping stable,
        ``'s'`` stable in frequency, damping and participation vector; ``(n_poles,)``.
    poles
        The poles [rad/s], complex ``(n_poles,)``.
    participation
        Participation vectors, complex ``(n_poles, n_in)``.
    band
        The fitted band ``(f_min, f_max)`` [Hz].
    """

    order: np.ndarray
    freq_hz: np.ndarray
    zeta: np.ndarray
    status: np.ndarray
    poles: np.ndarray
    participation: np.ndarray
    band: tuple[float, float]

    def stable(self) -> np.ndarray:
        """Boolean mask of the fully stable poles (status ``'s'``).

        Returns
        -------
        ndarray of bool, shape (n_poles,)
        """
        return self.status == "s"


def _mac(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    num = np.abs(np.sum(a.conj() * b, axis=-1)) ** 2
    den = np.sum(np.abs(a) ** 2, axis=-1) * np.sum(np.abs(b) ** 2, axis=-1)
    return num / np.where(den > 0, den, 1.0)


def _normal_matrices(freq, h, p_max, dt):
    """R (p+1,p+1), S (n_o, p+1, (p+1) n_i), T (n_o, (p+1) n_i, (p+1) n_i), real."""
    n_f, n_o, n_i = h.shape
    omega = 2 * np.pi * freq
    x = np.exp(1j * omega[:, None] * dt * np.arange(p_max + 1)[None, :])  # (n_f, p+1)
    # Y_o rows: -kron(x_f, H_o(f)) -> (n_o, n_f, p+1, n_i)
    y = -(x[None, :, :, None] * np.transpose(h, (1, 0, 2))[:, :, None, :])
    y = y.reshape(n_o, n_f, (p_max + 1) * n_i)
    r = np.real(x.conj().T @ x)
    s = np.real(np.einsum("fr,ofk->ork", x.conj(), y))
    t = np.real(np.einsum("ofk,ofl->okl", y.conj(), y))
    return r, s, t


def _poles_for_order(r, s, t, p, n_i, dt):
    k = (p + 1) * n_i
    rr = r[: p + 1, : p + 1]
    ss = s[:, : p + 1, :k]
    tt = t[:, :k, :k]
    m = 2 * np.sum(tt - np.einsum("ork,rq,oql->okl", ss, np.linalg.inv(rr), ss), axis=0)
    m11 = m[: p * n_i, : p * n_i]
    m12 = m[: p * n_i, p * n_i :]
    try:
        alpha = -np.linalg.solve(m11, m12)  # (p n_i, n_i): α_0..α_{p-1} stacked
    except np.linalg.LinAlgError:
        return np.zeros(0, complex), np.zeros((0, n_i), complex)
    comp = np.zeros((p * n_i, p * n_i))
    if p > 1:
        comp[: (p - 1) * n_i, n_i:] = np.eye((p - 1) * n_i)
    comp[(p - 1) * n_i :, :] = -_blocks_row(alpha, p, n_i)
    # left eigenvectors u (uᵀ C = z uᵀ): their last block w satisfies wᵀ α(z) = 0, i.e. the
    # modal participation vector L of the residue ψ Lᵀ (data-determined, unlike the right one)
    z, u = np.linalg.eig(comp.T)
    with np.errstate(divide="ignore", invalid="ignore"):
        lam = np.log(z.astype(complex)) / dt
    part = u[(p - 1) * n_i :, :].T
    return lam, part


def _blocks_row(alpha, p, n_i):
    """Last block row of the companion: [α_0 α_1 ... α_{p-1}] from the stacked α."""
    return np.concatenate([alpha[r * n_i : (r + 1) * n_i, :] for r in range(p)], axis=1)


def lscf_poles(freq, h, order: int, dt: float | None = None):
    """Poles (rad/s, all roots) and participation vectors of one pLSCF model order.

    Parameters
    ----------
    freq
        Frequencies [Hz], ``(n_f,)``.
    h
        FRF values, complex ``(n_f, n_out, n_in)``.
    order
        Polynomial order p.
    dt
        Sampling interval [s] of the z-domain basis (default ``1 / (2 max(freq))``).

    Returns
    -------
    poles : ndarray, complex, shape (p · n_in,)
        All roots [rad/s], physical or not.
    participation : ndarray, complex, shape (p · n_in, n_in)
        Participation vectors.
    """
    h = np.asarray(h, dtype=complex)
    dt = dt if dt is not None else 1.0 / (2 * float(np.max(freq)))
    r, s, t = _normal_matrices(np.asarray(freq, float), h, order, dt)
    return _poles_for_order(r, s, t, order, h.shape[2], dt)


def stabilisation_diagram(
    freq,
    h,
    max_order: int = 30,
    criteria: StabilisationCriteria = StabilisationCriteria(),
    min_order: int = 1,
) -> StabilisationDiagram:
    """pLSCF poles for model orders ``min_order..max_order`` and their stability.

    Parameters
    ----------
    freq
        Frequencies in Hz, shape ``(n_f,)`` (the fitted band).
    h
        FRF values ``(n_f, n_out, n_in)`` (any quantity: poles do not depend on it).
    max_order
        Highest polynomial order p (each order yields up to ``p · n_in`` poles).
    criteria
        :class:`StabilisationCriteria`.
    min_order
        Lowest polynomial order.

    Returns
    -------
    StabilisationDiagram

    Raises
    ------
    InputError
        If there are fewer lines than unknowns of the highest order.
    """
    freq = np.asarray(freq, dtype=float)
    h = np.asarray(h, dtype=complex)
    if h.ndim != 3 or h.shape[0] != freq.size:
        raise InputError(f"FRF values have shape {h.shape}, expected (n_freq, n_out, n_in) with n_freq={freq.size}")
    n_f, n_o, n_i = h.shape
    if max_order < min_order or min_order < 1:
        raise InputError(f"model orders must satisfy 1 <= min_order <= max_order (got {min_order}, {max_order})")
    if n_f * n_o < (max_order + 1) * (1 + n_i):
        raise InputError(
            f"{n_f} frequency lines are too few for model order {max_order}; widen the band or lower --max-order"
        )
    # per-output scaling for conditioning (does not move the poles of exact data)
    scale = np.sqrt(np.mean(np.abs(h) ** 2, axis=(0, 2)))
    if np.any(scale == 0):
        raise InputError("an FRF output row is identically zero")
    hs = h / scale[None, :, None]
    dt = 1.0 / (2 * freq[-1])
    r, s, t = _normal_matrices(freq, hs, max_order, dt)
    out = {k: [] for k in ("order", "freq_hz", "zeta", "status", "poles", "participation")}
    prev = None
    f_lo, f_hi = freq[0], freq[-1]
    for p in range(min_order, max_order + 1):
        lam, part = _poles_for_order(r, s, t, p, n_i, dt)
        keep = np.isfinite(lam) & (lam.imag > 0)
        lam, part = lam[keep], part[keep]
        fn = np.abs(lam) / (2 * np.pi)
        zeta = -lam.real / np.abs(lam)
        phys = (zeta > 0) & (zeta < criteria.max_damping) & (fn >= f_lo) & (fn <= f_hi)
        lam, part, fn, zeta = lam[phys], part[phys], fn[phys], zeta[phys]
        norm = np.linalg.norm(part, axis=1, keepdims=True)
        part = part / np.where(norm > 0, norm, 1.0)
        status = np.full(lam.size, "o", dtype="<U1")
        if prev is not None and prev[0].size and lam.size:
            pf, pz, pp = prev
            j = np.argmin(np.abs(fn[:, None] - pf[None, :]), axis=1)
            df = np.abs(fn - pf[j]) / fn
            dz = np.abs(zeta - pz[j]) / zeta
            mac = _mac(part, pp[j]) if n_i > 1 else np.ones(lam.size)
            fs = df < criteria.freq_tol
            ds = fs & (dz < criteria.damping_tol)
            vs = ds & (mac > criteria.mac_min)
            status[fs] = "f"
            status[ds] = "d"
            status[vs] = "s"
        prev = (fn, zeta, part)
        out["order"].append(np.full(lam.size, p))
        out["freq_hz"].append(fn)
        out["zeta"].append(zeta)
        out["status"].append(status)
        out["poles"].append(lam)
        out["participation"].append(part)
    cat = {k: np.concatenate(v) if v else np.zeros(0) for k, v in out.items()}
    if cat["participation"].size == 0:
        cat["participation"] = np.zeros((0, n_i), complex)
    return StabilisationDiagram(
        order=cat["order"].astype(int),
        freq_hz=cat["freq_hz"],
        zeta=cat["zeta"],
        status=cat["status"].astype("<U1"),
        poles=cat["poles"].astype(complex),
        participation=cat["participation"],
        band=(float(f_lo), float(f_hi)),
    )


def select_poles(diagram: StabilisationDiagram, n_modes: int | None = None, freq_tol: float = 0.01, min_count: int = 3):
    """Automatic pole selection: cluster the stable poles by frequency, keep the best clusters.

    Stable poles (status ``'s'``) are grouped when within ``freq_tol`` (relative)
    of the running cluster mean; clusters are ranked by how many model orders
    they appear in. With ``n_modes`` the ``n_modes`` best clusters are taken,
    otherwise every cluster seen in at least ``min_count`` orders. Each cluster
    is represented by its pole of median frequency.

    Parameters
    ----------
    diagram
        A :class:`StabilisationDiagram`.
    n_modes
        How many clusters to keep (None: every cluster seen in ``min_count`` orders).
    freq_tol
        Relative frequency tolerance of a cluster.
    min_count
        Orders a cluster must appear in when ``n_modes`` is None.

    Returns
    -------
    ndarray, complex
        The selected poles [rad/s], sorted by frequency.

    Raises
    ------
    NumericalError
        If fewer stable clusters exist than ``n_modes``.
    """
    mask = diagram.stable()
    f = diagram.freq_hz[mask]
    lam = diagram.poles[mask]
    order = diagram.order[mask]
    idx = np.argsort(f)
    f, lam, order = f[idx], lam[idx], order[idx]
    clusters: list[list[int]] = []
    for k in range(f.size):
        if clusters and abs(f[k] - np.mean(f[clusters[-1]])) <= freq_tol * f[k]:
            clusters[-1].append(k)
        else:
            clusters.append([k])
    counts = np.array([len(set(order[c])) for c in clusters])
    if n_modes is not None:
        if len(clusters) < n_modes:
            raise NumericalError(
                f"only {len(clusters)} stable pole(s) found in {diagram.band[0]:g}–{diagram.band[1]:g} Hz, "
                f"{n_modes} requested; raise --max-order, widen the band or ask for fewer modes"
            )
        best = np.argsort(-counts, kind="stable")[:n_modes]
    else:
        best = np.flatnonzero(counts >= min_count)
        if best.size == 0:
            raise NumericalError("no pole is stable over enough model orders; raise --max-order or give --modes")
    chosen = []
    for c in best:
        members = np.array(clusters[c])
        mid = members[np.argsort(f[members])[members.size // 2]]
        chosen.append(lam[mid])
    chosen = np.array(chosen)
    return chosen[np.argsort(np.abs(chosen))]
