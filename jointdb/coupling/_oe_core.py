"""Output-error joint identification: the coupled-assembly model, its Jacobian and the weighted fit.

The joint is a dynamic stiffness ``Z_J(ω; θ)`` acting between the contact DOFs
``C = a_dofs ∪ b_dofs`` of two substructures A and B. With ``H`` the
substructures' free receptances (block diagonal, no coupling between A and B),

    G_oi(θ) = H_oi − U X V,   X = Z_J (I + H_CC Z_J)⁻¹,

``U = H_oC``, ``V = H_Ci``. Only ``Z_J`` depends on θ; ``U``, ``V``, ``H_CC`` and
``H_oi`` are gathered once. With ``P = U (I + Z_J H_CC)⁻¹`` and
``Q = (I + H_CC Z_J)⁻¹ V`` the derivative is ``∂G/∂θ_p = −P (∂Z_J/∂θ_p) Q``,
batched over frequency lines (one ``solve`` per evaluation).

A spring–damper pair j between ``a_j`` and ``b_j`` contributes
``z_j (e_a − e_b)(e_a − e_b)ᵀ`` with ``z_j = k_j + iω c_j``; a joint body
contributes its full ``K + iD − ω²M`` over ``C``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from jointdb.coupling._common import as_receptance, fetch, same_grid
from jointdb.errors import InputError, NumericalError
from jointdb.frf import FRF, Dof, dofs

__all__ = ["CoupledBlocks", "coupled_blocks", "SpringDamperModel", "JointBodyModel", "OutputErrorResult", "fit"]


@dataclass(frozen=True, eq=False)
class CoupledBlocks:
    """The θ-independent blocks of the coupled model on one grid.

    ``h_oi`` (nf, no, ni), ``u`` (nf, no, nc), ``v`` (nf, nc, ni), ``h_cc`` (nf, nc, nc);
    ``contact`` lists the nc contact DOFs (a_dofs then b_dofs).
    """

    freq: np.ndarray
    h_oi: np.ndarray
    u: np.ndarray
    v: np.ndarray
    h_cc: np.ndarray
    outputs: tuple[Dof, ...]
    inputs: tuple[Dof, ...]
    n_a: int

    def coupled(self, z_j: np.ndarray) -> np.ndarray:
        """``G`` (nf, no, ni) for a joint dynamic stiffness ``z_j`` (nf, nc, nc)."""
        nc = self.h_cc.shape[1]
        q = np.linalg.solve(np.eye(nc) + self.h_cc @ z_j, self.v)
        return self.h_oi - self.u @ (z_j @ q)

    def coupled_and_sensitivity(self, z_j: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``G`` and the factors ``P`` (nf, no, nc), ``Q`` (nf, nc, ni) with ``∂G = −P ∂Z_J Q``."""
        nc = self.h_cc.shape[1]
        eye = np.eye(nc)
        q = np.linalg.solve(eye + self.h_cc @ z_j, self.v)
        pt = np.linalg.solve(np.swapaxes(eye + z_j @ self.h_cc, 1, 2), np.swapaxes(self.u, 1, 2))
        p = np.swapaxes(pt, 1, 2)
        return self.h_oi - self.u @ (z_j @ q), p, q


def coupled_blocks(
    substructures: Mapping[str, FRF],
    a: str,
    a_dofs: Sequence["Dof | str"],
    b: str,
    b_dofs: Sequence["Dof | str"],
    outputs: Sequence[tuple[str, "Dof | str"]],
    inputs: Sequence[tuple[str, "Dof | str"]],
) -> CoupledBlocks:
    """Gather the blocks of :class:`CoupledBlocks` from A's and B's receptances (reciprocity where needed).

    Raises
    ------
    InputError
        Unknown substructure, missing DOF, grids that differ.
    """
    for name in (a, b):
        if name not in substructures:
            raise InputError(f"substructure {name!r} is unknown (have: {', '.join(substructures)})")
    subs = {n: as_receptance(f"substructure {n!r}", substructures[n]) for n in (a, b)}
    freq = same_grid({f"substructure {a!r}": subs[a], f"substructure {b!r}": subs[b]})
    ca, cb = dofs(a_dofs), dofs(b_dofs)
    if len(ca) != len(cb) or not ca:
        raise InputError(f"interface {a}–{b}: {len(ca)} DOFs on {a} but {len(cb)} on {b}; pair them one to one")
    side = {a: ca, b: cb}
    off = {a: 0, b: len(ca)}
    outs = [(str(n), Dof.parse(d)) for n, d in outputs]
    ins = [(str(n), Dof.parse(d)) for n, d in inputs]
    for n, _ in outs + ins:
        if n not in side:
            raise InputError(f"output/input substructure {n!r} must be {a!r} or {b!r}")
    nf, nc, no, ni = freq.size, 2 * len(ca), len(outs), len(ins)
    h_cc = np.zeros((nf, nc, nc), complex)
    u = np.zeros((nf, no, nc), complex)
    v = np.zeros((nf, nc, ni), complex)
    h_oi = np.zeros((nf, no, ni), complex)
    for n in (a, b):
        s, sl = subs[n], slice(off[n], off[n] + len(ca))
        h_cc[:, sl, sl] = fetch(f"substructure {n!r}", s, side[n], side[n])
        ro = [r for r, (m, _) in enumerate(outs) if m == n]
        ci = [c for c, (m, _) in enumerate(ins) if m == n]
        if ro:
            u[:, ro, sl] = fetch(f"substructure {n!r}", s, [outs[r][1] for r in ro], side[n])
        if ci:
            v[:, sl, ci] = fetch(f"substructure {n!r}", s, side[n], [ins[c][1] for c in ci])
        if ro and ci:
            h_oi[:, np.ix_(ro, ci)[0], np.ix_(ro, ci)[1]] = fetch(
                f"substructure {n!r}", s, [outs[r][1] for r in ro], [ins[c][1] for c in ci])
    return CoupledBlocks(freq, h_oi, u, v, h_cc, tuple(d for _, d in outs), tuple(d for _, d in ins), len(ca))


def _legendre(freq: np.ndarray, order: int) -> np.ndarray:
    """Legendre polynomials 0..order on the band mapped to [−1, 1], shape (nf, order+1)."""
    x = 2 * (freq - freq[0]) / max(freq[-1] - freq[0], 1e-300) - 1
    return np.polynomial.legendre.legvander(x, order)


@dataclass(frozen=True, eq=False)
class SpringDamperModel:
    """Independent spring–dampers between ``a_dofs[j]`` and ``b_dofs[j]``.

    Parameters θ (all logarithmic, so every k, c stays positive): per pair j,
    ``log k_j(ω) = Σ_l θ_kjl P_l(x)``, ``log c_j(ω) = Σ_l θ_cjl P_l(x)`` with
    Legendre polynomials ``P_l`` of the band-normalised frequency ``x ∈ [−1, 1]``
    (``order=0``: constant k, c).
    """

    labels: tuple[Dof, ...]
    order: int = 0

    @property
    def names(self) -> list[str]:
        suf = [""] if self.order == 0 else [f"[P{l}]" for l in range(self.order + 1)]
        return [f"{q} {d}{s}" for d in self.labels for q in ("k", "c") for s in suf]

    def n_params(self) -> int:
        return 2 * len(self.labels) * (self.order + 1)

    def start(self, k: np.ndarray, c: np.ndarray) -> np.ndarray:
        th = np.zeros((len(self.labels), 2, self.order + 1))
        th[:, 0, 0] = np.log(np.maximum(k, 1e-300))
        # a damping estimate at or below zero (noise) starts at a loss factor of ~1e-3 at 1 kHz
        th[:, 1, 0] = np.log(np.where(c > 1e-9 * np.abs(k), c, 1.6e-7 * np.abs(k)))
        return th.ravel()

    def kc(self, theta: np.ndarray, freq: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """k(ω), c(ω), each (nf, n_pairs)."""
        th = theta.reshape(len(self.labels), 2, self.order + 1)
        basis = _legendre(freq, self.order)
        return np.exp(basis @ th[:, 0, :].T), np.exp(basis @ th[:, 1, :].T)

    def evaluate(self, theta, blocks: CoupledBlocks, jac: bool):
        freq, n = blocks.freq, len(self.labels)
        k, c = self.kc(theta, freq)
        w = 2 * np.pi * freq[:, None]
        z = k + 1j * w * c  # (nf, n)
        d = np.zeros((2 * n, n))
        d[np.arange(n), np.arange(n)] = 1.0
        d[n + np.arange(n), np.arange(n)] = -1.0
        z_j = np.einsum("cj,fj,dj->fcd", d, z, d)
        if not jac:
            return blocks.coupled(z_j), None
        g, p, q = blocks.coupled_and_sensitivity(z_j)
        pd = p @ d  # (nf, no, n)
        dq = np.einsum("cj,fci->fji", d, q)  # (nf, n, ni)
        base = -pd[:, :, None, :] * dq.transpose(0, 2, 1)[:, None, :, :]  # (nf, no, ni, n): ∂G/∂z_j
        basis = _legendre(freq, self.order)  # (nf, L)
        dz = np.stack([k, 1j * w * c], axis=2)  # (nf, n, 2): ∂z/∂log k, ∂z/∂log c
        dth = base[..., None, None] * dz[:, None, None, :, :, None] * basis[:, None, None, None, None, :]
        return g, dth.reshape(g.shape + (-1,))


def _sym_basis(n: int) -> tuple[np.ndarray, np.ndarray]:
    r, c = np.triu_indices(n)
    return r, c


@dataclass(frozen=True, eq=False)
class JointBodyModel:
    """A joint body with inertia: ``Z_J = K + iD − ω²M`` over the contact DOFs, K, D, M symmetric constants.

    θ holds the upper triangles of K (N/m …), D (hysteretic damping, same units)
    and M (kg, kg·m …), linear (the matrices are not sign-definite entry by entry).
    """

    labels: tuple[Dof, ...]

    @property
    def names(self) -> list[str]:
        r, c = _sym_basis(len(self.labels))
        return [f"{q}[{self.labels[i]},{self.labels[j]}]" for q in ("K", "D", "M") for i, j in zip(r, c)]

    def n_params(self) -> int:
        n = len(self.labels)
        return 3 * n * (n + 1) // 2

    def matrices(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        n = len(self.labels)
        r, c = _sym_basis(n)
        out = []
        for part in np.split(np.asarray(theta, float), 3):
            m = np.zeros((n, n))
            m[r, c] = part
            m[c, r] = part
            out.append(m)
        return tuple(out)

    def start_from_impedance(self, freq: np.ndarray, z: np.ndarray) -> np.ndarray:
        """Least-squares K, D, M from a per-line impedance ``z`` (nf, n, n) (e.g. the inverse of an IRC joint)."""
        w2 = (2 * np.pi * freq) ** 2
        a = np.stack([np.ones_like(w2), -w2], axis=1)
        coef, *_ = np.linalg.lstsq(a, z.real.reshape(freq.size, -1), rcond=None)
        k, m = coef[0].reshape(z.shape[1:]), coef[1].reshape(z.shape[1:])
        dmat = np.mean(z.imag, axis=0)
        r, c = _sym_basis(z.shape[1])
        sym = [(x + x.T) / 2 for x in (k, dmat, m)]
        return np.concatenate([s[r, c] for s in sym])

    def evaluate(self, theta, blocks: CoupledBlocks, jac: bool):
        k, dmat, m = self.matrices(theta)
        w2 = (2 * np.pi * blocks.freq) ** 2
        z_j = (k + 1j * dmat)[None] - w2[:, None, None] * m[None]
        if not jac:
            return blocks.coupled(z_j), None
        g, p, q = blocks.coupled_and_sensitivity(z_j)
        r, c = _sym_basis(len(self.labels))
        t = -(p[:, :, None, r] * np.swapaxes(q, 1, 2)[:, None, :, c]
              + p[:, :, None, c] * np.swapaxes(q, 1, 2)[:, None, :, r])
        t = np.where(r == c, 0.5, 1.0) * t  # diagonal entries were counted twice
        jk = t
        jd = 1j * t
        jm = -w2[:, None, None, None] * t
        return g, np.concatenate([jk, jd, jm], axis=3)


@dataclass(frozen=True, eq=False)
class OutputErrorResult:
    """Joint parameters fitted by output error, with their uncertainty.

    Attributes
    ----------
    model
        The parametrised joint model that was fitted (spring–damper or joint body).
    theta
        The fitted parameters as optimised, ``(n_par,)`` (log-parameters for spring–dampers).
    start_theta
        The starting point of the optimisation, ``(n_par,)``.
    cost_start, cost
        Weighted least-squares cost at the start and at the optimum.
    n_residuals
        Number of real residuals fitted.
    nfev
        Number of model evaluations.
    log_parameters
        True when ``theta`` holds log-parameters.
    fitted
        The assembly receptance the fitted model predicts on the fitted entries,
        ``(n_freq, n_out, n_in)`` [m/N].
    settings
        The fit's settings (model, order, band) as recorded in provenance.
    names
        Parameter names, e.g. ``"k 3x"``, ``"c 3ry"``.
    values
        Parameter values in physical units (k in N/m or N·m/rad, c in N·s/m or N·m·s/rad;
        for a joint body K, D, M entries). For ``order > 0`` spring models, the Legendre
        coefficients of log k, log c.
    std_error
        One standard error per parameter, same units (relative for log-parametrised
        ones multiplied by the value).
    covariance
        Covariance of the fitted parameters θ as optimised (log-parameters for
        spring–dampers, so ``sqrt(diag)`` is a relative standard error).
    correlation
        Correlation matrix of θ.
    residual_rms
        Weighted residual RMS (≈ 1 when the weights are the measurement's standard
        deviation and the model fits).
    """

    model: object
    theta: np.ndarray
    names: list[str]
    values: np.ndarray
    std_error: np.ndarray
    covariance: np.ndarray
    correlation: np.ndarray
    residual_rms: float
    start_theta: np.ndarray
    cost_start: float
    cost: float
    n_residuals: int
    nfev: int
    log_parameters: bool
    fitted: np.ndarray = field(repr=False)
    settings: Mapping[str, object] = field(default_factory=dict)

    def relative_std_error(self) -> np.ndarray:
        """Standard error over |value| per parameter.

        Returns
        -------
        ndarray, shape (n_par,)
        """
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.abs(self.std_error / self.values)

    def table(self) -> list[dict]:
        """One row per parameter: name, value, std_error, relative std error.

        Returns
        -------
        list of dict
            ``parameter``, ``value``, ``std_error``, ``relative_std_error``.
        """
        rel = self.relative_std_error()
        return [{"parameter": n, "value": float(v), "std_error": float(s), "relative_std_error": float(r)}
                for n, v, s, r in zip(self.names, self.values, self.std_error, rel)]

    def max_correlation(self) -> tuple[float, str, str]:
        """The strongest off-diagonal correlation and the two parameters it links.

        Returns
        -------
        (float, str, str)
            |correlation| and the two parameter names.
        """
        c = np.abs(self.correlation - np.eye(len(self.names)))
        if c.size == 0:
            return 0.0, "", ""
        i, j = np.unravel_index(np.argmax(c), c.shape)
        return float(c[i, j]), self.names[i], self.names[j]


def fit(model, blocks: CoupledBlocks, measured: np.ndarray, sigma: np.ndarray, theta0: np.ndarray,
        entries: np.ndarray | None = None, *, max_nfev: int = 200) -> OutputErrorResult:
    """Weighted least squares ``min Σ |G(θ) − G_meas|² / σ²`` over lines and entries, started at ``theta0``.

    Parameters
    ----------
    measured, sigma
        Measured assembly receptance (nf, no, ni) on ``blocks``' outputs/inputs and
        its standard deviation (same shape, > 0; inf or NaN drops an entry).
    entries
        Optional boolean (no, ni) mask of the entries to fit (default: all).

    Raises
    ------
    NumericalError
        If the model cannot be evaluated at the start point.
    """
    from scipy.optimize import least_squares

    sel = np.ones(measured.shape[1:], bool) if entries is None else np.asarray(entries, bool)
    good = np.isfinite(sigma) & (sigma > 0) & np.isfinite(measured) & sel[None]
    wts = np.where(good, 1.0 / np.where(good, sigma, 1.0), 0.0)

    big = None

    def resid(th):
        try:
            with np.errstate(over="ignore", invalid="ignore"):
                g, _ = model.evaluate(th, blocks, jac=False)
        except np.linalg.LinAlgError:  # a trial step made the interface singular: reject the step
            g = None
        r = None if g is None else ((g - measured) * wts)[good]
        if r is None or not np.all(np.isfinite(r)):
            if big is None:
                raise NumericalError("output-error fit: the coupled model is singular at the start point")
            return big
        return np.concatenate([r.real, r.imag])

    def jacobian(th):
        _, j = model.evaluate(th, blocks, jac=True)
        jr = (j * wts[..., None])[good]
        return np.concatenate([jr.real, jr.imag])

    r0 = resid(theta0)
    big = np.full_like(r0, 1e3 * max(np.sqrt(np.mean(r0 ** 2)), 1.0))
    log = isinstance(model, SpringDamperModel)
    sol = least_squares(resid, theta0, jac=jacobian, method="trf", x_scale="jac", max_nfev=max_nfev,
                        xtol=1e-12, ftol=1e-12, gtol=1e-12)
    n_res, p = sol.fun.size, sol.x.size
    s2 = 2 * sol.cost / max(n_res - p, 1)
    _, sv, vt = np.linalg.svd(sol.jac, full_matrices=False)
    keep = sv > sv[0] * 1e-12
    cov = (vt[keep].T / sv[keep] ** 2) @ vt[keep] * s2
    sd = np.sqrt(np.maximum(np.diag(cov), 0))
    with np.errstate(divide="ignore", invalid="ignore"):
        corr = cov / np.outer(sd, sd)
    corr = np.where(np.isfinite(corr), corr, 0.0)
    if log and model.order == 0:
        values = np.exp(sol.x)
        std = values * sd
    else:
        values, std = sol.x.copy(), sd
    g, _ = model.evaluate(sol.x, blocks, jac=False)
    return OutputErrorResult(
        model=model, theta=sol.x, names=model.names, values=values, std_error=std, covariance=cov,
        correlation=corr, residual_rms=float(np.sqrt(s2)), start_theta=np.asarray(theta0, float),
        cost_start=float(0.5 * r0 @ r0), cost=float(sol.cost), n_residuals=int(n_res), nfev=int(sol.nfev),
        log_parameters=log, fitted=g,
    )
