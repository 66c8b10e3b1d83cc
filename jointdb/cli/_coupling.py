"""CLI: ``jointdb identify`` (IRC) and ``jointdb couple`` (RC), driven by a campaign file.

Thin: the campaign is read, checked and identified by :func:`jointdb.usecases.identify`
(:mod:`jointdb.campaign`); files are written only after every
computation succeeded.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated, Optional

import typer

from jointdb.cli._options import LegacyPlotOpt, PlotsOpt, deprecation_note, plot_file, plots_dir

from jointdb.errors import InputError, NotFoundError


def _check_out(path: Path | None, suffixes: tuple[str, ...], option: str) -> None:
    if path is None:
        return
    if path.suffix.lower() not in suffixes:
        raise InputError(f"{option} {path}: use one of {', '.join(suffixes)}")
    if not path.parent.exists():
        raise InputError(f"{option} {path}: directory {path.parent} does not exist")


def identify_cmd(
    campaign: Annotated[Path, typer.Argument(help="Campaign file (JSON, format jointdb-campaign/1).")],
    out: Annotated[Path, typer.Option("--out", help="Joint FRF HDF5 exchange file to write (.h5).")],
    report: Annotated[Optional[Path], typer.Option("--report", help="Also write the report as JSON.")] = None,
    plots: Annotated[
        Optional[Path], typer.Option("--plots", metavar="DIR",
                                     help="Directory for PNGs: k(ω), c(ω) and measured vs reconstructed.")
    ] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Machine-readable report on stdout.")] = False,
    plot: LegacyPlotOpt = None,
) -> None:
    """Identify a joint (IRC) from a campaign's measured assembly FRFs and substructure models.

    Example: jointdb identify fixtures/campaigns/th-steel-30nm/campaign.json --out joint.h5 --plots figs
    """
    from jointdb.cli._output import emit, message
    from jointdb.campaign import joint_attrs
    from jointdb.usecases import identify

    _check_out(out, (".h5", ".hdf5"), "--out")
    _check_out(report, (".json",), "--report")
    plots = plots_dir(plots, plot)
    result = identify(campaign)
    c = result.campaign
    rep = result.report()
    # everything computed: now write
    from jointdb.io import write_frf_hdf5

    write_frf_hdf5(out, result.result.joint, joint_attrs(result))
    written = [str(out)]
    if report is not None:
        from jointdb.io._jsonable import to_jsonable
        from jointdb.io._atomic import atomic_path

        with atomic_path(report) as tmp:  # never a half-written report
            tmp.write_text(json.dumps(to_jsonable(rep), indent=2) + "\n", encoding="utf-8")
        written.append(str(report))
    if plots is not None:
        written += _identify_plots(plots, result)
        deprecation_note()
    message(f"wrote {', '.join(written)}")
    if as_json:
        emit(rep, as_json=True)
    else:
        flat = {k: v for k, v in rep.items() if not isinstance(v, (dict, list))}
        from jointdb.frf import Dof

        oe = rep.get("output_error")
        for row in rep.get("constant_fit", []):
            if oe is None:
                rot = Dof.parse(row["dof"]).is_rotation
                flat[f"k {row['dof']} [{'N·m/rad' if rot else 'N/m'}]"] = row["k"]
                flat[f"c {row['dof']} [{'N·m·s/rad' if rot else 'N·s/m'}]"] = row["c"]
            flat[f"{'IRC ' if oe else ''}fit error {row['dof']}"] = row["error"]
        if oe is not None and oe["theta_is_log"]:
            kept = (rep.get("model_adequacy") or {}).get("catalogued_joint", "constant")
            tag = "" if kept == "constant" else " (constant fit, not kept)"
            for row in oe["parameters"]:
                flat[row["parameter"] + tag] = f"{row['value']:.6g} ± {row['std_error']:.2g}"
        for k, v in rep.get("validation", {}).items():
            if not isinstance(v, (dict, list)):
                flat[f"validation {k}"] = v
        for name, peaks in (("peak", rep.get("peaks", [])), ("validation peak", rep.get("validation", {}).get("peaks", []))):
            for p in peaks[:1]:
                flat[f"{name} {p['f_measured_hz']:g} Hz"] = (
                    f"amplitude ×{p['amplitude_ratio']:.3f}, frequency {p['frequency_error']:+.2%}")
        emit(flat, title=f"joint identified from {c.name}")
        for line in rep.get("verdict", []):
            typer.echo(f"verdict: {line}")


def couple_cmd(
    campaign: Annotated[Path, typer.Argument(help="Campaign file (JSON, format jointdb-campaign/1).")],
    joint: Annotated[
        Optional[Path], typer.Option("--joint", help="Joint HDF5 file from 'jointdb identify' (default: the campaign's couple.joint, else rigid).")
    ] = None,
    out: Annotated[Optional[Path], typer.Option("--out", help="Write the assembly FRF (.h5 or .uff).")] = None,
    plots: PlotsOpt = None,
    as_json: Annotated[bool, typer.Option("--json", help="Machine-readable summary on stdout.")] = False,
    plot: LegacyPlotOpt = None,
) -> None:
    """Couple a campaign's substructures through a joint (RC) and compare with its measurements.

    What is coupled is the campaign's "couple" section: joint ("rigid", a joint HDF5 file or
    {"k": [...], "c": [...]} per interface a_dof), outputs and inputs ([substructure, DOF]
    pairs, rotations allowed; default the measured ones), frequency ({"min", "max", "step"}
    in Hz; default the measurements' lines). Every field is documented in
    docs/file-formats.md ("The couple section of a campaign") and checked by name.
    With --plots DIR the coupled (and measured) FRF is drawn in DIR/couple.png.

    Example: jointdb couple fixtures/campaigns/th-steel-30nm/campaign.json --joint joint.h5 --plots figs
    """
    from jointdb.cli._output import emit, message
    from jointdb.campaign import load_campaign
    from jointdb.campaign import couple_campaign

    _check_out(out, (".h5", ".hdf5", ".uff", ".unv"), "--out")
    plot = plots_dir(plots, plot, one_file=True)
    if joint is not None and not joint.is_file():
        raise NotFoundError(f"--joint {joint}: file not found")
    c = load_campaign(campaign)
    res = couple_campaign(c, joint)
    g = res["assembly"]
    written = []
    if out is not None:
        if out.suffix.lower() in (".h5", ".hdf5"):
            from jointdb.io import write_frf_hdf5

            write_frf_hdf5(out, g, {"kind": "assembly", "campaign": c.name, "joint": res["joint"]})
        else:
            from jointdb.io import write_uff58

            write_uff58(out, g)
        written.append(str(out))
    if plot is not None:
        from jointdb.plots._coupling import save_comparison_plot

        curves = [(f"coupled ({res['joint']})", g)]
        if res["measured"] is not None:
            curves.insert(0, ("measured", res["measured"].select(g.outputs, g.inputs)))
        plot = save_comparison_plot(plot_file(plot, "couple.png"), curves, title=f"{c.name}: coupled assembly")
        written.append(str(plot))
    if written:
        message(f"wrote {', '.join(written)}")
    summary = {
        "campaign": c.name, "joint": res["joint"], "lines": g.n_freq,
        "band_hz": f"{g.freq[0]:g}–{g.freq[-1]:g}",
        "outputs": " ".join(map(str, g.outputs)), "inputs": " ".join(map(str, g.inputs)),
    }
    if "error_mean" in res:
        summary["mean_relative_deviation_from_measurement"] = res["error_mean"]
    if "peaks" in res and as_json:
        summary["peaks"], summary["verdict"] = res["peaks"], res["verdict"]
    emit(summary, as_json=as_json, title="coupled assembly")
    if "verdict" in res and not as_json:
        for line in res["verdict"]:
            typer.echo(f"verdict: {line}")


def register(app: typer.Typer) -> None:
    """Add ``identify`` and ``couple`` to the app."""

    app.command("identify")(identify_cmd)
    app.command("couple")(couple_cmd)


def _identify_plots(directory: Path, result) -> list[str]:
    from jointdb.plots._coupling import save_comparison_plot, save_kc_plot

    directory.mkdir(parents=True, exist_ok=True)
    written = []
    if result.result.model != "matrix":
        p = save_kc_plot(directory / "joint_kc.png", result.result.extra.get("irc_joint", result.result.joint), result.kc,
                         title=f"{result.campaign.name}: identified joint", flagged=result.result.unreliable)
        written.append(str(p))
    p = save_comparison_plot(
        directory / "assembly_fit.png",
        [("measured", result.measured), ("reconstructed (identified joint)", result.reconstructed),
         ("rigid joint", result.rigid)],
        title=f"{result.campaign.name}: measured vs reconstructed vs rigid-joint assembly",
    )
    written.append(str(p))
    if result.validation is not None:
        v = result.validation
        p = save_comparison_plot(
            directory / "validation.png",
            [("measured", v["measured"]), ("predicted (identified joint)", v["predicted"]), ("rigid joint", v["rigid"])],
            title=f"{result.campaign.name}: validation assembly",
        )
        written.append(str(p))
    return written
