"""Run the diagnosis on generated cases and score it (per effect and overall)."""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from jointdb.diagnose_bench._cases import EFFECTS, BenchCase, generate_case

__all__ = ["CaseResult", "BenchResult", "run_case", "run_benchmark"]


@dataclass
class CaseResult:
    case: str
    effect: str
    named: str               # family of the selected explanation's first part ("none" if nothing)
    names: tuple             # full name of the selected explanation
    top3: tuple              # families of the first three ranked explanations
    improvement: float       # mismatch before / after (all lines)
    mismatch_before: float
    mismatch_after: float
    seconds: float
    level_improvements: tuple = ()
    affected_mode: int | None = None
    fitted: dict = field(default_factory=dict)
    sigmas: dict = field(default_factory=dict)   # reported 1-sigma of the fitted values (SI)
    truth: dict = field(default_factory=dict)
    top_improvement: float = 1.0   # nominal / best-ranked mismatch on the fit lines, accepted or not

    @property
    def first(self) -> bool:
        return self.named == self.effect

    @property
    def in_top3(self) -> bool:
        return self.effect == "none" and self.named == "none" or self.effect in self.top3


@dataclass
class BenchResult:
    cases: list
    seconds: float

    def per_effect(self) -> list[dict]:
        rows = []
        for eff in dict.fromkeys(c.effect for c in self.cases):
            cs = [c for c in self.cases if c.effect == eff]
            good = [c for c in cs if c.first]
            row = {
                "effect": eff, "cases": len(cs),
                "named_first_pct": round(100 * len(good) / len(cs), 1),
                "top3_pct": round(100 * sum(c.in_top3 for c in cs) / len(cs), 1),
                "median_improvement": round(float(np.median([c.improvement for c in cs])), 2),
                "median_improvement_when_named": round(float(np.median([c.improvement for c in good])), 2)
                if good else None,
                "improved_3x_when_named_pct": round(100 * sum(c.improvement >= 3 for c in good) / len(good), 1)
                if good else None,
                "median_mismatch_before_pct": round(100 * float(np.median([c.mismatch_before for c in cs])), 2),
                "median_mismatch_after_pct": round(100 * float(np.median([c.mismatch_after for c in cs])), 2),
                "median_seconds": round(float(np.median([c.seconds for c in cs])), 2),
                "second_effect_added_pct": round(100 * sum(any(" + " in n for n in c.names) for c in cs) / len(cs), 1),
            }
            if eff == "none":
                row["false_alarm_pct"] = round(100 * sum(c.named != "none" for c in cs) / len(cs), 1)
                row["max_rejected_improvement"] = round(max(c.top_improvement for c in cs), 3)
            if eff == "softening_joint":
                row["improves_every_level_pct"] = round(100 * sum(
                    bool(c.level_improvements) and min(c.level_improvements) > 1.0 for c in cs) / len(cs), 1)
                row["affected_mode_1_pct"] = round(100 * sum(c.affected_mode == 1 for c in cs) / len(cs), 1)
            rows.append(row)
        return rows

    def confusion(self) -> tuple[list[str], list[str], np.ndarray]:
        """Rows: hidden effect; columns: family named first (counts)."""
        rows = list(dict.fromkeys(c.effect for c in self.cases))
        cols = list(dict.fromkeys([*rows, *sorted({c.named for c in self.cases} - set(rows))]))
        m = np.zeros((len(rows), len(cols)), dtype=int)
        for c in self.cases:
            m[rows.index(c.effect), cols.index(c.named)] += 1
        return rows, cols, m


def run_case(case: BenchCase) -> CaseResult:
    """Diagnose one generated case and score it."""
    from jointdb.diagnose import Measurement, diagnose
    from jointdb.fe import model_from_dict

    model = model_from_dict(case.model)
    ms = [Measurement(r.frf, r.coherence, r.level_n, label=f"{case.name}/{i}") for i, r in enumerate(case.recordings)]
    t0 = time.perf_counter()
    d = diagnose(model, ms)
    dt = time.perf_counter() - t0
    best = d.best

    def first_family(f):
        return f.family.split(" + ")[0]

    named = first_family(best) if best is not None else "none"
    top3 = tuple(first_family(f) for f in d.ranking[:3]) if best is not None else ()
    lv = ()
    if best is not None:
        lv = tuple(float(a / b) for a, b in zip(d.nominal.mismatch_levels, best.mismatch_levels))
    return CaseResult(
        case=case.name, effect=case.effects[0], named=named,
        names=(best.name,) if best is not None else (), top3=top3,
        improvement=d.mismatch_before / d.mismatch_after if d.mismatch_after > 0 else float("inf"),
        mismatch_before=d.mismatch_before, mismatch_after=d.mismatch_after, seconds=dt,
        level_improvements=lv, affected_mode=d.before.affected_mode,
        fitted={} if best is None else dict(best.values), truth=case.truth,
        sigmas={} if best is None else dict(best.sigmas),
        top_improvement=(d.nominal.mismatch / d.ranking[0].mismatch) if d.ranking else 1.0,
    )


def run_benchmark(n_per_effect: int = 20, seed: int = 0, effects: Sequence[str] = EFFECTS,
                  progress: Callable | None = None) -> BenchResult:
    """Generate ``n_per_effect`` cases per effect (seeds ``seed…``) and diagnose them all."""
    t0 = time.perf_counter()
    jobs = [(e, seed + k) for e in effects for k in range(n_per_effect)]
    it = progress(jobs) if progress is not None else jobs
    results = [run_case(generate_case(e, s)) for e, s in it]
    return BenchResult(results, time.perf_counter() - t0)
