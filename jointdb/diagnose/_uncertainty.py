"""Uncertainty of a fitted candidate's parameters.

Statistical: the linearised ``cov = χ²_red τ (JᵀJ)⁻¹`` (:func:`linearised_sigmas`), with
``χ²_red = RSS/(n − p)`` (a residual larger than the noise inflates it) and τ the integrated
autocorrelation time of the residual along frequency (:func:`correlation_inflation`; only n/τ lines
are independent); a parameter the residual does not feel at all gets :data:`FLAT_SIGMA`.
Model form: a delete-one-block jackknife over frequency (:func:`jackknife_spread`).
"""

from __future__ import annotations

import copy
import numpy as np
import scipy.optimize

from jointdb.errors import NumericalError

__all__ = ["FLAT_SIGMA", "JACKKNIFE_BLOCKS", "correlation_inflation", "linearised_sigmas", "jackknife_spread"]

#: σ (in the fit's coordinates: log space for logarithmic parameters) given to a parameter with a flat
#: profile (the residual does not change with it): far beyond any identification threshold.
FLAT_SIGMA = 1e3

#: Contiguous frequency blocks for the delete-one-block jackknife (model-form spread).
JACKKNIFE_BLOCKS = 5


def correlation_inflation(r: np.ndarray, ev) -> float:
    """Variance inflation τ = n / n_eff for residuals correlated along frequency.

    τ = 1 + 2 Σ_k ρ_k is the integrated autocorrelation time of the residual
    along the fit lines (per FRF, real and imaginary parts), summed until ρ_k
    falls below 0.05 (at most 50 lags). Model-form error makes neighbouring
    residuals alike, so only about n/τ of the n residuals are independent; the
    textbook covariance (independent residuals) is too optimistic by τ.
    """
    shape = (2,) + ev.rec.shape
    x = r.reshape(shape)
    x = np.moveaxis(x, 2, -1).reshape(-1, shape[2])        # series along frequency
    den = float((x * x).sum())
    if den <= 0 or x.shape[1] < 3:
        return 1.0
    tau = 1.0
    for k in range(1, min(50, x.shape[1] - 1)):
        rho = float((x[:, :-k] * x[:, k:]).sum()) / den
        if rho < 0.05:
            break
        tau += 2 * rho
    return float(min(tau, max(ev.n / 4.0, 1.0)))


def linearised_sigmas(params, res, rss: float, ev):
    """Statistical σ of a least-squares fit: ``χ²_red τ (JᵀJ)⁻¹`` at the optimum.

    Parameters
    ----------
    params
        The candidate's :class:`Param` s, in the fit's order.
    res
        The ``scipy.optimize.least_squares`` result (its ``x``, ``jac`` and ``fun``).
    rss
        Weighted residual sum of squares at the optimum.
    ev
        The :class:`ModelEvaluator` of the fit.

    Returns
    -------
    sigmas : dict
        Parameter name → σ, SI (``FLAT_SIGMA`` × value, in log space, where the profile is flat).
    cov : ndarray (p, p) or None
        Covariance of the fitted coordinates (log space for logarithmic parameters).
    tau : float
        The residual's correlation inflation (:func:`correlation_inflation`).
    """
    p = len(params)
    J = res.jac
    dof = max(ev.n - p, 1)
    inflate = correlation_inflation(res.fun, ev)
    try:
        cov = np.linalg.pinv(J.T @ J) * (rss / dof) * inflate
        su = np.sqrt(np.clip(np.diag(cov), 0, None))
    except np.linalg.LinAlgError:  # pragma: no cover
        cov, su = None, np.full(p, np.nan)
    # a parameter the residual does not feel at all (a flat profile: e.g. a stiffness far beyond what the
    # recordings resolve) gets no σ from the pseudo-inverse; give it one that says "not resolved"
    col = np.linalg.norm(J, axis=0)
    su = np.where(col > 1e-9 * max(float(col.max(initial=0.0)), 1e-300), su, FLAT_SIGMA)
    sigmas = {}
    for q, x, s in zip(params, res.x, su):
        v = q.from_u(x)
        sigmas[q.name] = float(abs(v) * s) if q.log else float(q.scale * s)
    return sigmas, cov, inflate


def jackknife_spread(ev, nominal, fit, blocks: int = JACKKNIFE_BLOCKS) -> dict:
    """Model-form spread of a fit's parameters: delete-one-block jackknife over frequency.

    The fit lines are cut into ``blocks`` contiguous groups (in practice: the
    background and each resonance); the candidate is refitted with each group
    left out, starting from the full fit. If the candidate's physics is only an
    approximation, different parts of the spectrum ask for different values and
    the refits scatter. Returns ``{name: σ_jk}`` (SI) with
    ``σ_jk² = (B−1)/B Σ_b (θ_b − θ̄)²`` (in the fit's log space where the
    parameter is logarithmic). Costs ``blocks`` short refits.

    Parameters
    ----------
    ev
        The :class:`ModelEvaluator` of the fit.
    nominal
        The nominal :class:`jointdb.fe.BeamModel`.
    fit
        The :class:`Fit` to assess.
    blocks
        Number of contiguous frequency blocks B.

    Returns
    -------
    dict
        Parameter name → σ_jk, SI (empty when there are too few lines or no parameters).
    """
    cand = fit.candidate
    params = cand.params
    if not params or ev.freq.size < 2 * blocks:
        return {}
    lo = np.array([q.u_bounds[0] for q in params])
    hi = np.array([q.u_bounds[1] for q in params])
    u_hat = np.clip([q.to_u(fit.values[q.name]) for q in params], lo + 1e-9, hi - 1e-9)
    edges = np.linspace(0, ev.freq.size, blocks + 1).astype(int)
    us = []
    for a, b in zip(edges[:-1], edges[1:]):
        sub = copy.copy(ev)
        w = np.array(ev.w, copy=True)
        w[:, a:b] = 0.0
        sub.w = w
        sub.n = int(2 * np.count_nonzero(w))

        def fun(u, sub=sub):
            try:
                return sub.residual(sub.predict_u(nominal, cand, u))
            except (NumericalError, np.linalg.LinAlgError):
                return np.full(sub.n if sub.n else 1, 1e3)

        res = scipy.optimize.least_squares(fun, u_hat, bounds=(lo, hi), method="trf", diff_step=1e-4,
                                           max_nfev=min(8 * (len(params) + 1), 24), xtol=1e-6, ftol=1e-6)
        us.append(res.x)
    us = np.asarray(us)
    var = (blocks - 1) / blocks * ((us - us.mean(axis=0)) ** 2).sum(axis=0)
    out = {}
    for q, x, v in zip(params, u_hat, var):
        s = float(np.sqrt(v))
        out[q.name] = float(abs(q.from_u(x)) * s) if q.log else float(q.scale * s)
    return out
