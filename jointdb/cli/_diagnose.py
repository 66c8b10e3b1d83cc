"""CLI: ``jointdb diagnose`` (model vs recordings) and ``jointdb diagnose-bench``.

Thin: the use case :func:`jointdb.usecases.diagnose_recordings` reads the files and diagnoses (the
numerics live in :mod:`jointdb.diagnose`); the
benchmark in :mod:`jointdb.diagnose_bench`; output goes through
:mod:`jointdb.cli._output`. Nothing is written unless the diagnosis succeeded.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated, Optional

import typer

from jointdb.errors import InputError


def _parse_map(text: str | None) -> dict[int, str]:
    if not text:
        return {}
    out = {}
    for item in text.split(","):
        if not item.strip():
            continue
        if "=" not in item:
            raise InputError(f"--map {text!r}: write node=point pairs like 1=tip,2=flute")
        node, name = item.split("=", 1)
        try:
            out[int(node.strip())] = name.strip()
        except ValueError:
            raise InputError(f"--map: {node.strip()!r} is not a node number") from None
    return out


def _parse_floats(text: str | None, option: str) -> list[float]:
    if not text:
        return []
    try:
        return [float(v) for v in text.replace(":", ",").split(",") if v.strip()]
    except ValueError:
        raise InputError(f"{option} {text!r}: expected comma-separated numbers") from None


def _write_augmented(result, nominal, out: Path) -> list[str]:
    """Write the augmented model(s) as JSON (one per level when they differ); the files written."""
    from jointdb.cli._output import message
    from jointdb.fe import model_to_dict

    written: list[str] = []
    if result.explained and result.augmented and any(a is not nominal for a in result.augmented):
        from jointdb.io._atomic import atomic_path

        targets = [out] if len(result.augmented) == 1 else \
            [out.with_name(f"{out.stem}-level{i + 1}{out.suffix}") for i in range(len(result.augmented))]
        for p, a in zip(targets, result.augmented):
            with atomic_path(p) as tmp:
                tmp.write_text(json.dumps(model_to_dict(a), indent=2) + "\n", encoding="utf-8")
            written.append(str(p))
    elif result.explained:
        message("the explanation is in the measurement chain; the model needs no change: --out not written")
    else:
        message("nothing to add to the model: --out not written")
    return written


def _render_diagnosis(result) -> None:
    """The verdict, the ranked explanations, the modes before, the per-level tables."""
    from jointdb.cli._output import emit

    emit(result.verdict)
    emit(result.table()[:8], title="ranked explanations (BIC; ΔBIC vs the nominal model)")
    modes = [{"mode": p.mode, "model Hz": round(p.model.freq_hz, 1), "recorded Hz": round(p.recorded.freq_hz, 1),
              "shift %": round(100 * p.shift, 2), "damping ×": round(p.damping_ratio, 2),
              "height dB": round(p.height_db, 1), "band mismatch %": round(100 * p.mismatch, 1),
              "DOFs showing it": ", ".join(p.dofs)} for p in result.before.pairs]
    if modes:
        emit(modes, title="modes: model vs recording (before)")
    if result.levels_data is not None and result.levels_data.tracks:
        emit("recorded modes per excitation level (local modal fit, ±1σ):\n" + result.levels_data.summary())
    if result.level_table:
        emit(result.level_table, title="amplitude-dependent joint per level")


def diagnose_cmd(
    model: Annotated[Path, typer.Argument(help="Nominal model file (jointdb beam model JSON).")],
    recordings: Annotated[list[Path], typer.Argument(help="Recorded FRFs (UFF58); several = several excitation levels.")],
    mapping: Annotated[Optional[str], typer.Option("--map", help="Recording node to model point, e.g. 1=tip,2=flute.")] = None,
    levels: Annotated[Optional[str], typer.Option("--levels", help="Excitation level of each recording, e.g. 2,10,50 (N).")] = None,
    band: Annotated[Optional[str], typer.Option("--band", help="Frequency band FMIN:FMAX in Hz.")] = None,
    out: Annotated[Optional[Path], typer.Option("--out", help="Write the augmented model (JSON).")] = None,
    plots: Annotated[Optional[Path], typer.Option("--plots", metavar="DIR", help="Directory for before/after PNGs.")] = None,
    no_combinations: Annotated[bool, typer.Option("--no-combinations", help="Fit single explanations only.")] = False,
    mask_nonfinite: Annotated[bool, typer.Option("--mask-nonfinite", help="Give NaN/Inf lines of the recordings zero weight (with a note) instead of refusing them.")] = False,
    as_json: Annotated[bool, typer.Option("--json", help="Machine-readable result on stdout.")] = False,
) -> None:
    """Locate where a model and recordings disagree, name the missing physics, refit.

    "Explained" (explained: true in --json) means one candidate physics (or a pair) lowers the BIC by at
    least 10, brings the mismatch over the whole recorded band down at least 1.5x, and has its key
    parameters identified (1 sigma at most 0.5x the value). Otherwise nothing is named and --out is not
    written; the verdict says what the recording shows and, for a change it cannot identify, which
    measurement would.

    Exit codes: 0 diagnosis done (explained or not: read "explained"); 2 bad input (a file, an option,
    NaN/Inf or all-zero values, a recording outside the model's frequency range); 3 a file not found;
    6 a numerical failure.

    Example: jointdb diagnose tool.json tap-tip.uff --map 1=tip,2=flute,3=shank --plots figs --out tool-fixed.json
    """
    from jointdb.cli._output import emit, message
    from jointdb.usecases import diagnose_recordings

    if out is not None and out.suffix.lower() != ".json":
        raise InputError(f"--out {out}: the augmented model is written as JSON; use a .json name")
    if out is not None and not out.parent.exists():
        raise InputError(f"--out {out}: directory {out.parent} does not exist")
    if plots is not None and plots.exists() and not plots.is_dir():
        raise InputError(f"--plots {plots}: exists and is not a directory")
    b = _parse_floats(band, "--band")
    if band and len(b) != 2:
        raise InputError(f"--band {band!r}: write FMIN:FMAX, e.g. 100:5000")
    result, nominal = diagnose_recordings(model, recordings, mapping=_parse_map(mapping),
                                          levels=_parse_floats(levels, "--levels"), band=b,
                                          combinations=not no_combinations, mask_nonfinite=mask_nonfinite,
                                          say=message)
    for note in result.observation.notes:
        message(f"note: {note}")
    written = _write_augmented(result, nominal, out) if out is not None else []
    if plots is not None:
        from jointdb.plots._diagnose import plot_backbone, plot_diagnosis

        plots.mkdir(parents=True, exist_ok=True)
        written += plot_diagnosis(result, plots)
        if len(result.observation.levels) >= 2 and result.levels_data is not None and result.levels_data.tracks:
            written.append(str(plot_backbone(result.levels_data, plots / "backbone.png", result.levels_model)))
    if written:
        message(f"wrote {', '.join(written)}")
    if as_json:
        emit(result.to_dict() | {"input_notes": list(result.observation.notes)}, as_json=True)
        return
    _render_diagnosis(result)


def _run_cases(jobs: list, t0: float) -> list:
    """Generate and diagnose each ``(effect, seed)``: a progress bar on a terminal, one line per case
    when piped or logged."""
    import sys
    import time

    from jointdb.cli._output import message, progress, progress_line
    from jointdb.diagnose_bench import generate_case, run_case, single_blas_thread

    results = []
    with single_blas_thread():
        if sys.stderr.isatty():
            for e, s in progress(jobs, total=len(jobs), description="diagnosing"):
                results.append(run_case(generate_case(e, s)))
        else:
            # piped or logged: one line per case, so a long run is visibly alive
            for k, (e, s) in enumerate(jobs, 1):
                r = run_case(generate_case(e, s))
                results.append(r)
                where = "" if r.placed is None else (" placed" if r.placed else " NOT placed")
                message(f"{progress_line('diagnose-bench', k, len(jobs), time.perf_counter() - t0)} — "
                        f"{r.case}: named {r.named}{where}, improvement {r.improvement:.2f}x, {r.seconds:.1f} s")
    return results


def _render_bench(bench, per: list, rows: list, cols: list, m) -> None:
    """Per effect, the confusion matrix and the summary lines, for people."""
    import statistics

    from jointdb.cli._output import emit

    cols_show = ["effect", "cases", "named_first_pct", "top3_pct", "median_improvement",
                 "improved_3x_when_named_pct", "median_mismatch_before_pct", "median_mismatch_after_pct",
                 "median_seconds"]
    if any("placed_pct" in r for r in per):
        cols_show.insert(3, "placed_pct")
    emit(per, columns=cols_show, title="diagnosis of concealed effects, per hidden effect")
    emit([{"hidden \\ named first": r, **{c: int(v) for c, v in zip(cols, row)}} for r, row in zip(rows, m)],
         title="confusion matrix (rows: hidden effect; columns: family named first)")
    extra = {}
    for row in per:
        e = row["effect"]
        if "false_alarm_pct" in row:
            extra[f"{e}: false-alarm rate on null cases %"] = row["false_alarm_pct"]
        if "improves_every_level_pct" in row:
            extra[f"{e}: fit improves at every level %"] = row["improves_every_level_pct"]
            if "affected_mode_1_pct" in row:
                extra[f"{e}: mode 1 located as affected %"] = row["affected_mode_1_pct"]
    extra["median seconds per case"] = round(statistics.median(c.seconds for c in bench.cases), 1)
    extra["total time s"] = round(bench.seconds, 1)
    emit(extra, title="summary")


def diagnose_bench_cmd(
    cases: Annotated[int, typer.Option("--cases", help="Seeded cases per effect.")] = 20,
    seed: Annotated[int, typer.Option("--seed", help="First seed (seeds below 1000 are kept for development; "
                                                     "report results on seeds >= 1000).")] = 1000,
    effects: Annotated[Optional[str], typer.Option("--effects", help="Comma-separated subset of effects.")] = None,
    write_case: Annotated[Optional[Path], typer.Option("--write-case", help="Only write one case (model JSON + UFF58 recordings) of each effect to this directory.")] = None,
    out: Annotated[Optional[Path], typer.Option("--out", help="Write one row per case to .csv, .json or .h5.")] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Machine-readable result on stdout.")] = False,
) -> None:
    """Run the concealed-effect benchmark: generate, diagnose, score per effect.

    Progress: a bar on a terminal; one line per case (count, elapsed, ETA) when piped or logged.

    Example: jointdb diagnose-bench --cases 20 --seed 1000
    """
    from jointdb.cli._output import emit, message, write_rows
    from jointdb.cli._options import check_out
    from jointdb.diagnose_bench import EFFECTS

    check_out(out, (".csv", ".json", ".h5", ".hdf5"))

    chosen = EFFECTS if not effects else tuple(e.strip() for e in effects.split(",") if e.strip())
    bad = [e for e in chosen if e not in EFFECTS]
    if bad:
        raise InputError(f"--effects: unknown {', '.join(bad)}; known: {', '.join(EFFECTS)}")
    if cases < 1:
        raise InputError("--cases must be >= 1")
    if write_case is not None:
        _write_cases(write_case, chosen, seed)
        return
    import time

    from jointdb.diagnose_bench import BenchResult

    t0 = time.perf_counter()
    results = _run_cases([(e, seed + k) for e in chosen for k in range(cases)], t0)
    bench = BenchResult(results, time.perf_counter() - t0)
    rows, cols, m = bench.confusion()
    per = bench.per_effect()
    if out is not None:
        write_rows(out, [{"case": c.case, "effect": c.effect, "named": c.named, "explanation": " + ".join(c.names),
                          "top3": ", ".join(c.top3), "improvement": c.improvement, "seconds_s": c.seconds,
                          "position_m": c.position, "placed": c.placed} for c in bench.cases],
                   kind="diagnose_bench", meta={"seed": seed, "cases_per_effect": cases, "per_effect": per})
        message(f"wrote {out}")
    if as_json:
        emit({"per_effect": per, "confusion": {"rows": rows, "columns": cols, "counts": m},
              "total_seconds": bench.seconds,
              "cases": [{"case": c.case, "effect": c.effect, "named": c.named, "explanation": list(c.names),
                         "top3": list(c.top3), "improvement": c.improvement, "seconds": c.seconds,
                         "position_m": c.position, "placed": c.placed}
                        for c in bench.cases]}, as_json=True)
        return
    _render_bench(bench, per, rows, cols, m)
    message(f"{len(results)} cases in {bench.seconds:.1f} s")


def register(app: typer.Typer) -> None:
    """Add ``diagnose`` and ``diagnose-bench`` to the app."""

    app.command("diagnose")(diagnose_cmd)
    app.command("diagnose-bench")(diagnose_bench_cmd)


def _write_cases(directory: Path, effects, seed: int) -> None:
    from jointdb.cli._output import message
    from jointdb.diagnose_bench import generate_case
    from jointdb.io import write_uff58

    directory.mkdir(parents=True, exist_ok=True)
    for e in effects:
        case = generate_case(e, seed)
        base = directory / case.name
        (base.with_suffix(".json")).write_text(json.dumps(case.model, indent=2) + "\n", encoding="utf-8")
        for i, r in enumerate(case.recordings):
            suffix = f"-level{i + 1}" if len(case.recordings) > 1 else ""
            write_uff58(directory / f"{case.name}{suffix}.uff", r.frf)
        (directory / f"{case.name}.truth.json").write_text(json.dumps(case.truth, indent=2, default=float) + "\n",
                                                          encoding="utf-8")
        message(f"wrote {case.name}: model, {len(case.recordings)} recording(s), truth")
