"""CLI: ``jointdb optimize SPEC`` — the stack and cut of highest stable removal rate (thin: use case + render)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Optional

import typer


def _people_row(rank: int, r) -> dict:
    b, c = r.best, r.candidate
    return {"rank": rank, "holder": c.holder, "overhang_mm": c.overhang_m * 1e3, "torque_nm": c.torque_nm,
            "drawbar_kn": c.drawbar_n / 1e3, "speed_rpm": round(b["spindle_speed_rpm"]), "depth_mm": b["depth_m"] * 1e3,
            "rate_cm3_min": b["removal_rate_m3_s"] * 6e7, "binding": b["binding"],
            "limit_by": ("ZOA+band+SD" if b.get("band_limit_m") is not None else "ZOA+SD") if "sd_limit_m" in b else "ZOA",
            "joints": f"{r.joints.get('tool-holder')}, {r.joints.get('holder-spindle')}"}


def _write_outputs(out: Path, problem, outcome) -> list[Path]:
    """ranking.csv, result.json and the figures in ``out``."""
    from jointdb.cli._output import write_rows
    from jointdb.io._jsonable import to_jsonable
    from jointdb.io._atomic import atomic_path
    from jointdb.usecases._optimize_run import outcome_json
    from jointdb.plots._optimize import plot_pareto, plot_rate_vs_overhang
    from jointdb.plots._lobes import plot_lobes
    from jointdb.usecases._optimize import pareto_front
    from jointdb.usecases._optimize_run import rate_by_overhang

    out.mkdir(parents=True, exist_ok=True)
    rows = [r.row() for r in outcome.ranked]
    files = [out / "ranking.csv"]
    write_rows(files[0], rows, kind="optimize")
    best = outcome.ranked[0]
    joints = "; ".join(f"{k}: {v}" for k, v in best.joints.items())
    files.append(plot_lobes(best.lobes, out / "best-lobes.png", band=outcome.best_band,
                            title=f"Best stack: {best.candidate.holder}, overhang {best.candidate.overhang_m * 1e3:g} mm",
                            flute_length_m=problem.spec.tool.flute_length_m, joints=joints or None))
    files.append(plot_rate_vs_overhang(rate_by_overhang(outcome.ranked), out / "rate-vs-overhang.png"))
    b = best.best
    zoa = b.get("zoa_limit_m") or float("nan")
    point = (1 - b["depth_m"] / zoa, b["removal_rate_m3_s"]) if 0 < zoa < float("inf") else None
    by = "band's 5 % edge, SD" if b.get("band_limit_m") is not None else "SD"
    files.append(plot_pareto(*pareto_front(problem, outcome.ranked), out / "pareto-rate-vs-margin.png", point=point,
                             point_label=f"recommended (margin {b['margin']:.0%}, {by}; binding: {b['binding']})"))
    if outcome.checks:
        from jointdb.plots._simulate import plot_simulation

        for name, sim in zip(("recommended", "above-limit"), outcome.checks):
            files.append(plot_simulation(sim, out / f"simulate-{name}.png"))
    import json

    with atomic_path(out / "result.json") as tmp:
        Path(tmp).write_text(json.dumps(to_jsonable(outcome_json(problem, outcome)), indent=1))
    files.append(out / "result.json")
    return files


def optimize(
    spec_file: Annotated[Path, typer.Argument(help="Optimize spec (JSON, format jointdb-optimize/1).")],
    db: Annotated[Optional[str], typer.Option("--db", help="Joint database URL or SQLite path "
                                              "(default: $JOINTDB_URL or the per-user database).")] = None,
    top: Annotated[int, typer.Option("--top", help="Rows of the ranking to print.")] = 10,
    no_simulate: Annotated[bool, typer.Option("--no-simulate", help="Skip the time-domain check of the best stack.")] = False,
    out: Annotated[Optional[Path], typer.Option("--out", help="Directory for ranking.csv, result.json and the figures.")] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Machine-readable output (SI units).")] = False,
    scheduler: Annotated[str, typer.Option("--scheduler", help="Where candidates are evaluated: local (a Dask local "
                                           "cluster), in-process, or a Dask scheduler ADDRESS (tcp://host:8786).")] = "local",
    workers: Annotated[int, typer.Option("--workers", help="Workers of the local cluster.")] = 2,
) -> None:
    """Find the holder, overhang, torque, drawbar force, speed and depth of highest stable removal rate.

    Candidates are every allowed holder (inline, a catalogued part, or a family's catalogued holders) ×
    overhang × catalogued clamping torque × catalogued drawbar force in the spec's ranges; the spindle is
    the template's or the machine's catalogued part. Each tip is predicted (both planes), its zero-order
    lobes computed, and the best cut obeys stability (less the margin, or at the lobe band's lower edge),
    flute length, spindle power (flat or a curve over speed) and torque. The best five are confirmed by
    semi-discretization; the best stack is simulated in the time domain at the recommended cut and at
    1.1× its limit.

    Example: jointdb optimize fixtures/optimize/optimize-catalogue.json --db demo-out/joints.sqlite --out opt
    """
    from jointdb.cli._output import emit, message, progress_line
    from jointdb.cli._target import check_db_target
    from jointdb.errors import InputError
    from jointdb.store import Repository
    from jointdb.usecases import load_problem, optimize_stack
    from jointdb.usecases._optimize_run import outcome_json

    if not 1 <= workers <= 256:
        raise InputError(f"--workers must be between 1 and 256, got {workers}")
    if not 1 <= top <= 100_000:
        raise InputError(f"--top must be between 1 and 100000, got {top}")
    check_db_target(db)
    import time

    start = time.monotonic()

    def report(done: int, total: int, what: str) -> None:
        message(progress_line(f"candidates ({what})", done, total, time.monotonic() - start))

    repo = Repository(db)
    try:
        problem = load_problem(spec_file, repo)
        for line in problem.notes:
            message(line)
        outcome = optimize_stack(problem, repo, progress=report, simulate=not no_simulate, scheduler=scheduler,
                                 n_workers=workers)
    finally:
        repo.close()
    for line in outcome.notes:
        message(line)
    if out is not None:
        for f in _write_outputs(out, problem, outcome):
            message(f"wrote {f}")
    if as_json:
        emit(outcome_json(problem, outcome), as_json=True)
        return
    b = outcome.ranked[0]
    message(f"recommended: holder {b.candidate.holder}, overhang {b.candidate.overhang_m * 1e3:g} mm, clamping torque "
            f"{b.candidate.torque_nm:g} N·m, drawbar {b.candidate.drawbar_n / 1e3:g} kN, "
            f"{b.best['spindle_speed_rpm']:.0f} rpm, depth {b.best['depth_m'] * 1e3:.3g} mm "
            f"({b.best['removal_rate_m3_s'] * 6e7:.3g} cm³/min, bound by {b.best['binding']})")
    emit([_people_row(i + 1, r) for i, r in enumerate(outcome.ranked[:top])],
         title=f"Best {min(top, len(outcome.ranked))} of {len(outcome.ranked)} candidate stacks (highest stable removal rate)")


def register(app: typer.Typer) -> None:
    """Add ``optimize`` to the app."""
    app.command("optimize")(optimize)
