"""CLI: ``jointdb modal-fit`` and ``jointdb lobes`` (thin: read file, call library, render)."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import numpy as np
import typer

from jointdb._output import emit, message, progress, write_rows
from jointdb.cli._options import (
    LegacyPlotOpt,
    PlotsOpt,
    TableOpt,
    check_out,
    deprecation_note,
    plot_file,
    plots_dir,
)
from jointdb.errors import InputError

#: Largest sizes accepted from options (far above real use; they bound memory and run time).
MAX_SPEEDS = 100_000
MAX_TEETH = 1000
MAX_INTERVALS = 2000
MAX_ORDER = 400


def _at_most(value: int, option: str, limit: int) -> None:
    if value > limit:
        raise InputError(f"{option} {value}: the limit is {limit}")


def read_frf_file(path: Path):
    """Read a tool-tip FRF from UFF58, the HDF5 exchange file or CSV (by suffix)."""
    from jointdb.usecases import read_frf_file as read

    return read(path)


def _node_select(frf, node: Optional[int]):
    if node is None:
        return frf
    outs = [d for d in frf.outputs if d.node == node]
    ins = [d for d in frf.inputs if d.node == node]
    if not outs or not ins:
        raise InputError(f"--node {node}: the file has no output and input DOFs at node {node}")
    return frf.select(outs, ins)


def _translational(frf, path: Path):
    """The translational entries of a tool-tip FRF: turning adds driving points, and a
    rotation (rad/(N·m)) must not be added to a displacement (m/N)."""
    outs = [d for d in frf.outputs if not d.is_rotation]
    ins = [d for d in frf.inputs if not d.is_rotation]
    if not outs or not ins:
        raise InputError(f"{path}: turning needs a translational tool-tip FRF (x, y or z); the file has "
                         f"outputs {' '.join(map(str, frf.outputs))}, inputs {' '.join(map(str, frf.inputs))}")
    if len(outs) < len(frf.outputs) or len(ins) < len(frf.inputs):
        dropped = sorted({str(d) for d in (*frf.outputs, *frf.inputs) if d.is_rotation})
        message(f"note: rotational DOFs {' '.join(dropped)} ignored for turning")
        frf = frf.select(outs, ins)
    return frf


def _floats(text: Optional[str], name: str):
    if text is None:
        return None
    try:
        return [float(v) for v in text.replace(";", ",").split(",") if v.strip()]
    except ValueError:
        raise InputError(f"{name}: expected comma-separated numbers, got {text!r}") from None


def _fit_tip_model(frf, frf_y, n_modes, band, max_order):
    """Fit the tool-tip x/y driving points (library call) and report each fit on stderr."""
    from jointdb.modal import fit_tool_tip

    model, fits = fit_tool_tip(frf, frf_y, n_modes, band, max_order=max_order)
    for fit in fits:
        message(
            f"modal fit {fit.model.outputs[0]}: {fit.model.n_modes} modes at "
            + ", ".join(f"{f:.1f} Hz (ζ {z:.4f})" for f, z in zip(fit.freq_hz, fit.zeta))
            + f"; NMSE {fit.quality.nmse_total:.2e}, FRAC {fit.quality.frac_min:.4f}"
        )
    return model, fits


def _sd_lobes_with_progress(model, cut, speeds: np.ndarray, n_intervals: int, n_chunks: int = 25):
    """``stability.milling_lobes_sd`` in chunks of speeds, with a progress bar on a terminal.

    Each speed is solved independently (same start depth, which depends only on
    the model and the cut), so the result equals one call over all speeds.
    """
    from jointdb.stability import LobeResult, milling_lobes_sd

    chunks = np.array_split(speeds, min(n_chunks, speeds.size))
    parts = [milling_lobes_sd(model, cut, chunk, n_intervals=n_intervals)
             for chunk in progress(chunks, total=len(chunks), description="lobes (SD)")]
    info = dict(parts[0].info)
    info["evaluations"] = int(sum(p.info.get("evaluations", 0) for p in parts))
    return LobeResult(parts[0].method, *(np.concatenate([getattr(p, a) for p in parts]) for a in
                      ("spindle_speed_rpm", "depth_m", "chatter_freq_hz", "lobe", "kind")), (), info)


#: Formats of ``lobes --out`` (by suffix).
LOBE_FORMATS = (".csv", ".json", ".h5", ".hdf5")


def lobe_rows_mm(res) -> list[dict]:
    """The lobe table for people: depth in mm (the unit of the plot and the summary)."""
    return [{"spindle_speed_rpm": r["spindle_speed_rpm"], "depth_mm": r["depth_m"] * 1e3,
             "chatter_freq_hz": r["chatter_freq_hz"], "lobe": r["lobe"], "kind": r["kind"]} for r in res.table()]


def lobe_summary(res, n_base: int) -> dict:
    """The lobe summary (SI) of :func:`jointdb.usecases.lobe_summary`, which the API gives too."""
    from jointdb.usecases import lobe_summary as summary

    return summary(res, n_base)


def _summary_for_people(summary: dict) -> dict:
    """The SI summary with depths in mm (as in the plot and the table)."""
    return {(k[:-2] + "_mm" if k.endswith("depth_m") else k): (v * 1e3 if k.endswith("depth_m") else v)
            for k, v in summary.items()}


def _modal_fit_tables(fit) -> tuple[list[dict], list[dict], dict]:
    """The modes for people (one row a mode, residues as text), for files (one row a mode and
    entry, SI) and the fit quality, from a modal fit."""
    rows, table_rows = [], []
    for k in range(fit.model.n_modes):
        mode = {"mode": k + 1, "freq_hz": float(fit.freq_hz[k]), "zeta": float(fit.zeta[k])}
        row = dict(mode)
        for i, o in enumerate(fit.model.outputs):
            for j, inp in enumerate(fit.model.inputs):
                r = fit.residues[k, i, j]
                table_rows.append({**mode, "output": str(o), "input": str(inp), "residue_re": float(r.real),
                                   "residue_im": float(r.imag)})
                row[f"R {o}/{inp}"] = f"{r.real:.3g}{r.imag:+.3g}j"
        rows.append(row)
    quality = {
        "band_hz": list(fit.band),
        "quantity": fit.quantity.value,
        "nmse_total": fit.quality.nmse_total,
        "frac_min": fit.quality.frac_min,
        "per_entry": [
            {"output": str(o), "input": str(inp), "nmse": float(fit.quality.nmse[i, j]), "frac": float(fit.quality.frac[i, j])}
            for i, o in enumerate(fit.model.outputs)
            for j, inp in enumerate(fit.model.inputs)
        ],
    }
    return rows, table_rows, quality


def _modal_fit_json(fit, quality: dict) -> dict:
    """``modal-fit --json``: the modes with their residue matrices, the DOFs, residuals and quality (SI)."""
    modes_json = [
        {"mode": k + 1, "freq_hz": float(fit.freq_hz[k]), "zeta": float(fit.zeta[k]), "residues": fit.residues[k]}
        for k in range(fit.model.n_modes)
    ]
    return {
        "modes": modes_json,
        "outputs": [str(d) for d in fit.model.outputs],
        "inputs": [str(d) for d in fit.model.inputs],
        "upper": fit.model.upper,
        "lower": fit.model.lower,
        "quality": quality,
    }


def modal_fit(
    frf_file: Path = typer.Argument(..., exists=False, help="FRF file: UFF58 (.uff/.unv) or HDF5 exchange file (.h5)."),
    band: Optional[tuple[float, float]] = typer.Option(None, "--band", help="Frequency band FMIN FMAX in Hz."),
    modes: Optional[int] = typer.Option(None, "--modes", help="Number of modes (default: all well-stabilised poles)."),
    max_order: int = typer.Option(30, "--max-order", help="Highest pLSCF model order of the stabilisation diagram."),
    no_residuals: bool = typer.Option(False, "--no-residuals", help="Do not fit upper/lower residual terms."),
    plots: PlotsOpt = None,
    out: Optional[Path] = typer.Option(None, "--out", help="Write the modes (SI) to .csv, .json or .h5."),
    as_json: bool = typer.Option(False, "--json", help="Machine-readable output (SI units)."),
    plot: LegacyPlotOpt = None,
) -> None:
    """Fit modes to an FRF (pLSCF poles + LSFD residues) and report the fit quality.

    Writes modal-fit-stabilisation.png and modal-fit-overlay.png with --plots.

    Example: jointdb modal-fit tip.uff --band 5 1000 --modes 6 --plots figs
    """
    from jointdb.modal import fit_modes

    _at_most(max_order, "--max-order", MAX_ORDER)
    if modes is not None:
        _at_most(modes, "--modes", MAX_ORDER)
    if band is not None and not (np.all(np.isfinite(band)) and 0 <= band[0] < band[1]):
        raise InputError(f"--band must be FMIN FMAX with finite 0 <= FMIN < FMAX Hz, got {band[0]:g} {band[1]:g}")
    plot = plots_dir(plots, plot)
    check_out(out, LOBE_FORMATS)
    frf = read_frf_file(frf_file)
    fit = fit_modes(frf, n_modes=modes, band=band, max_order=max_order, residuals=not no_residuals)
    rows, table_rows, quality = _modal_fit_tables(fit)
    if plot is not None:
        from jointdb.plots._lobes import plot_modal_fit, plot_stabilisation

        plot.mkdir(parents=True, exist_ok=True)
        deprecation_note()
        p1 = plot_stabilisation(fit, plot / "modal-fit-stabilisation.png", frf=frf)
        p2 = plot_modal_fit(frf, fit, plot / "modal-fit-overlay.png")
        message(f"wrote {p1} and {p2}")
    if out is not None:
        write_rows(out, table_rows, kind="modes", meta={
            "source": str(frf_file), "residue_unit": "receptance (m/N or rad/(N·m)) · rad/s", **quality})
        message(f"wrote {out}")
    if as_json:
        emit(_modal_fit_json(fit, quality), as_json=True)
        return
    emit(rows, title=f"Modes of {frf_file.name} ({fit.band[0]:g}–{fit.band[1]:g} Hz, receptance residues)")
    emit([{"entry": f"{q['output']}/{q['input']}", "nmse": q["nmse"], "frac": q["frac"]} for q in quality["per_entry"]],
         title=f"Fit quality ({fit.quantity.value}): NMSE total {fit.quality.nmse_total:.3g}, FRAC min {fit.quality.frac_min:.4f}")


def lobes(
    frf_file: Path = typer.Argument(..., help="Tool-tip FRF: UFF58 (.uff/.unv) or HDF5 exchange file (.h5)."),
    op: str = typer.Option("milling", "--op", help="turning or milling."),
    method: str = typer.Option("zoa", "--method", help="Milling method: zoa (zero-order) or sd (semi-discretization)."),
    kf: Optional[float] = typer.Option(None, "--kf", help="Turning: cutting coefficient K_f in N/m²."),
    orientation: Optional[str] = typer.Option(None, "--orientation", help="Turning: directional factors per driving point, e.g. '0.75,0.5'."),
    teeth: int = typer.Option(2, "--teeth", help="Milling: number of teeth."),
    kt: Optional[float] = typer.Option(None, "--kt", help="Milling: tangential coefficient K_t in N/m²."),
    kr: Optional[float] = typer.Option(None, "--kr", help="Milling: radial (normal) coefficient K_r in N/m²."),
    immersion: float = typer.Option(1.0, "--immersion", help="Milling: radial immersion a_e/D in (0, 1]."),
    up: bool = typer.Option(False, "--up", help="Up-milling (default: down-milling)."),
    rpm_min: float = typer.Option(2000.0, "--rpm-min", help="Lowest spindle speed in rpm."),
    rpm_max: float = typer.Option(20000.0, "--rpm-max", help="Highest spindle speed in rpm."),
    n_speeds: int = typer.Option(300, "--n-speeds", help="Number of spindle speeds."),
    intervals: int = typer.Option(40, "--intervals", help="SD: intervals per tooth period."),
    modes: Optional[int] = typer.Option(None, "--modes", help="SD: modes to fit per direction."),
    band: Optional[tuple[float, float]] = typer.Option(None, "--band", help="SD: band FMIN FMAX (Hz) of the modal fit."),
    max_order: int = typer.Option(30, "--max-order", help="SD: highest pLSCF order."),
    frf_y: Optional[Path] = typer.Option(None, "--frf-y", help="Separate file with the y-direction tool-tip FRF."),
    node: Optional[int] = typer.Option(None, "--node", help="Use only the DOFs of this node (tool tip)."),
    cross_terms: Optional[bool] = typer.Option(
        None, "--cross-terms/--no-cross-terms",
        help="ZOA: use the x–y cross FRFs of the tip file (default: when the file has non-zero ones)."),
    refine: int = typer.Option(3, "--refine", help="Rounds of extra speeds near the minima and pockets "
                               "of the lobes (0: only the --n-speeds grid)."),
    plots: PlotsOpt = None,
    out: Optional[Path] = typer.Option(None, "--out", help="Write the lobe table (SI: depth in m) to "
                                       ".csv, .json or .h5."),
    table: TableOpt = False,
    as_json: bool = typer.Option(False, "--json", help="Machine-readable summary and table (SI units)."),
    plot: LegacyPlotOpt = None,
) -> None:
    """Stability lobes from a tool-tip FRF (turning: Tlusty; milling: ZOA or SD).

    Prints a summary (smallest limiting depth, deepest pocket); --table prints
    every speed (depth in mm), --json everything in SI units. With --plots DIR
    the diagram is DIR/lobes.png.

    Example: jointdb lobes tip.h5 --op milling --method sd --teeth 2 --kt 6e8 --kr 2e8 --immersion 0.1 --plots figs
    """
    op_l, method_l = op.lower(), method.lower()
    _check_lobe_options(op, method, rpm_min, rpm_max, n_speeds, teeth, intervals, max_order, refine,
                        kf=kf, kt=kt, kr=kr, immersion=immersion)
    plot = plots_dir(plots, plot, one_file=True)
    check_out(out, LOBE_FORMATS)
    speeds = np.linspace(rpm_min, rpm_max, n_speeds)
    from jointdb.cli._tip_inputs import coefficient_warnings, read_tool_tip

    frf, notes = read_tool_tip(frf_file)
    frf = _node_select(frf, node)
    frf2 = _node_select(read_frf_file(frf_y), node) if frf_y is not None else None
    notes += coefficient_warnings(kf=kf, kt=kt, kr=kr)
    if op_l == "turning":
        res, title = _turning_lobes(frf, frf2, frf_file, frf_y, kf, orientation, speeds, refine, notes)
    else:
        if kt is None or kr is None:
            raise InputError("milling needs --kt and --kr (cutting coefficients in N/m²)")
        from jointdb import stability

        cut = stability.MillingCut(teeth, kt, kr, immersion, not up)
        cross_terms = _cross_terms_choice(frf, cross_terms, method_l, notes)
        if method_l == "zoa":
            res = stability.refine_lobes(lambda s: stability.milling_lobes_zoa(
                frf, cut, frf2, cross_terms=cross_terms, spindle_speed_rpm=s), speeds, rounds=refine)
        else:
            model, _ = _fit_tip_model(frf, frf2, modes, band, max_order)
            res = stability.refine_lobes(lambda s: _sd_lobes_with_progress(model, cut, s, intervals),
                                         speeds, rounds=refine)
        title = (f"Milling lobes ({method_l.upper()}), {teeth} teeth, a/D = {immersion:g}, "
                 f"{'up' if up else 'down'}-milling")
    _render_lobes(res, lobe_summary(res, n_speeds), notes, title, plot=plot, out=out, as_json=as_json, table=table)


def _check_lobe_options(op, method, rpm_min, rpm_max, n_speeds, teeth, intervals, max_order, refine,
                        **coefficients) -> None:
    """The ``lobes`` options that must hold before any file is read (InputError naming the option)."""
    if op.lower() not in ("turning", "milling"):
        raise InputError(f"--op must be turning or milling, got {op!r}")
    if method.lower() not in ("zoa", "sd"):
        raise InputError(f"--method must be zoa or sd, got {method!r}")
    if not (0 < rpm_min < rpm_max) or not np.isfinite(rpm_max) or n_speeds < 2:
        raise InputError("need finite 0 < --rpm-min < --rpm-max and --n-speeds >= 2")
    _at_most(n_speeds, "--n-speeds", MAX_SPEEDS)
    _at_most(teeth, "--teeth", MAX_TEETH)
    if intervals < 2:
        raise InputError(f"--intervals must be >= 2, got {intervals}")
    _at_most(intervals, "--intervals", MAX_INTERVALS)
    _at_most(max_order, "--max-order", MAX_ORDER)
    for name, value in coefficients.items():
        if value is not None and not np.isfinite(value):
            raise InputError(f"--{name} must be a finite number, got {value}")
    if refine < 0 or refine > 10:
        raise InputError(f"--refine must be between 0 and 10 rounds, got {refine}")


def _turning_lobes(frf, frf2, frf_file: Path, frf_y, kf, orientation, speeds, refine: int, notes: list):
    """Turning lobes (Tlusty) over the translational driving points; notes are appended to ``notes``."""
    from jointdb import stability
    from jointdb.cli._tip_inputs import turning_frf

    if kf is None:
        raise InputError("turning needs --kf (cutting coefficient in N/m²)")
    frf = _translational(frf, frf_file)
    frf, more = turning_frf(frf, frf2, frf_y)
    notes += more
    if orientation is None and len(frf.outputs) > 1:
        notes.append(f"note: turning with {len(frf.outputs)} driving points and no --orientation: "
                     "each weighted 1 (give --orientation for the cut's directional factors)")
    mu = _floats(orientation, "--orientation")
    res = stability.refine_lobes(lambda s: stability.turning_lobes(frf, kf, mu, spindle_speed_rpm=s),
                                 speeds, rounds=refine)
    return res, f"Turning lobes, K_f = {kf:g} N/m²"


def _cross_terms_choice(frf, cross_terms: Optional[bool], method_l: str, notes: list) -> bool:
    """Whether milling uses the tip file's x–y cross terms (default: ZOA when the file has them)."""
    from jointdb.cli._tip_inputs import has_cross_terms

    present = has_cross_terms(frf)
    if cross_terms is None:
        cross_terms = present and method_l == "zoa"
        if present:
            notes.append("note: the tip file's x–y cross terms are used (--no-cross-terms drops them)"
                         if method_l == "zoa" else
                         "note: SD fits the x and y planes separately; the tip file's x–y cross terms "
                         "are not used")
    elif cross_terms and not present:
        notes.append("note: --cross-terms asked, but the file has none: they are zero")
    elif cross_terms and method_l == "sd":
        notes.append("note: SD fits the x and y planes separately; --cross-terms is not used")
    return cross_terms


def _render_lobes(res, summary: dict, notes: list, title: str, *, plot, out, as_json: bool, table: bool) -> None:
    """Notes, the plot and the --out file, then the summary, the table or the JSON."""
    for line in notes:
        message(line)
    if plot is not None:
        from jointdb.plots._lobes import plot_lobes

        message(f"wrote {plot_lobes(res, plot_file(plot, 'lobes.png'), title=title)}")
    if out is not None:
        write_rows(out, res.table(), kind="lobes", meta={"title": title, "method": res.method, "info": res.info,
                                                         "summary": summary})
        message(f"wrote {out} ({len(res.spindle_speed_rpm)} rows)")
    if as_json:
        emit({"method": res.method, "info": res.info, "summary": summary, "rows": res.table(), "notes": notes},
             as_json=True)
        return
    if table:
        emit(lobe_rows_mm(res), columns=["spindle_speed_rpm", "depth_mm", "chatter_freq_hz", "lobe", "kind"],
             title=title)
        return
    emit(_summary_for_people(summary), title=f"{title} (--table: all {summary['speeds']} speeds)")


def register(app: typer.Typer) -> None:
    """Add ``modal-fit`` and ``lobes`` to the app."""

    app.command("modal-fit")(modal_fit)
    app.command("lobes")(lobes)
