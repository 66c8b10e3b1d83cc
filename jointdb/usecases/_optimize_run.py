"""``optimize_stack``: enumerate, evaluate and rank the candidates, confirm the best by semi-discretization,
check the best in the time domain (the use case the CLI and a job queue call)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

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
    """Ranked candidates (best first), and the time-domain check of the best one.

    Parameters
    ----------
    ranked
        Every candidate's result (``CandidateResult``: candidate, lobes, ``best`` cut, joints), highest
        removal rate [m³/s] first; those confirmed by semi-discretization carry ``best["sd_limit_m"]``.
    checks
        The time-domain check of the best candidate, each a :class:`jointdb.stability.SimulationResult`:
        at the recommended cut and at 1.1× its stability limit at that speed; empty when not simulated
        (``simulate=False``, no stable cut, or no finite limit).
    notes
        Messages for the user (how many were confirmed, the time-domain verdicts).
    best_band
        With ``margin_from: band``: the best candidate's :class:`jointdb.stability.LobeBand` (5/50/95 % of
        its zero-order limit per speed), else None.
    """

    ranked: list
    checks: tuple = ()
    notes: tuple = ()
    best_band: Any = None


def lobe_band_of(problem: OptimizeProblem, result: CandidateResult, repo):
    """A candidate's zero-order lobe band on its lobes' speeds, from the uncertainty of its joints
    (every term of :data:`jointdb.usecases._stack_band.TERMS`, as ``jointdb predict`` samples it); None when its
    joints carry no uncertainty.

    Parameters
    ----------
    problem
        The optimize problem.
    result
        The candidate's result (its candidate and lobes).
    repo
        The joint store.

    Returns
    -------
    jointdb.stability.LobeBand or None
        ``depth_m`` of shape ``(3, n_speeds)``: 5/50/95 % [m], NaN where no sample has a finite limit.
    """
    from jointdb.stack import prediction_grid
    from jointdb.usecases._demo_band import journey_bands
    from jointdb.usecases._optimize import candidate_stack
    from jointdb.usecases._stack import resolve_joints

    spec = candidate_stack(problem, result.candidate)
    _, make, _ = journey_bands(spec, resolve_joints(spec, repo), prediction_grid(spec), lambda _: None)
    return None if make is None else make(problem.cut, result.lobes.spindle_speed_rpm)


def _band_limited(problem: OptimizeProblem, r: CandidateResult, repo) -> CandidateResult:
    """``r`` with its best cut under the smaller of its nominal limit and the band's lower edge."""
    from dataclasses import replace

    band = lobe_band_of(problem, r, repo)
    if band is None:
        return replace(r, best={**r.best, "band_limit_m": None})
    p05 = np.asarray(band.depth_m[0], dtype=float)
    nominal = np.asarray(r.lobes.depth_m, dtype=float)
    stab = np.where(np.isnan(p05), nominal, np.minimum(nominal, p05))
    best = best_cut(problem, r.lobes, stability_m=stab)
    i = int(np.argmin(np.abs(r.lobes.spindle_speed_rpm - best["spindle_speed_rpm"])))
    return replace(r, best={**best, "stability_limit_m": float(stab[i]), "band_limit_m": float(p05[i])})


def confirm_with_sd(problem: OptimizeProblem, results: Sequence[CandidateResult], n_intervals: int = 40
                    ) -> list[CandidateResult]:
    """Semi-discretization at each result's best speed: the depth becomes the smaller of the limit used so
    far (zero-order, or the band's lower edge when ``best`` holds ``band_limit_m``) and the SD limit (less the
    margin) under the same other limits; ``best`` gains ``zoa_limit_m`` and ``sd_limit_m``.

    The zero-order approximation can overrate the pockets of few-tooth, partial-immersion cuts; SD on the
    tip's fitted modes is the check (docs/theory.md §5). It is of the nominal tip, not of the band.
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
        used = r.best["stability_limit_m"] if "band_limit_m" in r.best else float(lobes.depth_m[i])
        limit = min(used, sd) if np.isfinite(used) else sd
        one = replace(lobes, spindle_speed_rpm=lobes.spindle_speed_rpm[i:i + 1], depth_m=np.array([limit]),
                      chatter_freq_hz=lobes.chatter_freq_hz[i:i + 1], lobe=lobes.lobe[i:i + 1], kind=lobes.kind[i:i + 1])
        best = {**best_cut(problem, one), "zoa_limit_m": float(lobes.depth_m[i]), "sd_limit_m": sd}
        if "band_limit_m" in r.best:
            best["band_limit_m"] = r.best["band_limit_m"]
        out.append(replace(r, best=best))
    return out


def _confirm_top(problem: OptimizeProblem, ranked: list, repo, confirm: int, max_confirm: int,
                 progress: Progress | None = None):
    """Confirm by SD until the best ``confirm`` of the ranking are all confirmed (or ``max_confirm`` are spent).

    SD (and, with ``margin_from: band``, the band's lower edge, taken no higher than the nominal limit) only
    lowers a candidate's rate, so once the best ``confirm`` are confirmed no unconfirmed one below them can
    overtake them. Returns the re-ranked list and notes.
    """
    done, notes = 0, []
    while confirm > 0 and done < max_confirm:
        todo = [i for i, r in enumerate(ranked[:confirm]) if "sd_limit_m" not in r.best][: max_confirm - done]
        if not todo:
            break
        # their tip FRFs again (the search keeps none: 10 000 tips would not fit in memory)
        fresh = evaluate_candidates(problem, [ranked[i].candidate for i in todo], repo, keep_tips=True)
        if problem.spec.objective.margin_from == "band":
            fresh = [_band_limited(problem, r, repo) for r in fresh]
        for i, r in zip(todo, confirm_with_sd(problem, fresh)):
            ranked[i] = r
        done += len(todo)
        ranked = rank(ranked)
        if progress:  # the search is done; a job may still be cancelled between these checks
            progress(len(ranked), len(ranked), f"{done} of the best confirmed by semi-discretization")
    if confirm > 0:
        band = problem.spec.objective.margin_from == "band"
        note = (f"the best {confirm} confirmed by semi-discretization at their best speed (depth = the smaller of "
                f"the ZOA{', the lobe band’s 5 % edge' if band else ''} and SD limits; {done} candidates checked)")
        if band and any(r.best.get("band_limit_m", 0.0) is None for r in ranked[:confirm]):
            note += "; some joints carry no uncertainty: no band for those, their nominal limit is used"
        if not all("sd_limit_m" in r.best for r in ranked[:confirm]):
            note += f"; not settled after {max_confirm} checks: unconfirmed candidates (ZOA only) remain among them"
        notes.append(note)
    if ranked[0].tip is None:  # the best is unconfirmed (confirm exhausted): its tip for the time-domain check
        ranked[0] = evaluate_candidates(problem, [ranked[0].candidate], repo, keep_tips=True)[0]
    return ranked, notes


def optimize_stack(problem: OptimizeProblem, repo, *, progress: Progress | None = None, simulate: bool = True,
                   confirm: int = 5, max_confirm: int = 15, revolutions: int = 120,
                   scheduler: str | None = "local", n_workers: int | None = None) -> OptimizeOutcome:
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
    confirm, max_confirm
        How many of the best candidates must be SD-confirmed (0: none), and at most how many
        confirmations to spend getting there (see :func:`_confirm_top`).
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
    ranked, notes = _confirm_top(problem, ranked, repo, confirm, max_confirm, progress)
    if confirm == 0 and problem.spec.objective.margin_from == "band":
        notes.append("margin_from band: no candidate was confirmed (confirm=0), so no band was applied")
    checks: tuple = ()
    best = ranked[0]
    best_band = None
    if problem.spec.objective.margin_from == "band" and best.best.get("band_limit_m") is not None:
        best_band = lobe_band_of(problem, best, repo)
    limit = best.best.get("sd_limit_m", best.best["stability_limit_m"])
    if simulate and best.best["removal_rate_m3_s"] > 0 and math.isfinite(limit):
        from jointdb.usecases._simulate import simulate_tip

        if progress:
            progress(len(ranked), len(ranked), "time-domain check of the best")
        n, a = best.best["spindle_speed_rpm"], best.best["depth_m"]
        sim = simulate_tip(best.tip, problem.cut, [n, n], [a, 1.1 * limit], revolutions=revolutions,
                           feed_per_tooth_m=problem.spec.cut.feed_per_tooth_m)
        checks = sim.results
        verdicts = ["chatter" if r.chatter else "stable" for r in checks]
        notes.append(f"time domain at {n:.0f} rpm: recommended {a * 1e3:.3g} mm {verdicts[0]}; "
                     f"1.1× the limit ({1.1 * limit * 1e3:.3g} mm) {verdicts[1]}")
    return OptimizeOutcome(ranked, checks, tuple(notes), best_band)


def rate_by_overhang(results: Sequence[CandidateResult]) -> dict[str, tuple[list[float], list[float]]]:
    """Per holder, the best removal rate [m³/s] at each overhang [m] (best over torques and drawbar forces).

    Parameters
    ----------
    results
        Candidate results (any order).

    Returns
    -------
    dict
        ``holder -> (overhangs, rates)``, overhangs ascending.
    """
    best: dict[str, dict[float, float]] = {}
    for r in results:
        row = best.setdefault(r.candidate.holder, {})
        g = r.candidate.overhang_m
        row[g] = max(row.get(g, 0.0), r.best["removal_rate_m3_s"])
    return {h: (sorted(row), [row[g] for g in sorted(row)]) for h, row in sorted(best.items())}


def outcome_json(problem: OptimizeProblem, outcome: OptimizeOutcome, top: int | None = None) -> dict:
    """The result of an optimize run as JSON-ready values (SI units): what ``jointdb optimize --json``
    prints and an optimize job returns.

    Parameters
    ----------
    problem
        The problem that was solved (its notes: which holders a family selected).
    outcome
        From :func:`optimize_stack`.
    top
        Rows of the ranking to include (None: all).

    Returns
    -------
    dict
        ``candidates`` (how many), ``ranked`` (rows, best first: candidate, best cut, binding constraint,
        joints), ``checks`` (time-domain summaries), ``notes``, ``parts`` (the catalogued parts of the
        template the candidates share: spindle, tool, and the holder when the spec allows no others),
        ``holder_parts`` (the catalogued holders allowed, ``name@version``), ``best_lobes`` (speeds [rpm], limiting
        depth [m] of the best candidate's zero-order lobes), ``rate_vs_overhang`` (per holder) and
        ``pareto`` (the best rate against the margin held back) — the data of the three figures; non-finite
        numbers as null.
    """
    from jointdb.io._jsonable import to_jsonable
    from jointdb.usecases._optimize import pareto_front

    rows = outcome.ranked if top is None else outcome.ranked[:top]
    best = outcome.ranked[0]
    margins, rates = pareto_front(problem, outcome.ranked)
    return to_jsonable({"candidates": len(outcome.ranked), "ranked": [r.row() for r in rows],
            "checks": [s.summary() for s in outcome.checks], "notes": [*problem.notes, *outcome.notes],
            "parts": [p for p in problem.template.parts if not (problem.spec.holders and p.get("slot") == "holder")],
            "holder_parts": [h.part for h in problem.holders if h.part],
            "best_lobes": {"spindle_speed_rpm": np.asarray(best.lobes.spindle_speed_rpm).tolist(),
                           "depth_m": np.asarray(best.lobes.depth_m, float),
                           "band": None if outcome.best_band is None else outcome.best_band.to_json()},
            "rate_vs_overhang": {h: {"overhang_m": g, "removal_rate_m3_s": q}
                                 for h, (g, q) in rate_by_overhang(outcome.ranked).items()},
            "pareto": {"margin": margins, "removal_rate_m3_s": rates}})
