"""CLI: ``jointdb predict STACK.json`` — tool-tip FRF of a new stack with joints from the database.

Thin: :func:`jointdb.usecases.load_stack` / :func:`jointdb.usecases.predict_stack` do the
work; this module parses options, writes the requested files and renders.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Optional

import typer

from jointdb.cli._options import LegacyPlotOpt, PlotsOpt, plot_file, plots_dir


def _frequency_override(spec, fmin, fmax, df):
    """The prediction's lines when --fmin/--fmax/--df override the stack file's grid, else None."""
    from jointdb.schemas._limits import check_lines
    from jointdb.errors import InputError
    from jointdb.stack import FrequencyGrid, prediction_grid

    if fmin is None and fmax is None and df is None:
        return None
    base = spec.frequency or FrequencyGrid()
    grid = FrequencyGrid(fmin if fmin is not None else base.fmin, fmax if fmax is not None else base.fmax,
                         df if df is not None else base.step)
    if not (math.isfinite(grid.fmin) and math.isfinite(grid.fmax) and math.isfinite(grid.step)) or \
            grid.fmin <= 0 or grid.fmax <= grid.fmin or grid.step <= 0:
        raise InputError(f"--fmin/--fmax/--df: need finite 0 < fmin < fmax and df > 0, got "
                         f"{grid.fmin:g}, {grid.fmax:g}, {grid.step:g}")
    check_lines((grid.fmax - grid.fmin) / grid.step + 1, "--df")
    return prediction_grid(spec, grid.lines())


def _load_stack(stack_file: Path, db: str | None):
    """The stack of a file; catalogued parts it names are read from --db (or --server) and reported."""
    from jointdb import usecases
    from jointdb.schemas._jsonfile import read_json_file
    from jointdb.cli._output import message

    if not usecases.part_refs(read_json_file(stack_file, "stack file")):
        return usecases.load_stack(stack_file)
    from jointdb.cli._target import open_repo

    with open_repo(db) as store:
        spec = usecases.load_stack(stack_file, store)
    for used in spec.parts:
        message(f"{used['slot']}: part {used['part']}" + (f" ({used['ref']})" if used["ref"] != used["part"] else ""))
    return spec


def _report_joint_choices(joints) -> None:
    """On stderr, per interface: how its joint was chosen (method), the joints used with their weights and
    distances, the next candidates, conditions outside the catalogue, and warnings (docs/stacks.md wording)."""
    from jointdb.cli._output import message

    for res in joints:
        if not res.neighbours:
            continue
        used = ", ".join(f"{n}@{v} (weight {w:.3f}, distance {d:.3f})" for n, v, w, d in res.neighbours)
        message(f"{res.interface}: {res.method}: {used}")
        shown = {(n, v) for n, v, _, _ in res.neighbours}
        nxt = [f"{n}@{v} {d:.3f}" for n, v, d in res.candidates if (n, v) not in shown]
        if nxt:
            message(f"{res.interface}: next candidates (distance): {', '.join(nxt)}")
        if res.extrapolating:
            message(f"warning: {res.interface}: the request lies outside the catalogued range of "
                    f"{', '.join(res.outside_range)}; the nearest catalogued edge is used (no extrapolation)")
        for w in res.warnings:
            if w.startswith("note: "):
                message(f"note: {res.interface}: {w[6:]}")
            elif not (res.extrapolating and "outside the catalogued range" in w):  # said just above
                message(f"warning: {res.interface}: {w}")


def predict(
    stack_file: Annotated[Path, typer.Argument(help="Stack description (JSON, format jointdb-stack/1).",
                                               metavar="STACK.json")],
    db: Annotated[Optional[str], typer.Option("--db", help="Joint database URL or SQLite path "
                                              "(default: $JOINTDB_URL or the per-user database).")] = None,
    out: Annotated[Optional[Path], typer.Option("--out", help="Write the tool-tip FRF (x, y): "
                                                ".uff (UFF58), .h5 (HDF5) or .csv.")] = None,
    plots: PlotsOpt = None,
    fmin: Annotated[Optional[float], typer.Option(help="Lowest line [Hz] (overrides the stack file).")] = None,
    fmax: Annotated[Optional[float], typer.Option(help="Highest line [Hz].")] = None,
    df: Annotated[Optional[float], typer.Option(help="Line spacing [Hz].")] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Machine-readable output.")] = False,
    plot: LegacyPlotOpt = None,
) -> None:
    """Predict the tool-tip FRF of a tool / holder / spindle stack (three-component RC).

    Each interface's joint is taken from the stack file: rigid, explicit (k, c),
    a pinned catalogued joint name@version, or the nearest catalogued joint to
    the given conditions. The chosen versions, their distances and any
    extrapolation are reported. With `jointdb --server URL` (and no --db) the
    catalogued joints are read from that server; the coupling runs here.

    With --plots DIR, DIR/tip-vs-rigid.png compares the prediction with rigid
    joints (the legend names the joint versions and interpolation weights).

    Example: jointdb predict fixtures/stacks/endmill-modelled-spindle.json --out tip.uff --plots figs
    """
    from jointdb import usecases
    from jointdb.cli._output import emit, message
    from jointdb.errors import InputError

    plot = plots_dir(plots, plot, one_file=True)
    for label, path in (("--out", out),):
        if path is not None and not path.parent.exists():
            raise InputError(f"{label} {str(path)!r}: directory {str(path.parent)!r} does not exist")
    if out is not None:
        usecases.frf_format(out, "--out")
    spec = _load_stack(stack_file, db)
    freq = _frequency_override(spec, fmin, fmax, df)
    from jointdb.cli._target import check_db_target

    source = db
    if any(j.kind in ("catalogued", "query") for j in spec.interfaces.values()):  # only then is a db read
        import os

        if db is None and os.environ.get("JOINTDB_SERVER"):  # jointdb --server URL: joints read over HTTP
            from jointdb.cli._target import open_repo

            source = open_repo(None)
        else:
            check_db_target(db)  # after every option is checked; a mistyped --db is not found, not created empty
    result = usecases.predict_stack(spec, source, freq)
    pred = result.prediction
    _report_joint_choices(result.joints.values())
    for note in pred.notes:
        message(f"note: {note}")
    from jointdb.cli._predict_band import band_for, choice_sensitivity

    tip_band, terms = band_for(result)
    choice = choice_sensitivity(result, source, pred.tip.freq)
    files = {}
    if out is not None:
        usecases.write_frf_file(out, pred.tip)
        files["tip_frf"] = str(out)
        message(f"wrote {out}")
    if plot is not None:
        from jointdb.plots._stack import joints_legend, save_tip_comparison

        plot = save_tip_comparison(plot_file(plot, "tip-vs-rigid.png"), pred, title=spec.name,
                                   label=joints_legend(result.joints), band=tip_band)
        files["plot"] = str(plot)
        message(f"wrote {plot}")
    joints = [r.row() for r in result.joints.values()]
    if as_json:
        emit({"stack": spec.name, "parts": list(spec.parts), "joints": joints, "prediction": pred.summary(),
              "notes": [*pred.notes, *terms.grid_edge],
              "frequency_hz": [float(pred.tip.freq[0]), float(pred.tip.freq[-1]), int(pred.tip.n_freq)],
              "files": files, "band": None if tip_band is None else {**tip_band.to_json(), **terms.to_json()},
              "joint_choice_sensitivity": choice}, as_json=True)
        return
    emit([{"interface": j["interface"], "method": j["method"],
           "joints used (weight, distance)": "; ".join(f"{u['joint']} ({u['weight']:.3f}, {u['distance']:.3f})"
                                                      for u in j["joints_used"])
           or (j["joint"] if j["kind"] != "explicit" else "explicit k, c"),
           "outside the catalogue": ", ".join(j["outside_range"]) or "no"} for j in joints],
         title=f"joints of {spec.name}")
    emit([{"dir": r["direction"], "peak (Hz)": r["peak_hz"], "peak (m/N)": r["peak_m_per_n"],
           "rigid peak (Hz)": r["rigid_peak_hz"], "rigid peak (m/N)": r["rigid_peak_m_per_n"]}
          for r in pred.summary()], title="tool-tip receptance (rigid: all joints rigid)")


def register(app: typer.Typer) -> None:
    """Add ``predict`` to the app."""

    app.command("predict")(predict)
