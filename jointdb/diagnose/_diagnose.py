"""Diagnosis: compare, fit every candidate physics (and small combinations),
select by BIC with a practical false-alarm threshold, and explain."""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from jointdb.diagnose._compare import Signature, signature
from jointdb.diagnose._data import Measurement, Observation, prepare
from jointdb.diagnose._fit import Fit, ModelEvaluator, fit_candidate, jackknife_spread, nominal_fit
from jointdb.diagnose.physics import Combination, Context, candidates_for
from jointdb.errors import InputError

__all__ = ["Diagnosis", "diagnose", "BIC_MARGIN", "MIN_IMPROVEMENT", "MIN_PAIR_IMPROVEMENT"]

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

    def table(self) -> list[dict]:
        """Ranked explanations as rows (name, family, parameters, ΔBIC, mismatch, improvement)."""
        rows = []
        for rank, f in enumerate(self.ranking, 1):
            rows.append({
                "rank": rank, "explanation": f.name,
                "parameters": "; ".join(f"{q.name}={q.fmt(f.values[q.name], f.sigmas.get(q.name))}"
                                        for q in f.candidate.params) if f.candidate else "",
                "dBIC": round(f.bic - self.nominal.bic, 1),
                "mismatch %": round(100 * f.mismatch, 2),
                "gain x": round(self.nominal.mismatch / f.mismatch, 2) if f.mismatch > 0 else None,
            })
        return rows

    def to_dict(self) -> dict:
        b = self.best
        return {
            "explained": self.explained,
            "verdict": self.verdict,
            "criterion": f"BIC = n ln(RSS/n) + p ln n; accept if ΔBIC <= -{BIC_MARGIN:g} and "
                         f"mismatch falls >= {MIN_IMPROVEMENT:g}x; a second effect only if it lowers BIC by "
                         f">= {BIC_MARGIN:g} per residual correlation length and mismatch >= "
                         f"{MIN_PAIR_IMPROVEMENT:g}x below the best single; prefer fewer parameters within "
                         f"{OCCAM_TOLERANCE:g}x of the best mismatch",
            "mismatch_before": self.mismatch_before,
            "mismatch_after": self.mismatch_after,
            "best": None if b is None else {
                "name": b.name, "family": b.family, "description": b.describe(),
                "values": b.values, "sigmas": b.sigmas, "sigmas_statistical": b.sigmas_stat,
                "sigmas_model_form": b.sigmas_model, "reduced_chi2": b.chi2_red,
                "residual_correlation_lines": b.tau, "parameters_at_bound": b.at_bound},
            "ranking": [{"rank": r["rank"], "explanation": r["explanation"], "family": f.family,
                         "values": f.values, "sigmas": f.sigmas, "delta_bic": r["dBIC"],
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
            "chain_correction": self.chain_correction,
            "seconds": self.seconds,
        }


def _shift_text(sig: Signature) -> str:
    if not sig.pairs:
        return "no resonance of the model could be paired with one in the recording"
    low, high, same = [], [], []
    for p in sig.pairs:
        s = 100 * p.shift
        (same if abs(s) < 0.7 else low if s < 0 else high).append((p.mode, abs(s)))

    def grp(items, word):
        modes = ", ".join(str(m) for m, _ in items)
        vals = [v for _, v in items]
        rng = f"{min(vals):.1f} %" if len(vals) == 1 or max(vals) - min(vals) < 0.3 else \
            f"{min(vals):.1f}–{max(vals):.1f} %"
        return f"mode{'s' if len(items) > 1 else ''} {modes} {'is' if len(items) == 1 else 'are'} {rng} {word}"

    parts = []
    if low:
        parts.append(grp(low, "low in the recording"))
    if high:
        parts.append(grp(high, "high in the recording"))
    if same:
        m = ", ".join(str(m) for m, _ in same)
        parts.append(f"mode{'s' if len(same) > 1 else ''} {m} {'is' if len(same) == 1 else 'are'} "
                     "unchanged in frequency")
    text = "; ".join(parts)
    damp = [p.damping_ratio for p in sig.pairs if np.isfinite(p.damping_ratio)]
    if damp and (max(damp) > 1.4 or min(damp) < 0.7):
        text += "; recorded damping is " + ", ".join(f"×{d:.2g}" for d in damp) + " the model's (by mode)"
    if abs(sig.gain_db) > 0.5:
        text += f"; away from resonances the recording is {sig.gain_db:+.1f} dB off"
    if sig.delay_r2 > 0.5 and abs(sig.delay_s) > 3e-6:
        text += f"; its phase drifts in proportion to frequency (≈ {sig.delay_s * 1e6:.0f} µs)"
    if sig.extra_peaks:
        text += "; extra recorded peak(s) at " + ", ".join(f"{f:.0f}" for f in sig.extra_peaks) + " Hz"
    if sig.missing_peaks:
        text += "; model peak(s) missing in the recording at " + ", ".join(f"{f:.0f}" for f in sig.missing_peaks) \
            + " Hz"
    if sig.level_shifts:
        w = max(sig.level_shifts, key=lambda s: abs(s["shift"]))
        text += (f"; with rising excitation level mode {sig.affected_mode} moves {100 * w['shift']:+.1f} % "
                 f"and its damping changes ×{w['damping_ratio']:.2g}")
    return text


def diagnose(model, measurements: Sequence[Measurement], mapping: Mapping[int, str] | None = None,
             band: tuple[float | None, float | None] = (None, None), combinations: bool = True,
             families: Sequence[str] | None = None) -> Diagnosis:
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

    Returns
    -------
    Diagnosis

    Raises
    ------
    InputError
        See :func:`jointdb.diagnose._data.prepare`; also when the recorded band
        holds no resonance of model or recording.
    """
    t0 = time.perf_counter()
    modes = model.modes(8).freq_hz
    obs = prepare(model, measurements, mapping, band, model_freqs=modes)
    ev = ModelEvaluator(obs)
    full = ModelEvaluator(obs, full=True, method="direct")
    H0_full = full.predict(model)
    before = signature(full, np.asarray(H0_full))
    in_band = [f for f in modes if obs.full_freq[0] <= f <= obs.full_freq[-1]]
    if not in_band and not before.pairs and not before.extra_peaks:
        raise InputError(
            f"the recording ({obs.full_freq[0]:g}–{obs.full_freq[-1]:g} Hz) and the model share no resonance: "
            f"the model's modes are at {', '.join(f'{f:.0f}' for f in modes[:4])} Hz; "
            "record (or choose with --band) a range that contains them"
        )
    nominal = nominal_fit(ev, model)
    ctx = Context(model=model, points=tuple(dict.fromkeys(obs.out_points)), n_levels=len(obs.levels),
                  levels=obs.levels, modes_hz=modes)
    cands = candidates_for(ctx)
    if families is not None:
        cands = [c for c in cands if c.family in set(families)]
    # recorded resonances for the stage-1 frequency pre-fit: the strong recorded
    # peaks (10 % of the strongest), each pulling its nearest model mode
    from jointdb.diagnose._compare import find_peaks

    rpk = find_peaks(full.freq, full.rec[0], full.w[0])
    top = max((p.height for p in rpk), default=0.0)
    strong = sorted(p.freq_hz for p in rpk if p.height >= 0.1 * top)
    target = np.asarray(strong) if strong else None
    singles = [c for c in cands if not c.per_level]
    fits = [fit_candidate(ev, model, c, target_freqs=target) for c in singles]
    for c in cands:
        if c.per_level:
            joints = [f for f in fits if f.family in ("joint_compliance", "joint_damping")]
            seed = min(joints, key=lambda f: f.bic).values if joints else None
            start = {k: v for k, v in (seed or {}).items() if k in {q.name for q in c.params}}
            fits.append(fit_candidate(ev, model, c, start=start or None))
    fits.sort(key=lambda f: f.bic)

    def passes(f, ref):
        return f.bic <= ref.bic - BIC_MARGIN and f.mismatch * MIN_IMPROVEMENT <= ref.mismatch

    def simplest(f):
        """The member of f's slot with fewest parameters that is practically as good."""
        near = [g for g in fits if g.candidate.slot == f.candidate.slot and passes(g, nominal)
                and g.mismatch <= OCCAM_TOLERANCE * f.mismatch]
        return min(near, key=lambda g: (g.p, g.bic)) if near else f

    if combinations and fits:
        tops = []
        for f in (simplest(f) for f in fits):
            if passes(f, nominal) and all(f.candidate.slot != t.candidate.slot and
                                          f.family != t.family for t in tops):
                tops.append(f)
            if len(tops) == 3:
                break
        best_single = fits[0]
        pair_fits = []
        for i in range(len(tops)):
            for j in range(i + 1, len(tops)):
                a, b = tops[i], tops[j]
                if a.candidate.per_level and b.candidate.per_level:
                    continue
                combo = Combination(a.candidate, b.candidate)
                start = {f"a.{k}": v for k, v in a.values.items()} | {f"b.{k}": v for k, v in b.values.items()}
                pf = fit_candidate(ev, model, combo, start=start, max_nfev=12 * (len(combo.params) + 1))
                tau = max(best_single.tau, 1.0)
                if (best_single.bic - pf.bic) / tau >= BIC_MARGIN and pf.mismatch * MIN_PAIR_IMPROVEMENT <= \
                        best_single.mismatch:
                    pair_fits.append(pf)
        fits = sorted(fits + pair_fits, key=lambda f: f.bic)

    best = fits[0] if fits and passes(fits[0], nominal) else None
    if best is not None:
        near = [f for f in fits if passes(f, nominal) and f.mismatch <= OCCAM_TOLERANCE * best.mismatch]
        best = min(near, key=lambda f: (f.p, f.bic))
        fits = [best] + [f for f in fits if f is not best]
        # honest uncertainty of the selected explanation: statistical (χ²_red, τ) ⊕ model-form (jackknife)
        best.sigmas_model = jackknife_spread(ev, model, best)
        # model-form spread across the accepted variants of the same physics (e.g. a sensor as point mass,
        # with rotary inertia, with an offset): RMS deviation of their estimates of a shared parameter
        if best.candidate.slot:
            rivals = [g for g in fits if g is not best and g.candidate.slot == best.candidate.slot
                      and passes(g, nominal)]
            for k in best.values:
                dev = [g.values[k] - best.values[k] for g in rivals if k in g.values]
                if dev:
                    v = float(np.sqrt(np.mean(np.square(dev))))
                    best.sigmas_model[k] = float(np.hypot(best.sigmas_model.get(k, 0.0), v))
        best.sigmas = {k: float(np.hypot(v, best.sigmas_model.get(k, 0.0))) for k, v in best.sigmas_stat.items()}
    augmented: tuple = ()
    chain: dict = {}
    level_table: list = []
    after = None
    H1_full = None
    if best is not None:
        c = best.candidate
        augmented = tuple(c.apply(model, best.values, lv) for lv in range(len(obs.levels) if c.per_level else 1))
        parts = c.parts if isinstance(c, Combination) else (c,)
        prefix = ("a.", "b.") if isinstance(c, Combination) else ("",)
        for part, pre in zip(parts, prefix):
            if part.family == "gain":
                chain["gain"] = best.values[pre + "gain"]
            if part.family == "delay":
                chain["delay_s"] = best.values[pre + "delay"]
            if hasattr(part, "level_table"):
                vals = {k[len(pre):]: v for k, v in best.values.items() if k.startswith(pre)}
                level_table = part.level_table(vals)
        H1_full = full.predict(model, c, best.values)
        after = signature(full, np.asarray(H1_full))
    mis0 = full.mismatch(np.asarray(H0_full))
    mis1 = full.mismatch(np.asarray(H1_full)) if H1_full is not None else mis0

    where = _shift_text(before)
    if best is None:
        runner = fits[0] if fits else None
        if nominal.mismatch < 0.08 or runner is None:
            verdict = (f"No significant mismatch: model and recording agree to {100 * mis0:.1f} % "
                       f"({where}); no physics is added.")
        else:
            verdict = (f"The recording differs from the model ({where}; mismatch {100 * mis0:.1f} %), but no "
                       f"candidate physics explains it well: the best, {runner.describe()}, only brings it to "
                       f"{100 * runner.mismatch:.1f} % on the fit lines. Nothing is added.")
    else:
        lv = ""
        if level_table:
            lv = " Per level: " + "; ".join(
                f"{r['level'] if r['level'] is not None else i + 1}: k_x {r['k_x_n_per_m'] / 1e6:.3g} N/µm, "
                f"k_ry {r['k_ry_nm_per_rad'] / 1e3:.3g} kN·m/rad, η {r['loss_factor']:.3g}"
                for i, r in enumerate(level_table)) + "."
        verdict = (f"{where[0].upper() + where[1:]}. Best explained by {best.describe()}; "
                   f"mismatch {100 * mis0:.1f} % → {100 * mis1:.1f} %.{lv}")
    return Diagnosis(
        explained=best is not None, verdict=verdict, best=best, ranking=fits, nominal=nominal, before=before,
        after=after, mismatch_before=mis0, mismatch_after=mis1, augmented=augmented, chain_correction=chain,
        observation=obs, level_table=level_table, seconds=time.perf_counter() - t0,
        H_before=np.asarray(H0_full), H_after=None if H1_full is None else np.asarray(H1_full),
    )
