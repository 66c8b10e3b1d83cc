"""``optimize_stack``: enumerate, evaluate and rank the candidates, confirm the best by semi-discretization,
check the best in the time domain (the use case the CLI and a job queue call)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from jointdb.usecases._optimize import (
    CandidateResult,
    OptimizeProblem,
    Progress,
    best_cut,
    enumerate_candidates,
    rank,
)
from jointdb.usecases._optimize_eval import evaluate_candidates


@dataclass(frozen=True, eq=False)
class OptimizeOutcome:
    """Ranked candidates (best first), and the time-domain check of the best one (``checks``: at the
    recommended cut and at 1.1× its stability limit, each a :class:`jointdb.stability.SimulationResult`)."""

    ranked: list
    checks: tuple = ()
    notes: tuple = ()


def confirm_with_sd(problem: OptimizeProblem, results: Sequence[CandidateResult], n_intervals: int = 40
                    ) -> list[CandidateResult]:
    """Semi-discretization at each result's best speed: the depth becomes the smaller of the zero-order and
    SD limits (less the margin) under the same other limits; ``best`` gains ``sd_limit_m``.

    The zero-order approximation can overrate the pockets of few-tooth, partial-immersion cuts; SD on the
    tip's fitted modes is the check (docs/theory.md §5).
    """
    from dataclasses import replace

    from jointdb.modal import fit_tool_tip
    from jointdb.stability import milling_lobes_sd

    out = []
    for r in results:
        n = r.best["spindle_speed_rpm"]
        model, _ = fit_tool_tip(r.tip)
        sd = float(milling_lobes_sd(model, problem.cut, [n], n_intervals=n_intervals).depth_m[0])
        lobes = r.lobes
        i = int(np.argmin(np.abs(lobes.spindle_speed_rpm - n)))
        depth = np.array(lobes.depth_m, dtype=float)
        depth[i] = min(depth[i], sd) if np.isfinite(depth[i]) else sd
        one = replace(lobes, spindle_speed_rpm=lobes.spindle_speed_rpm[i:i + 1], depth_m=depth[i:i + 1],
                      chatter_freq_hz=lobes.chatter_freq_hz[i:i + 1], lobe=lobes.lobe[i:i + 1], kind=lobes.kind[i:i + 1])
        best = {**best_cut(problem, one), "zoa_limit_m": float(lobes.depth_m[i]), "sd_limit_m": sd}
        out.append(replace(r, best=best))
    return out


def optimize_stack(problem: OptimizeProblem, repo, *, progress: Progress | None = None, simulate: bool = True,
                   confirm: int = 5, revolutions: int = 120, scheduler: str | None = "local",
                   n_workers: int | None = None) -> OptimizeOutcome:
    """Enumerate, evaluate (zero-order lobes) and rank the candidates; confirm the top few by
    semi-discretization at their best speed and re-rank them; check the best one in the time domain.

    Parameters
    ----------
    problem
        From :func:`load_problem`.
    repo
        The joint store.
    progress
        ``progress(done, total, message)``.
    simulate
        Run :func:`jointdb.usecases.simulate_tip` on the best candidate at its recommended cut and at
        1.1× its (confirmed) stability limit at that speed.
    confirm
        How many of the best candidates SD confirms (0: none).
    scheduler, n_workers
        Where the candidates are evaluated (see :func:`jointdb.usecases._optimize_eval.evaluate_candidates`).
    revolutions
        Simulated revolutions.

    Returns
    -------
    OptimizeOutcome
    """
    candidates = enumerate_candidates(problem, repo)
    ranked = rank(evaluate_candidates(problem, candidates, repo, progress, scheduler=scheduler, n_workers=n_workers))
    # the best few again with their tip FRFs (the search keeps none: 10 000 tips would not fit in memory)
    keep = max(confirm, 1)
    ranked = evaluate_candidates(problem, [r.candidate for r in ranked[:keep]], repo, keep_tips=True) + ranked[keep:]
    notes = []
    if confirm > 0:
        top = rank(confirm_with_sd(problem, ranked[:confirm]))
        ranked = top + ranked[confirm:]
        notes.append(f"the best {len(top)} confirmed by semi-discretization at their best speed (depth = the "
                     "smaller of the ZOA and SD limits)")
    checks: tuple = ()
    best = ranked[0]
    limit = best.best.get("sd_limit_m", best.best["stability_limit_m"])
    if simulate and best.best["removal_rate_m3_s"] > 0 and math.isfinite(limit):
        from jointdb.usecases._simulate import simulate_tip

        n, a = best.best["spindle_speed_rpm"], best.best["depth_m"]
        sim = simulate_tip(best.tip, problem.cut, [n, n], [a, 1.1 * limit], revolutions=revolutions,
                           feed_per_tooth_m=problem.spec.cut.feed_per_tooth_m)
        checks = sim.results
        verdicts = ["chatter" if r.chatter else "stable" for r in checks]
        notes.append(f"time domain at {n:.0f} rpm: recommended {a * 1e3:.3g} mm {verdicts[0]}; "
                     f"1.1× the limit ({1.1 * limit * 1e3:.3g} mm) {verdicts[1]}")
    return OptimizeOutcome(ranked, checks, tuple(notes))
