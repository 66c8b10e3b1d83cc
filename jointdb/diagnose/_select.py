"""Selection of an explanation: the acceptance rules, which candidates are fitted, the single and
paired fits, plausibility, and the settled best (simplest practically as good, refined, with its
model-form uncertainty)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from jointdb.diagnose._compare import Signature, find_peaks
from jointdb.diagnose._data import Observation
from jointdb.diagnose._fit import Fit, ModelEvaluator, fit_candidate
from jointdb.diagnose._identify import damping_grows, model_form_sigmas
from jointdb.diagnose.physics import Combination, Context, candidates_for
from jointdb.diagnose.physics.interface import screen_sites

__all__ = ["BIC_MARGIN", "MIN_IMPROVEMENT", "MIN_PAIR_IMPROVEMENT", "OCCAM_TOLERANCE", "PLAUSIBILITY_WEIGHT",
           "CLOSE_CALL", "Rules", "plausibility", "select_candidates", "prefit_targets", "fit_singles",
           "fit_pairs", "settle_best"]

#: An explanation must lower the BIC by at least this much ...
BIC_MARGIN = 10.0
#: ... and reduce the mismatch by at least this factor (false-alarm threshold,
#: chosen on null cases of the benchmark generator: see docs/validation/diagnose-bench.md).
MIN_IMPROVEMENT = 1.5
#: A combination (a second effect) must beat the best single explanation by this
#: factor in mismatch, and by BIC_MARGIN in BIC *per independent line group*
#: (ΔBIC divided by the residual's correlation time τ), so that a second effect
#: is not added merely to soak up the model-form error of the first.
MIN_PAIR_IMPROVEMENT = 2.0
#: Parsimony: an explanation with fewer parameters whose mismatch is within
#: this factor of the BIC-best one is preferred (BIC alone under-penalises,
#: because residuals on neighbouring lines are correlated).
OCCAM_TOLERANCE = 1.15
#: A fit whose parameters lie outside their plausible range keeps only 1/(1 + w Σd²) of its BIC gain
#: (d: distance outside the range in units of its width; see Param.implausibility).
PLAUSIBILITY_WEIGHT = 4.0
#: Another explanation within this factor of the best's mismatch is named as a close alternative.
CLOSE_CALL = 1.25
#: Evaluations per parameter (+1) of the harmonic-balance refinement of a selected micro-slip joint.
REFINE_EVALUATIONS = 3
#: Interface sites at which level-dependent joints are fitted (those of the best linear joint fits).
LEVEL_SITES = 2
#: Families of linear joints (a level-dependent joint starts from their fit at the same place).
JOINT_FAMILIES = ("joint_compliance", "joint_damping")


def plausibility(fit: Fit, nominal: Fit) -> None:
    """Mark parameters outside their plausible range and shrink the fit's BIC gain accordingly.

    ``score = BIC_nominal + ΔBIC / (1 + PLAUSIBILITY_WEIGHT Σ d²)`` for a gain
    (ΔBIC < 0), ``d`` being each parameter's distance outside its plausible
    range in units of the range width (:meth:`Param.implausibility`).
    """
    params = fit.candidate.params if fit.candidate is not None else ()
    bad = {q.name: q.implausibility(fit.values[q.name]) for q in params}
    fit.implausible = {k: v for k, v in bad.items() if v > 0}
    d2 = sum(v * v for v in fit.implausible.values())
    gain = fit.bic - nominal.bic
    fit.score = nominal.bic + (gain / (1.0 + PLAUSIBILITY_WEIGHT * d2) if gain < 0 else gain)


def per_level_start(cand, fits: list[Fit]) -> dict | None:
    """Start a level-dependent candidate from the best fitted linear joint at the same place."""
    names = {q.name for q in cand.params}
    same = [f for f in fits if f.candidate.slot == cand.slot and f.family in JOINT_FAMILIES
            and names >= {q.name for q in f.candidate.params} - {"eta_joint"}]
    if not same:
        same = [f for f in fits if f.family in JOINT_FAMILIES and not hasattr(f.candidate, "site")]
    if not same:
        return None
    seed = min(same, key=lambda f: f.bic).values
    start = {k: v for k, v in seed.items() if k in names}
    if "eta_joint" in seed and "eta_0" in names:
        start["eta_0"] = seed["eta_joint"]
    return start or None


@dataclass(frozen=True)
class Rules:
    """The selection rules of a diagnosis, against its nominal fit."""

    nominal: Fit
    #: the recordings differ across levels beyond noise
    level_dependent: bool
    #: ... and their damping grows with the level
    damping_grows: bool = False

    def eligible(self, f: Fit) -> bool:
        # when the levels disagree beyond noise, only an explanation that accounts for all of them may win;
        # when the recorded damping grows with the level, only one whose damping grows with it
        if not self.level_dependent:
            return True
        return f.candidate.per_level and (not self.damping_grows or damping_grows(f))

    @staticmethod
    def passes(f: Fit, ref: Fit) -> bool:
        return f.score <= ref.score - BIC_MARGIN and f.mismatch * MIN_IMPROVEMENT <= ref.mismatch

    def simplest(self, f: Fit, fits: list[Fit]) -> Fit:
        """The member of f's slot with fewest parameters that is practically as good."""
        near = [g for g in fits if g.candidate.slot == f.candidate.slot and self.passes(g, self.nominal)
                and self.eligible(g) and g.mismatch <= OCCAM_TOLERANCE * f.mismatch]
        return min(near, key=lambda g: (g.p, g.score)) if near else f


def select_candidates(model, obs: Observation, modes: np.ndarray, before: Signature, families, level_dependent: bool):
    """The candidates worth fitting: the families asked for, the best-screened interface sites, and
    level-dependent physics only when the levels differ."""
    ctx = Context(model=model, points=tuple(dict.fromkeys(obs.out_points)), n_levels=len(obs.levels),
                  levels=obs.levels, modes_hz=modes)
    cands = candidates_for(ctx)
    if families is not None:
        cands = [c for c in cands if c.family in set(families)]
    # joints inside the stack: screen the sites on the recorded frequency shifts, fit only the best few
    sites = sorted({c.site for c in cands if hasattr(c, "site")}, key=lambda st: st.position)
    kept = set(screen_sites(model, sites, before.pairs)) if sites else set()
    cands = [c for c in cands if not hasattr(c, "site") or c.site in kept]
    if not level_dependent:
        # a level-dependent explanation of recordings that agree across levels is invented physics
        cands = [c for c in cands if not c.per_level]
    return cands


def prefit_targets(full: ModelEvaluator) -> np.ndarray | None:
    """Recorded resonances for the stage-1 frequency pre-fit: the strong recorded peaks
    (10 % of the strongest), each pulling its nearest model mode."""
    rpk = find_peaks(full.freq, full.rec[0], full.w[0])
    top = max((p.height for p in rpk), default=0.0)
    strong = sorted(p.freq_hz for p in rpk if p.height >= 0.1 * top)
    return np.asarray(strong) if strong else None


def fit_singles(ev: ModelEvaluator, model, cands, target, rules: Rules) -> list[Fit]:
    """Fit every single candidate, best score first (level-dependent joints only at the best sites)."""
    fits = [fit_candidate(ev, model, c, target_freqs=target) for c in cands if not c.per_level]
    # level-dependent joints (each fit costs one model per level) only where a linear joint fits best
    linear = sorted((f for f in fits if hasattr(f.candidate, "site") and f.family in JOINT_FAMILIES),
                    key=lambda f: f.bic)
    best_sites = list(dict.fromkeys(f.candidate.site for f in linear))[:LEVEL_SITES]
    for c in cands:
        if c.per_level and (not hasattr(c, "site") or c.site in best_sites):
            fits.append(fit_candidate(ev, model, c, start=per_level_start(c, fits)))
    for f in fits:
        plausibility(f, rules.nominal)
    fits.sort(key=lambda f: f.score)
    return fits


def fit_pairs(ev: ModelEvaluator, model, fits: list[Fit], rules: Rules) -> list[Fit]:
    """Add the pairs of the (up to three) best single explanations of different slots and families
    that beat the best single one clearly enough; all fits, best score first."""
    tops = []
    for f in (rules.simplest(f, fits) for f in fits):
        if rules.passes(f, rules.nominal) and all(f.candidate.slot != t.candidate.slot and
                                                  f.family != t.family for t in tops):
            tops.append(f)
        if len(tops) == 3:
            break
    best_single = next((f for f in fits if rules.eligible(f)), fits[0])
    pair_fits = []
    for i in range(len(tops)):
        for j in range(i + 1, len(tops)):
            a, b = tops[i], tops[j]
            if a.candidate.per_level and b.candidate.per_level:
                continue
            if rules.level_dependent and not (a.candidate.per_level or b.candidate.per_level):
                continue
            combo = Combination(a.candidate, b.candidate)
            start = {f"a.{k}": v for k, v in a.values.items()} | {f"b.{k}": v for k, v in b.values.items()}
            pf = fit_candidate(ev, model, combo, start=start, max_nfev=12 * (len(combo.params) + 1))
            plausibility(pf, rules.nominal)
            tau = max(best_single.tau, 1.0)
            if (best_single.score - pf.score) / tau >= BIC_MARGIN and pf.mismatch * MIN_PAIR_IMPROVEMENT <= \
                    best_single.mismatch:
                pair_fits.append(pf)
    return sorted(fits + pair_fits, key=lambda f: f.score)


def settle_best(ev: ModelEvaluator, model, ok: list[Fit], fits: list[Fit], rules: Rules):
    """The selected explanation among the accepted ``ok`` (the simplest practically as good as the best),
    with its uncertainties, refined by harmonic balance when it can be; and the ranking, it first."""
    best = ok[0]
    near = [f for f in ok if f.mismatch <= OCCAM_TOLERANCE * best.mismatch]
    best = min(near, key=lambda f: (bool(f.implausible), f.p, f.score))
    fits = [best] + [f for f in fits if f is not best]
    model_form_sigmas(ev, model, best, fits, rules)
    # an amplitude-dependent joint with known forces: refine by harmonic balance line by line (the
    # selection used the per-level describing function at the linear peak, which is ~20x cheaper)
    refine = getattr(best.candidate, "refined", None)
    fine = refine() if refine is not None else None
    if fine is not None:
        rf = fit_candidate(ev, model, fine, start=best.values, max_nfev=REFINE_EVALUATIONS * (best.p + 1))
        plausibility(rf, rules.nominal)
        if rf.mismatch < best.mismatch:
            rf.sigmas_model = best.sigmas_model
            rf.sigmas = {k: float(np.hypot(v, rf.sigmas_model.get(k, 0.0))) for k, v in rf.sigmas_stat.items()}
            fits = [rf] + fits
            best = rf
    return best, fits
