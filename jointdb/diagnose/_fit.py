"""Fitting candidate physics to recordings and scoring them (BIC).

Residual (per recorded line, output, input and level): the complex log ratio
``log(H_model / H_recorded)`` — its real part is the log-magnitude error, its
imaginary part the phase error in radians — weighted by ``1/σ`` with σ from
the coherence and a 2 % model floor (``_data.MODEL_FLOOR``). Real and
imaginary parts are stacked, so ``n`` (the number of residuals) is twice the
number of usable complex entries.

Selection criterion: the Bayesian information criterion of the weighted
residual, ``BIC = n ln(RSS/n) + p ln n`` (Schwarz 1978), p = number of fitted
parameters. Fits use ``scipy.optimize.least_squares`` (trust-region
reflective, bounded, parameters in log space where physical) from the
candidate's start and its extra starts. Uncertainty: the linearised
``cov = χ²_red τ (JᵀJ)⁻¹`` with ``χ²_red = RSS/(n − p)`` (absorbs a residual
larger than the noise) and τ the integrated autocorrelation time of the
residual along frequency (n/τ independent lines); for the selected
explanation, a delete-one-block jackknife over frequency adds the model-form
spread (:func:`jointdb.diagnose._uncertainty.jackknife_spread`), and the reported σ is the root sum of
squares of the two.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass, field

import numpy as np
import scipy.optimize

from jointdb.diagnose._uncertainty import linearised_sigmas
from jointdb.errors import InputError, NumericalError
from jointdb.fe import frf_direct, frf_modal, natural_frequencies

__all__ = ["Fit", "ModelEvaluator", "fit_candidate", "MEMO_SIZE", "MEMO_BYTES"]

#: Predictions an evaluator remembers by their fit coordinates (:meth:`ModelEvaluator.predict_u`), at most this many
#: and at most MEMO_BYTES of arrays (a server runs several diagnoses at once; 3 levels × 4,000 lines × 3 × 3 entries
#: are 0.9 MB a prediction).
MEMO_SIZE = 64
MEMO_BYTES = 32 * 2**20


class ModelEvaluator:
    """Model FRFs at the observation's lines and DOFs, with residuals.

    Parameters
    ----------
    obs
        The :class:`Observation`.
    full
        Evaluate on all recorded lines in the band (``obs.full_*``) instead of the fit lines.
    method
        ``"modal"`` (truncated modal superposition, fast) or ``"direct"``.
    n_modes
        Modes kept by the modal method.
    """

    def __init__(self, obs, full: bool = False, method: str = "modal", n_modes: int = 12):
        self.obs = obs
        self.full = full
        self.method = method
        self.n_modes = n_modes
        self.freq = obs.full_freq if full else obs.freq
        self.rec = obs.full_values if full else obs.values
        self.w = obs.full_weight if full else obs.weight
        self.points = obs.model_points
        used = set(obs.out_dirs) | set(obs.in_dirs)
        self.dirs = [d for d in ("x", "y", "z", "rx", "ry", "rz") if d in used]
        labels = [(p, d) for p in self.points for d in self.dirs]
        self.oi = [labels.index((p, d)) for p, d in zip(obs.out_points, obs.out_dirs)]
        self.ii = [labels.index((p, d)) for p, d in zip(obs.in_points, obs.in_dirs)]
        self.n = int(2 * np.count_nonzero(self.w))
        # predictions by fit coordinates (they do not depend on the weights: shared with copies of this
        # evaluator that weight other lines, e.g. the jackknife's)
        self._memo: OrderedDict = OrderedDict()
        self._memo_bytes = [0]  # a list: shared, like the memo, with shallow copies of this evaluator

    def frf(self, model) -> np.ndarray:
        """Receptance ``(n_freq, n_out, n_in)`` of ``model`` at the recorded DOFs.

        Parameters
        ----------
        model
            A :class:`jointdb.fe.BeamModel` with the observation's points.

        Returns
        -------
        ndarray, complex
        """
        idx = self._point_dofs(model)
        mats = model.assemble()
        if self.method == "modal":
            n = min(self.n_modes, max(1, model.mesh().n_dof - 4))
            H = frf_modal(mats, self.freq, idx, n_modes=n)
        else:
            H = frf_direct(mats, self.freq, idx)
        if not np.all(np.isfinite(H)):      # what model.frf's FRF would refuse
            raise InputError(f"FRF values contain {int(np.count_nonzero(~np.isfinite(H)))} NaN or inf entries")
        return H[:, self.oi][:, :, self.ii]

    def _point_dofs(self, model) -> list[int]:
        """Global DOFs of the evaluator's points × directions in ``model``'s mesh (what ``model.frf`` would
        use), remembered for the last mesh numbering and point positions (a fit's models share them)."""
        mesh = model.mesh()
        where = tuple(model.point(name).position for name in self.points)
        last = getattr(self, "_dofs_of", None)
        if last is not None and last[0] is mesh.dof_table and last[1] is mesh.node_positions and last[2] == where:
            return last[3]
        idx = [mesh.dof(mesh.node_at(z, f"point {name!r}"), d) for name, z in zip(self.points, where)
               for d in self.dirs]
        self._dofs_of = (mesh.dof_table, mesh.node_positions, where, idx)
        return idx

    def dof_indices(self, model) -> tuple[list[int], list[int]]:
        """Global DOF indices in ``model``'s mesh of the recorded outputs and inputs.

        Parameters
        ----------
        model
            A :class:`jointdb.fe.BeamModel` with the observation's points.

        Returns
        -------
        outputs, inputs : list of int
        """
        mesh = model.mesh()

        def dof(point, direction):
            return mesh.dof(mesh.node_at(model.point(point).position, f"point {point!r}"), direction)

        obs = self.obs
        return ([dof(p, d) for p, d in zip(obs.out_points, obs.out_dirs)],
                [dof(p, d) for p, d in zip(obs.in_points, obs.in_dirs)])

    def predict(self, nominal, cand=None, values=None) -> np.ndarray:
        """Predictions of the nominal model, with a candidate's physics when given.

        Parameters
        ----------
        nominal
            The nominal :class:`jointdb.fe.BeamModel`.
        cand
            A :class:`Candidate`, or None.
        values
            The candidate's parameter values, SI.

        Returns
        -------
        ndarray, complex, shape (n_level, n_freq, n_out, n_in)
        """
        n_lv = self.rec.shape[0]
        if cand is None:
            return np.broadcast_to(self.frf(nominal), self.rec.shape)
        out = []
        base = None
        if not _changes_model(cand):
            key = id(nominal)
            if getattr(self, "_cache_key", None) != key:
                self._cache = self.frf(nominal)
                self._cache_key = key
            base = self._cache
        line_by_line = getattr(cand, "receptance_at_level", None)
        for lv in range(n_lv):
            H_lv = line_by_line(self, nominal, values, lv) if line_by_line is not None else None
            if H_lv is not None:
                base = H_lv
            elif cand.per_level or base is None:
                base = self.frf(cand.apply(nominal, values, lv))
            H = base
            factor = cand.chain(self.freq, values, lv)
            if factor is not None:
                H = H * factor[:, None, None]
            out.append(H)
        return np.stack(out)

    def predict_u(self, nominal, cand, u: np.ndarray) -> np.ndarray:
        """:meth:`predict` at the fit coordinates ``u`` of ``cand``'s parameters, remembered.

        A least-squares fit asks for the same point more than once (its start after a first look at
        it, its optimum once more for the mismatch; every block of a jackknife starts at the same
        optimum with the same finite-difference Jacobian): the last :data:`MEMO_SIZE` predictions are
        kept, keyed by the exact bytes of ``u``, so a repeated point costs nothing and gives the
        identical array.

        Parameters
        ----------
        nominal, cand
            As for :meth:`predict`.
        u
            The candidate's fit coordinates, ``(p,)``.

        Returns
        -------
        ndarray, complex, shape (n_level, n_freq, n_out, n_in), read-only
        """
        u = np.asarray(u, dtype=float)
        key = (id(nominal), id(cand), u.tobytes())
        hit = self._memo.get(key)
        if hit is not None and hit[0] is nominal and hit[1] is cand:
            self._memo.move_to_end(key)
            return hit[2]
        H = self.predict(nominal, cand, _values_of(cand.params, u))
        H.flags.writeable = False
        self._memo[key] = (nominal, cand, H)      # the objects are kept: their ids are not reused
        self._memo_bytes[0] += H.nbytes
        while len(self._memo) > 1 and (len(self._memo) > MEMO_SIZE or self._memo_bytes[0] > MEMO_BYTES):
            self._memo_bytes[0] -= self._memo.popitem(last=False)[1][2].nbytes
        return H

    def log_ratio(self, H: np.ndarray) -> np.ndarray:
        """``log(H / H_rec)``, 0 where the weight is 0 or the ratio is not finite.

        Parameters
        ----------
        H
            Model receptance, ``(n_level, n_freq, n_out, n_in)``.

        Returns
        -------
        ndarray, complex, same shape
            Real part: the log amplitude ratio; imaginary part: the phase difference [rad].
        """
        with np.errstate(divide="ignore", invalid="ignore"):
            lr = np.log(H / self.rec)
        if not np.isfinite(lr).all():          # (the usual case, all finite, needs no copy)
            lr = np.nan_to_num(lr, nan=0.0, posinf=0.0, neginf=0.0)
        return np.where(self.w > 0, lr, 0.0)

    def residual(self, H: np.ndarray) -> np.ndarray:
        """The weighted residual ``w log(H / H_rec)``, real and imaginary parts stacked.

        Parameters
        ----------
        H
            As :meth:`log_ratio`.

        Returns
        -------
        ndarray, shape (2 · H.size,)
        """
        r = self.w * self.log_ratio(H)
        return np.concatenate([r.real.ravel(), r.imag.ravel()])

    def mismatch(self, H: np.ndarray, per_level: bool = False):
        """Weighted RMS of ``|log(H_model/H_rec)|`` (≈ relative FRF error; 0.05 = 5 %).

        Parameters
        ----------
        H
            Model receptance, ``(n_level, n_freq, n_out, n_in)``.
        per_level
            One value per level instead of one overall.

        Returns
        -------
        float or ndarray of shape (n_level,)
        """
        lr = np.abs(self.log_ratio(H)) ** 2
        w2 = self.w**2
        if per_level:
            return np.sqrt((w2 * lr).sum(axis=(1, 2, 3)) / w2.sum(axis=(1, 2, 3)))
        return float(np.sqrt((w2 * lr).sum() / w2.sum()))


@dataclass
class Fit:
    """A fitted candidate (or the nominal model when ``candidate is None``).

    Attributes
    ----------
    candidate
        The :class:`Candidate`, or None for the nominal model.
    values, sigmas
        Fitted value and standard deviation per parameter, SI.
    rss
        Weighted residual sum of squares.
    n, p
        Number of real residuals and of parameters.
    bic
        ``n ln(RSS/n) + p ln n``.
    mismatch
        Weighted RMS ``|log(H_model/H_rec)|`` on the fit lines.
    mismatch_levels
        The same per excitation level.
    nfev
        Model evaluations used.
    at_bound
        Parameters that ended at a bound of the fit.
    chi2_red
        ``RSS / (n − p)`` (> 1: model-form error or underestimated noise).
    tau
        Integrated autocorrelation time of the residual along frequency (n_eff = n / τ).
    sigmas_stat, sigmas_model
        Statistical σ (linearised, scaled by χ²_red and τ) and model-form σ (jackknife).
    score
        Ranking criterion: the BIC with its gain shrunk for implausible parameters.
    implausible
        Parameters outside their plausible range: name → distance in range widths.
    cov_u
        Statistical covariance of the fitted coordinates (log space for logarithmic parameters), in
        the candidate's parameter order; None if not computed.
    """

    candidate: object
    values: dict
    sigmas: dict
    rss: float
    n: int
    p: int
    bic: float
    mismatch: float
    mismatch_levels: np.ndarray
    nfev: int = 0
    at_bound: list = field(default_factory=list)
    #: χ²_red = RSS/(n − p) of the weighted residual (> 1: model-form error or underestimated noise)
    chi2_red: float = 1.0
    #: integrated autocorrelation time of the residual along frequency (n_eff = n / tau)
    tau: float = 1.0
    #: statistical σ (linearised, scaled by χ²_red and τ) and model-form σ (jackknife), if computed
    sigmas_stat: dict = field(default_factory=dict)
    sigmas_model: dict = field(default_factory=dict)
    #: ranking criterion: the BIC with its gain shrunk for implausible parameters (set by the diagnosis)
    score: float = float("nan")
    #: parameters outside their plausible range: {name: distance in units of the range width}
    implausible: dict = field(default_factory=dict)
    #: statistical covariance of the fitted coordinates (log space for logarithmic parameters), in the
    #: candidate's parameter order; None if not computed
    cov_u: np.ndarray | None = None

    @property
    def name(self) -> str:
        return "nominal" if self.candidate is None else self.candidate.name

    @property
    def family(self) -> str:
        return "none" if self.candidate is None else self.candidate.family

    def describe(self) -> str:
        """Plain-language phrase of this fit (the nominal model, or the candidate with its values).

        Returns
        -------
        str
        """
        if self.candidate is None:
            return "the nominal model as it is"
        return self.candidate.describe(self.values, self.sigmas)


def _bic(rss: float, n: int, p: int) -> float:
    return float(n * np.log(max(rss, 1e-300) / n) + p * np.log(n))


def _unfitted(ev: ModelEvaluator, H: np.ndarray, cand=None, nfev: int = 0) -> Fit:
    """The fit of a model without free parameters (the nominal one when ``cand`` is None)."""
    r = ev.residual(H)
    rss = float(r @ r)
    return Fit(cand, {}, {}, rss, ev.n, 0, _bic(rss, ev.n, 0), ev.mismatch(H), ev.mismatch(H, True), nfev)


def nominal_fit(ev: ModelEvaluator, nominal) -> Fit:
    """The nominal model scored like a fit (no parameters)."""
    return _unfitted(ev, ev.predict(nominal))


def _changes_model(cand) -> bool:
    from jointdb.diagnose.physics import Candidate

    return type(cand).apply is not Candidate.apply


def _prefit_frequencies(nominal, cand, params, u0, lo, hi, target):
    """Stage 1: move each recorded peak's nearest natural frequency onto it (smooth, cheap)."""
    n = len(target)
    n_modes = n + 4

    def fun(u):
        vals = {q.name: q.from_u(x) for q, x in zip(params, u)}
        try:
            f = natural_frequencies(cand.apply(nominal, vals, 0).assemble(), n_modes)   # = .modes(n).freq_hz
        except (NumericalError, np.linalg.LinAlgError, InputError):
            return np.full(n, 10.0)
        f = f[f > 1e-6 * target.max()]
        if f.size == 0:
            return np.full(n, 10.0)
        lr = np.log(f[None, :] / target[:, None])
        return lr[np.arange(n), np.argmin(np.abs(lr), axis=1)]

    # a rough match is all stage 2 needs: loose tolerances, few evaluations (each is an eigen-solve)
    res = scipy.optimize.least_squares(fun, u0, bounds=(lo, hi), method="trf", diff_step=1e-4,
                                       max_nfev=10 * (len(u0) + 1), xtol=1e-4, ftol=1e-4)
    return res.x, float(2 * res.cost)


def fit_candidate(ev: ModelEvaluator, nominal, cand, start: dict | None = None, max_nfev: int | None = None,
                  target_freqs: np.ndarray | None = None) -> Fit:
    """Fit one candidate's parameters (bounded least squares) and score it.

    Parameters
    ----------
    ev
        :class:`ModelEvaluator` over the observation.
    nominal
        The nominal :class:`jointdb.fe.BeamModel`.
    cand
        A :class:`jointdb.diagnose.physics.Candidate`.
    start
        Optional starting values (SI) overriding the candidate's.
    max_nfev
        Most model evaluations of the least-squares fit (default ``30 (p + 1)``).
    target_freqs
        Recorded resonance frequencies [Hz] (ascending, the model's first
        modes); if given, each start is first moved to match them (stage 1)
        before the FRF residual is minimised (stage 2).

    Returns
    -------
    Fit
    """
    params = cand.params
    p = len(params)
    if p == 0:
        return _unfitted(ev, ev.predict(nominal, cand, {}), cand, nfev=1)
    lo = np.array([q.u_bounds[0] for q in params])
    hi = np.array([q.u_bounds[1] for q in params])
    fun = _residual_function(ev, nominal, cand)
    starts = _starts(nominal, cand, start, target_freqs, lo, hi)
    res, rss, nfev = _refine_best(fun, starts, lo, hi, max_nfev or 30 * (p + 1), cand.name)
    values = _values_of(params, res.x)
    sigmas, cov, inflate = linearised_sigmas(params, res, rss, ev)
    at_bound = [q.name for q, x, a, b in zip(params, res.x, lo, hi) if min(x - a, b - x) < 1e-3]
    H = ev.predict_u(nominal, cand, res.x)
    return Fit(cand, values, sigmas, rss, ev.n, p, _bic(rss, ev.n, p), ev.mismatch(H), ev.mismatch(H, True),
               nfev, at_bound, chi2_red=rss / max(ev.n - p, 1), tau=inflate, sigmas_stat=dict(sigmas), cov_u=cov)


def _values_of(params, u) -> dict:
    """Parameter values (SI) from the fit's coordinates ``u``."""
    return {q.name: q.from_u(x) for q, x in zip(params, u)}


def _residual_function(ev: ModelEvaluator, nominal, cand):
    """The weighted residual as a function of the fit's coordinates (1e3 everywhere where the model fails)."""
    def fun(u):
        try:
            return ev.residual(ev.predict_u(nominal, cand, u))
        except (NumericalError, np.linalg.LinAlgError):
            return np.full(ev.n if ev.n else 1, 1e3)

    return fun


def _starts(nominal, cand, start: dict | None, target_freqs, lo: np.ndarray, hi: np.ndarray) -> list:
    """Starting points in the fit's coordinates: the given start (or the candidate's and its extra
    starts), each first moved to match the recorded resonances when they are given (stage 1; the best
    two are kept)."""
    params = cand.params
    starts = []
    u0 = np.array([q.to_u(start[q.name]) if start and q.name in start else 0.0 for q in params])
    starts.append(np.clip(u0, lo + 1e-9, hi - 1e-9))
    if not start:
        for k in range(max(len(q.starts) for q in params)):
            alt = np.array([q.to_u(q.starts[k]) if k < len(q.starts) else 0.0 for q in params])
            starts.append(np.clip(alt, lo + 1e-9, hi - 1e-9))
    if target_freqs is not None and len(target_freqs) and not cand.per_level and \
            _changes_model(cand):
        moved = []
        for u_start in starts:
            u1, c1 = _prefit_frequencies(nominal, cand, params, u_start, lo, hi, np.asarray(target_freqs))
            moved.append((c1, np.clip(u1, lo + 1e-9, hi - 1e-9)))
        moved.sort(key=lambda t: t[0])
        starts = [u for _, u in moved[:2]]
    return starts


def _refine_best(fun, starts: list, lo: np.ndarray, hi: np.ndarray, max_nfev: int, name: str):
    """Stage 2: minimise the FRF residual from the starts (a start already 4× worse than the best so
    far is not refined). Returns ``(least-squares result, RSS, model evaluations)``."""
    best = None
    nfev = 0
    for u_start in starts:
        # a cheap look at each start first; only the best one is refined fully
        r0 = fun(u_start)
        cost0 = float(r0 @ r0)
        if best is not None and cost0 > 4 * best[1]:
            nfev += 1
            continue
        try:
            res = scipy.optimize.least_squares(fun, u_start, bounds=(lo, hi), method="trf", diff_step=1e-4,
                                               x_scale=1.0, max_nfev=max_nfev, xtol=1e-5, ftol=1e-5)
        except ValueError as exc:  # pragma: no cover - defensive
            raise InputError(f"cannot fit candidate {name}: {exc}") from None
        nfev += res.nfev
        rss = float(2 * res.cost)
        if best is None or rss < best[1]:
            best = (res, rss)
    res, rss = best
    return res, rss, nfev
