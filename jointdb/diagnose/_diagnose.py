"""Diagnosis: compare, fit every candidate physics (and small combinations),
select by BIC with a practical false-alarm threshold, and explain."""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from jointdb.diagnose._compare import Signature, signature
from jointdb.diagnose._data import Measurement, Observation, prepare
from jointdb.diagnose._fit import Fit, ModelEvaluator, nominal_fit
from jointdb.diagnose._identify import combination_note, identified, identify_advice, next_ranked, unidentified
from jointdb.diagnose._select import (
    BIC_MARGIN,
    CLOSE_CALL,
    MIN_IMPROVEMENT,
    MIN_PAIR_IMPROVEMENT,
    OCCAM_TOLERANCE,
    Rules,
    fit_pairs,
    fit_singles,
    prefit_targets,
    select_candidates,
    settle_best,
)
from jointdb.diagnose._validity import check_beam_range
from jointdb.diagnose._verdict import (
    explained_verdict,
    levels_text,
    not_better_verdict,
    rank_text,
    shift_text,
    unexplained_verdict,
    unidentified_verdict,
)
from jointdb.diagnose.physics import Combination
from jointdb.errors import InputError

__all__ = ["Diagnosis", "diagnose", "BIC_MARGIN", "MIN_IMPROVEMENT", "MIN_PAIR_IMPROVEMENT"]


@dataclass
class Diagnosis:
    """The result of :func:`diagnose`.

    Attributes
    ----------
    explained
        True if some candidate physics passes the selection (ΔBIC ≤ −BIC_MARGIN
        and mismatch reduced ≥ MIN_IMPROVEMENT ×); False = nothing significant
        to add (no invented physics).
    verdict
        Plain-language summary.
    best
        The selected :class:`Fit` (None if not explained).
    ranking
        All fits (candidates and combinations), best BIC first.
    nominal
        The nominal model's :class:`Fit` (on the fit lines).
    before, after
        :class:`Signature` of the nominal and the augmented model on all lines.
    mismatch_before, mismatch_after
        Weighted RMS |log ratio| on all recorded lines in the band.
    augmented
        The augmented model(s), one per level (a single one unless the
        explanation is level dependent); None if not explained.
    chain_correction
        For measurement-chain explanations: ``{"gain": g, "delay": τ}`` to
        apply to the recording (the model itself is unchanged).
    observation
        The :class:`Observation` the fits ran on.
    level_table
        Per excitation level, the fitted level-dependent values (level-dependent explanations).
    seconds
        Wall time of the diagnosis [s].
    H_before, H_after
        Nominal and augmented model receptance on all recorded lines,
        ``(n_level, n_freq, n_out, n_in)``, or None.
    levels_data, levels_model
        Local modal fits per excitation level of the recordings and of the augmented model
        (:class:`LevelAnalysis`), or None.
    alternative
        A close second explanation (another physics within ``CLOSE_CALL`` of the best), or None.
    advice
        How to separate the best explanation from the alternative (which measurement to add).
    unresolved
        The best-fitting explanation when its key parameters are not identified (it is then not
        named, or a nearly as good identified one is; :mod:`jointdb.diagnose._identify`), or None.
    """

    explained: bool
    verdict: str
    best: Fit | None
    ranking: list
    nominal: Fit
    before: Signature
    after: Signature | None
    mismatch_before: float
    mismatch_after: float
    augmented: tuple
    chain_correction: dict
    observation: Observation
    level_table: list = field(default_factory=list)
    seconds: float = 0.0
    H_before: np.ndarray | None = None
    H_after: np.ndarray | None = None
    #: local modal fits per excitation level of the recordings and of the augmented model (``LevelAnalysis``)
    levels_data: object = None
    levels_model: object = None
    #: a close second explanation (another physics within CLOSE_CALL of the best) and how to separate them
    alternative: Fit | None = None
    advice: str = ""
    #: the best-fitting explanation when its key parameters are not identified (it is then not named, or
    #: a nearly as good identified one is); see :mod:`jointdb.diagnose._identify`
    unresolved: Fit | None = None

    @property
    def location(self) -> str | None:
        """Where the selected explanation sits, in words (joints, sensors), or None."""
        return self._where("location")

    @property
    def position(self) -> float | None:
        """Axial position [m] of the selected explanation (model coordinates), or None."""
        return self._where("position")

    def _where(self, attr: str):
        """``attr`` of the selected candidate (the first of a combination), or None."""
        if self.best is None:
            return None
        c = self.best.candidate
        c = c.parts[0] if hasattr(c, "parts") else c
        return getattr(c, attr, None)

    def table(self) -> list[dict]:
        """Ranked explanations as rows (name, family, parameters, ΔBIC, mismatch, improvement).

        Returns
        -------
        list of dict
        """
        rows = []
        for rank, f in enumerate(self.ranking, 1):
            rows.append({
                "rank": rank, "explanation": f.name,
                "parameters": "; ".join(q.shown(f.values[q.name], f.sigmas.get(q.name))
                                        for q in f.candidate.params) if f.candidate else "",
                "dBIC": round(f.bic - self.nominal.bic, 1),
                "plausible": not f.implausible,
                "fit-line mismatch %": round(100 * f.mismatch, 2),
                "gain x": round(self.nominal.mismatch / f.mismatch, 2) if f.mismatch > 0 else None,
            })
        return rows

    def to_dict(self) -> dict:
        """The diagnosis as a JSON-ready dict (verdict, signatures, ranking, level tables).

        Returns
        -------
        dict
        """
        b = self.best
        return {
            "explained": self.explained,
            "verdict": self.verdict,
            "criterion": f"BIC = n ln(RSS/n) + p ln n (gain shrunk for implausible parameters); accept if "
                         f"ΔBIC <= -{BIC_MARGIN:g} and "
                         f"mismatch falls >= {MIN_IMPROVEMENT:g}x; a second effect only if it lowers BIC by "
                         f">= {BIC_MARGIN:g} per residual correlation length and mismatch >= "
                         f"{MIN_PAIR_IMPROVEMENT:g}x below the best single; prefer fewer parameters within "
                         f"{OCCAM_TOLERANCE:g}x of the best mismatch",
            "mismatch_before": self.mismatch_before,
            "mismatch_after": self.mismatch_after,
            "location": self.location, "position_m": self.position,
            "best": None if b is None else {
                "name": b.name, "family": b.family, "description": b.describe(),
                "implausible": dict(b.implausible),
                "values": b.values, "sigmas": b.sigmas, "sigmas_statistical": b.sigmas_stat,
                "sigmas_model_form": b.sigmas_model, "reduced_chi2": b.chi2_red,
                "residual_correlation_lines": b.tau, "parameters_at_bound": b.at_bound},
            "ranking": [{"rank": r["rank"], "explanation": r["explanation"], "family": f.family,
                         "values": f.values, "sigmas": f.sigmas, "delta_bic": r["dBIC"],
                         "fit_line_mismatch": f.mismatch,
                         "mismatch": f.mismatch, "improvement": r["gain x"]}
                        for r, f in zip(self.table(), self.ranking)],
            "modes": [{"mode": p.mode, "f_model_hz": p.model.freq_hz, "f_recorded_hz": p.recorded.freq_hz,
                       "shift_pct": 100 * p.shift, "damping_ratio": p.damping_ratio,
                       "height_db": p.height_db, "band_mismatch_pct": 100 * p.mismatch, "dofs": list(p.dofs)}
                      for p in self.before.pairs],
            "extra_peaks_hz": self.before.extra_peaks, "missing_peaks_hz": self.before.missing_peaks,
            "gain_offset_db": self.before.gain_db, "phase_drift_delay_s": self.before.delay_s,
            "frac": self.before.frac,
            "level_shifts": self.before.level_shifts, "affected_mode": self.before.affected_mode,
            "level_table": self.level_table,
            "levels": None if self.levels_data is None else self.levels_data.to_dict(),
            "levels_model": None if self.levels_model is None else self.levels_model.to_dict(),
            "alternative": None if self.alternative is None else {
                "name": self.alternative.name, "family": self.alternative.family,
                "description": self.alternative.describe(), "mismatch": self.alternative.mismatch,
                "separating_measurement": self.advice},
            "unresolved": None if self.unresolved is None else {
                "name": self.unresolved.name, "family": self.unresolved.family,
                "values": self.unresolved.values, "sigmas": self.unresolved.sigmas,
                "not_identified": unidentified(self.unresolved)},
            "chain_correction": self.chain_correction,
            "seconds": self.seconds,
        }


def _level_analysis(obs: Observation, centres=None):
    """Local modal fits per level (None with a single level or when no mode can be fitted)."""
    if len(obs.levels) < 2:
        return None
    from jointdb.diagnose._levels import track_modes
    from jointdb.errors import NumericalError

    try:
        return track_modes(obs.full_freq, obs.full_values, obs.full_weight, obs.levels, centres=centres)
    except (InputError, NumericalError, np.linalg.LinAlgError):
        return None


def _model_level_analysis(full: ModelEvaluator, H: np.ndarray, obs: Observation, data):
    """The same local modal fits on a model's per-level FRFs (for trends comparable with the data's)."""
    if data is None or not data.tracks:
        return None
    from jointdb.diagnose._levels import track_modes
    from jointdb.errors import NumericalError

    centres = [t.freq_hz[data.order[0]] for t in data.tracks]
    try:
        return track_modes(full.freq, H, np.where(full.w > 0, full.w, 0.0), obs.levels, centres=centres)
    except (InputError, NumericalError, np.linalg.LinAlgError):
        return None


def diagnose(model, measurements: Sequence[Measurement], mapping: Mapping[int, str] | None = None,
             band: tuple[float | None, float | None] = (None, None), combinations: bool = True,
             families: Sequence[str] | None = None, mask_nonfinite: bool = False) -> Diagnosis:
    """Locate the mismatch between a model and recordings and explain it with candidate physics.

    Parameters
    ----------
    model
        Nominal :class:`jointdb.fe.BeamModel`.
    measurements
        :class:`Measurement` s (several = several excitation levels of one test).
    mapping
        ``{recording node: model point name}`` (default: by the points' ``node``).
    band
        Optional ``(fmin, fmax)`` [Hz].
    combinations
        Also fit pairs of the best single explanations.
    families
        Restrict the candidate families (default: all offered).
    mask_nonfinite
        Give non-finite recorded lines zero weight (with a note) instead of refusing them.

    Returns
    -------
    Diagnosis

    Raises
    ------
    InputError
        See :func:`jointdb.diagnose._data.prepare`; also when the recorded band
        holds no resonance of model or recording.

    Examples
    --------
    A clamped steel rod recorded with a 20 g accelerometer at its tip that the model left
    out: the bending modes are recorded 6–7 % low, and the diagnosis names the sensor and
    its mass (here only the sensor-mass family is tried, to keep the example fast):

    >>> import numpy as np
    >>> from jointdb.fe import BeamModel, Clamp, ModalDamping, NamedPoint, PointMass, Segment
    >>> from jointdb.diagnose import Measurement, diagnose
    >>> shaft, tip = (Segment(0.2, 0.02, material="steel"),), (NamedPoint("tip", 0.0, node=1),)
    >>> model = BeamModel(shaft, tip, (Clamp(0.2), ModalDamping(0.01)))
    >>> with_sensor = BeamModel(shaft, tip, (Clamp(0.2), ModalDamping(0.01), PointMass(0.0, 0.02)))
    >>> recording = with_sensor.frf(np.arange(50.0, 3000.0, 5.0), points=["tip"]).select(["1x"], ["1x"])
    >>> result = diagnose(model, [Measurement(recording)], families=["sensor_mass"], combinations=False)
    >>> result.explained, result.best.candidate.family
    (True, 'sensor_mass')
    >>> round(result.best.values["mass"] * 1e3, 2)                     # g
    20.0
    >>> result.mismatch_before > 0.5, result.mismatch_after < 1e-6
    (True, True)
    """
    t0 = time.perf_counter()
    run = _compare(model, measurements, mapping, band, mask_nonfinite)
    best, unresolved, ok, fits, found = _search(run, model, families, combinations)
    # rank 1 is what the verdict talks about: the named fit, else the unidentified one, else the best
    # fit that could explain these recordings (with level dependence: an amplitude-dependent one)
    top = best or unresolved
    fits = ([top] if top is not None else []) + sorted((f for f in fits if f is not top),
                                                        key=lambda f: (not run.rules.eligible(f), f.score))
    mis0 = run.full.mismatch(np.asarray(run.H0_full))
    mis1 = run.full.mismatch(np.asarray(found.H_full)) if found.H_full is not None else mis0
    if best is not None and mis1 * MIN_IMPROVEMENT > mis0:
        # the fit lines improved but the whole band did not: not an explanation (never explained=True below 1.5x)
        words = _Words(not_better_verdict(best, _where(run), mis0, mis1, MIN_IMPROVEMENT))
        best, found, mis1 = None, _Found(), mis0
    else:
        words = _words(run, best, unresolved, ok, fits, found, mis0, mis1)
    levels_model = _model_level_analysis(run.full, np.asarray(found.H_full), run.obs, run.levels_data) \
        if found.H_full is not None and run.levels_data is not None else None
    return Diagnosis(
        explained=best is not None, verdict=words.verdict, best=best, ranking=fits, nominal=run.nominal,
        before=run.before, after=found.after, mismatch_before=mis0, mismatch_after=mis1,
        augmented=found.augmented, chain_correction=found.chain, observation=run.obs,
        level_table=found.level_table, seconds=time.perf_counter() - t0, H_before=np.asarray(run.H0_full),
        H_after=None if found.H_full is None else np.asarray(found.H_full),
        levels_data=run.levels_data, levels_model=levels_model, alternative=words.alternative,
        advice=words.advice, unresolved=unresolved,
    )


@dataclass(frozen=True)
class _Run:
    """A diagnosis's first step: the recordings on the model's lines, the nominal model compared with
    them, and the selection rules that follow from the levels."""

    obs: Observation
    ev: ModelEvaluator            # the fit lines
    full: ModelEvaluator          # all recorded lines (direct synthesis)
    modes: np.ndarray             # the nominal model's first natural frequencies [Hz]
    H0_full: object               # the nominal receptance on all lines
    before: Signature
    nominal: Fit
    levels_data: object           # LevelAnalysis of the recordings, or None
    rules: Rules


def _compare(model, measurements, mapping, band, mask_nonfinite: bool) -> _Run:
    """Read the recordings onto the model's lines and compare the nominal model with them."""
    modes = model.modes(8).freq_hz
    kw = {"mask_nonfinite": True} if mask_nonfinite else {}
    obs = prepare(model, measurements, mapping, band, model_freqs=modes, **kw)
    obs = check_beam_range(obs, model)
    ev = ModelEvaluator(obs)
    full = ModelEvaluator(obs, full=True, method="direct")
    H0_full = full.predict(model)
    before = signature(full, np.asarray(H0_full))
    _check_shared_resonance(obs, modes, before)
    nominal = nominal_fit(ev, model)
    nominal.score = nominal.bic
    levels_data = _level_analysis(obs)
    rules = Rules(nominal, levels_data is not None and levels_data.differs,
                  levels_data is not None and levels_data.damping_grows)
    return _Run(obs, ev, full, modes, H0_full, before, nominal, levels_data, rules)


def _search(run: _Run, model, families, combinations: bool):
    """Fit the candidates (and pairs), select, and keep the selection only if it is identified.

    Returns ``(best, unresolved, ok, fits, found)``: the named fit (or None), the best fit left unnamed
    as not identified (or None), the accepted fits, all fits, and what the named fit gives (:class:`_Found`).
    """
    cands = select_candidates(model, run.obs, run.modes, run.before, families, run.rules.level_dependent)
    fits = fit_singles(run.ev, model, cands, prefit_targets(run.full), run.rules)
    if combinations and fits:
        fits = fit_pairs(run.ev, model, fits, run.rules)
    ok = [f for f in fits if run.rules.eligible(f) and run.rules.passes(f, run.nominal)]
    best, found, unresolved = None, _Found(), None
    if ok:
        best, fits = settle_best(run.ev, model, ok, fits, run.rules)
        best, unresolved = identified(run.ev, model, best, ok, fits, run.rules, CLOSE_CALL)
        if best is not None:
            found = _apply_best(model, best, run.obs, run.full, run.levels_data)
    return best, unresolved, ok, fits, found


@dataclass(frozen=True)
class _Words:
    verdict: str
    alternative: Fit | None = None
    advice: str = ""


def _where(run: _Run) -> str:
    """Where the recording departs from the model (mode shifts, level trends), in words."""
    return shift_text(run.before) + levels_text(run.levels_data)


def _words(run: _Run, best, unresolved, ok, fits, found, mis0: float, mis1: float) -> _Words:
    """The verdict: what was named (rank 1) and why it beats the next, or why nothing is named."""
    where, rules = _where(run), run.rules
    if unresolved is not None and best is None:
        return _Words(unidentified_verdict(unresolved, unidentified(unresolved), where, mis0,
                                           identify_advice(unresolved, len(set(run.obs.out_points)),
                                                           len(run.obs.levels))))
    if best is None:
        runner = fits[0] if fits else None
        verdict = unexplained_verdict(fits, runner, rules.nominal.mismatch, rules.level_dependent, where, mis0)
        if runner is not None and rules.level_dependent and not rules.eligible(runner):
            verdict += f" ({runner.candidate.explanation} cannot change with the excitation level.)"
        return _Words(verdict)
    verdict, alternative, advice = explained_verdict(best, ok, found.level_table, run.obs, where, mis0, mis1,
                                                     CLOSE_CALL)
    nxt = next_ranked(best, fits)
    # a close alternative is already named with the measurement that separates it
    verdict += combination_note(best) + rank_text(best, None if nxt is alternative else nxt, rules.eligible,
                                                  unresolved)
    return _Words(verdict, alternative, advice)


def _check_shared_resonance(obs: Observation, modes: np.ndarray, before: Signature) -> None:
    """InputError when the recorded band holds no resonance of the model or the recording."""
    in_band = [f for f in modes if obs.full_freq[0] <= f <= obs.full_freq[-1]]
    if not in_band and not before.pairs and not before.extra_peaks:
        raise InputError(
            f"the recording ({obs.full_freq[0]:g}–{obs.full_freq[-1]:g} Hz) and the model share no resonance: "
            f"the model's modes are at {', '.join(f'{f:.0f}' for f in modes[:4])} Hz; "
            "record (or choose with --band) a range that contains them"
        )


@dataclass
class _Found:
    """What a selected explanation gives: the augmented model(s), the measurement-chain correction,
    the per-level joint table, the signature and FRFs after (all empty without one)."""

    augmented: tuple = ()
    chain: dict = field(default_factory=dict)
    level_table: list = field(default_factory=list)
    after: Signature | None = None
    H_full: object = None


def _apply_best(model, best: Fit, obs: Observation, full: ModelEvaluator, levels_data) -> _Found:
    c = best.candidate
    found = _Found(augmented=tuple(c.apply(model, best.values, lv)
                                   for lv in range(len(obs.levels) if c.per_level else 1)))
    parts = c.parts if isinstance(c, Combination) else (c,)
    prefix = ("a.", "b.") if isinstance(c, Combination) else ("",)
    found.H_full = full.predict(model, c, best.values)
    for part, pre in zip(parts, prefix):
        if part.family == "gain":
            found.chain["gain"] = best.values[pre + "gain"]
        if part.family == "delay":
            found.chain["delay_s"] = best.values[pre + "delay"]
        if hasattr(part, "level_table"):
            vals = {k[len(pre):]: v for k, v in best.values.items() if k.startswith(pre)}
            f1 = levels_data.tracks[0].freq_hz if levels_data is not None and levels_data.tracks else None
            grid = None if f1 is None else np.linspace(0.9 * f1.min(), 1.1 * f1.max(), 81)
            found.level_table = part.level_table(vals, models=found.augmented if isinstance(c, type(part)) else None,
                                                 input_point=obs.in_points[0], freq_hz=grid)
    found.after = signature(full, np.asarray(found.H_full))
    return found
