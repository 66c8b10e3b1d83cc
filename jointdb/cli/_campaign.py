"""CLI: ``jointdb campaign init|check`` and ``jointdb rotations``.

Thin: the inference and checks are in :mod:`jointdb.campaign._scaffold`, the
rotation estimates and their noise amplification in
:mod:`jointdb.campaign._rotations`. Files are written only after everything
was computed (atomically).
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path
from typing import Annotated, Any, Optional

import typer

from jointdb.cli._target import DbOpt
from jointdb.errors import InputError

CAMPAIGN_HELP = "Scaffold a measurement campaign from a folder of files, or check one."
ROTATIONS_HELP = "Rotational receptances at a contact point from translational measurements, with noise amplification."


def _pairs(values: list[str] | None, option: str) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for item in values or []:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise InputError(f"{option} {item!r}: expected key=value")
        try:
            out[key.strip()] = float(value)
        except ValueError:
            out[key.strip()] = value
    return out


def _ask(value, flag: str, prompt: str, cast=str, required: bool = True):
    """The flag's value; else ask on a terminal; else (not interactive) refuse naming the flag."""
    if value is not None:
        return value
    if sys.stdin.isatty():
        answer = typer.prompt(f"{prompt} (or give {flag})", default="" if not required else None,
                              show_default=False)
        return cast(answer) if str(answer).strip() else None
    if required:
        raise InputError(f"{flag} is required (it cannot be inferred from the files)")
    return None


def _write_json_atomic(path: Path, doc: dict) -> None:
    from jointdb.io._atomic import atomic_path

    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(doc, indent=2) + "\n", encoding="utf-8")


def init_cmd(
    folder: Annotated[Path, typer.Argument(help="Folder with the measured UFF58 file(s) and the part files.")],
    joint_type: Annotated[Optional[str], typer.Option("--type", help="Joint type, e.g. tool-holder or holder-spindle.")] = None,
    material: Annotated[Optional[list[str]], typer.Option("--material", help="Interface material (repeat).")] = None,
    torque: Annotated[Optional[float], typer.Option("--torque", help="Tightening torque [N·m].")] = None,
    preload: Annotated[Optional[float], typer.Option("--preload", help="Preload, e.g. drawbar force [N].")] = None,
    geometry: Annotated[Optional[list[str]], typer.Option("--geometry", help="Geometry key=value in SI (repeat).")] = None,
    extra: Annotated[Optional[list[str]], typer.Option("--extra", help="Free-form condition key=value (repeat), e.g. taper=HSK-A63.")] = None,
    name: Annotated[Optional[str], typer.Option("--name", help="Campaign / joint name (default: the folder name).")] = None,
    out: Annotated[Optional[Path], typer.Option("--out", help="Campaign file to write (default: FOLDER/campaign.json).")] = None,
    smoothing: Annotated[Optional[int], typer.Option("--smoothing", help="Savitzky-Golay window (odd number of lines) for the identification.")] = None,
    fit_band: Annotated[Optional[str], typer.Option("--fit-band", help="FMIN,FMAX [Hz] of the constant (k, c) fit.")] = None,
    force: Annotated[bool, typer.Option("--force", help="Overwrite an existing campaign file (and holder-on-spindle.uff).")] = False,
    spindle: Annotated[Optional[str], typer.Option("--spindle", help="Build A from parts: the catalogued spindle, NAME@VERSION or NAME@LABEL.")] = None,
    holder: Annotated[Optional[str], typer.Option("--holder", help="Build A from parts: the catalogued holder, NAME@VERSION or NAME@LABEL.")] = None,
    through_joint: Annotated[Optional[str], typer.Option("--through-joint", help="Build A from parts: the holder-spindle joint, NAME@VERSION, NAME@LABEL or a JSON query (docs/campaigns.md).")] = None,
    insertion: Annotated[Optional[float], typer.Option("--insertion", help="Build A from parts: clamped shank length in the holder bore [m].")] = None,
    shank_diameter: Annotated[Optional[float], typer.Option("--shank-diameter", help="Build A from parts: test tool shank diameter [m].")] = None,
    shank_material: Annotated[Optional[str], typer.Option("--shank-material", help="Build A from parts: test tool material, e.g. carbide.")] = None,
    db: DbOpt = None,
) -> None:
    """Write a campaign file for the UFF58 and model files in FOLDER.

    Infers the measurements, substructure A (UFF58 with rotations or a clamped/supported
    model), substructure B (free-free model), the interface DOFs and the tip node; asks
    (or takes flags) for the joint type and conditions. Then run `jointdb campaign check`.
    Example: jointdb campaign init tests-2026-11/ --type tool-holder --material carbide
    --material steel --torque 40

    A tool-holder campaign can build A from the catalogue instead: --spindle, --holder and
    --through-joint (the catalogued taper joint) with the test tool's --insertion,
    --shank-diameter and --shank-material give FOLDER/holder-on-spindle.uff (the holder
    with the shank stub on the spindle at the holder nose, x and ry) and record the parts
    and joint versions in the campaign (docs/campaigns.md).
    """
    from jointdb.cli._output import message
    from jointdb.campaign._scaffold import scaffold_campaign

    if not folder.is_dir():
        raise InputError(f"FOLDER {folder}: not a directory (give the folder holding the UFF58 and model files)")
    target = out if out is not None else folder / "campaign.json"
    if target.exists() and not force:
        raise InputError(f"--out {target}: exists; give --force to overwrite")
    if not target.parent.is_dir():
        raise InputError(f"--out {target}: directory {target.parent} does not exist")
    jt = _ask(joint_type, "--type", "joint type (tool-holder, holder-spindle, ...)")
    mats = material
    if not mats and sys.stdin.isatty():
        answer = _ask(None, "--material", "interface materials, e.g. carbide,steel", required=False)
        mats = [m.strip() for m in (answer or "").split(",") if m.strip()]
    if torque is None and preload is None and sys.stdin.isatty():
        torque = _ask(None, "--torque", "tightening torque [N·m] (empty: none)", float, required=False)
        preload = _ask(None, "--preload", "preload / drawbar force [N] (empty: none)", float, required=False)
    conditions = {"materials": list(mats or []), "torque_nm": torque, "preload_n": preload,
                  "geometry": _pairs(geometry, "--geometry"), "extra": _pairs(extra, "--extra")}
    options = _init_options(smoothing, fit_band)
    if target.resolve().parent != folder.resolve():
        raise InputError(f"--out {target}: write the campaign file into {folder} (its paths are relative to it)")
    from jointdb.usecases._substructure_a import A_FILE

    parts = dict(spindle=spindle, holder=holder, through_joint=through_joint, insertion=insertion,
                 shank_diameter=shank_diameter, shank_material=shank_material)
    recorded = _shank_conditions(jt, conditions["geometry"], insertion, shank_diameter)
    a_path = folder / A_FILE
    from_parts = any(v is not None for v in parts.values())
    kept = a_path.with_name(a_path.name + ".before-init") if from_parts and a_path.exists() else None
    if kept is not None and force:
        os.replace(a_path, kept)  # an earlier A is kept aside until this run has written its campaign file
    built = None
    try:
        built = _substructure_a(folder, force, db, **parts) if from_parts else None
        doc, notes = scaffold_campaign(folder, joint_type=jt, conditions=conditions, name=name)
        if built is not None:
            doc["substructures"][doc["interface"]["a"]]["provenance"] = dict(built[1].provenance)
            notes = (*notes, _through_note(built[1].provenance))
        if options:
            doc["options"] = options
        _write_json_atomic(target, doc)
    except BaseException:  # a failed init leaves the folder as it was: no new A, the earlier one back
        if built is not None:
            built[0].unlink(missing_ok=True)
        if kept is not None and kept.exists():
            os.replace(kept, a_path)
        raise
    if kept is not None and kept.exists():
        kept.unlink()
    sub = doc["substructures"]
    message(f"measurements: {', '.join(doc['measurements'])}; A = {doc['interface']['a']} "
            f"({next(iter(sub[doc['interface']['a']].values()))}) at {' '.join(doc['interface']['a_dofs'])}; "
            f"B = {doc['interface']['b']} ({sub[doc['interface']['b']]['model']}) at "
            f"{' '.join(doc['interface']['b_dofs'])}, tip node {doc['planar']['b_tip']}")
    for note in (*notes, *recorded):
        message(f"note: {note}")
    if not doc["conditions"]:
        message("note: no conditions given; the joint can be pinned but not found by a query")
    typer.echo(str(target))


def _shank_conditions(joint_type: str, geometry: dict, insertion, shank_diameter) -> tuple[str, ...]:
    """Record a tool–holder campaign's clamped shank (``--insertion``, ``--shank-diameter``) in ``geometry`` as
    ``insertion_m`` and ``shank_diameter_m`` where ``--geometry`` does not give them (the joint carries that shank:
    docs/stacks.md, *The shank inside the holder*); the notes saying so."""
    if str(joint_type or "").strip().lower().replace("_", "-") != "tool-holder":
        return ()
    added = []
    for key, value in (("insertion_m", insertion), ("shank_diameter_m", shank_diameter)):
        if value is not None and key not in geometry:
            geometry[key] = float(value)
            added.append(f"{key}={float(value):g}")
    return (f"conditions.geometry records the clamped shank: {', '.join(added)}",) if added else ()


def _init_options(smoothing: int | None, fit_band: str | None) -> dict[str, Any]:
    """The campaign's ``options`` from ``--smoothing`` and ``--fit-band``, checked before anything is written."""
    options: dict[str, Any] = {}
    if smoothing is not None:
        if smoothing < 3 or smoothing % 2 == 0:
            raise InputError(f"--smoothing {smoothing}: must be an odd number of lines >= 3")
        options["smoothing"] = smoothing
    if fit_band is not None:
        try:
            lo, hi = (float(v) for v in fit_band.split(","))
        except ValueError:
            raise InputError(f"--fit-band {fit_band!r}: expected FMIN,FMAX in Hz, e.g. 100,4000") from None
        if not 0 <= lo < hi:
            raise InputError(f"--fit-band {fit_band!r}: need 0 <= FMIN < FMAX")
        options["fit_band"] = [lo, hi]
    return options


def _substructure_a(folder: Path, force: bool, db, **given):
    """``(path, SubstructureA)`` written into FOLDER from the parts options (all of them needed)."""
    flags = {"spindle": "--spindle", "holder": "--holder", "through_joint": "--through-joint",
             "insertion": "--insertion", "shank_diameter": "--shank-diameter", "shank_material": "--shank-material"}
    missing = [flags[k] for k, v in given.items() if v is None]
    if missing:
        raise InputError(f"{', '.join(missing)}: substructure A from catalogued parts needs "
                         + ", ".join(flags.values()))
    from jointdb.cli._target import open_repo
    from jointdb.usecases._substructure_a import through_joint_choice, write_substructure_a

    given["through_joint"] = through_joint_choice(given["through_joint"])
    with open_repo(db) as repo:
        return write_substructure_a(folder, force=force, store=repo, **given)


def _through_note(prov: dict) -> str:
    """One line: which parts and which taper joint substructure A was built from."""
    tj = prov["through_joint"]
    used = ", ".join(f"{u['joint']} (weight {u['weight']:.2f})" for u in tj["joints_used"]) or tj["joint"]
    return (f"substructure A = {', '.join(p['part'] for p in prov['parts'])} through the holder–spindle joint "
            f"{used} ({tj['method']}){'; ' + tj['warnings'] if tj['warnings'] else ''}")


def check_cmd(
    file: Annotated[Path, typer.Argument(help="Campaign file (JSON, format jointdb-campaign/1).")],
    as_json: Annotated[bool, typer.Option("--json", help="Machine-readable report on stdout.")] = False,
) -> None:
    """Check a campaign file and every file it names, as identify would (no identification).

    Errors name the campaign file and the field, e.g.
    "campaign c.json: interface.b_dofs: substructure 'tool' has no DOF(s) 7x".
    Example: jointdb campaign check tests-2026-11/campaign.json
    """
    from jointdb.cli._output import emit, message
    from jointdb.campaign._scaffold import check_campaign

    report = check_campaign(file)
    if as_json:
        emit(report, as_json=True)
        return
    message(f"{file}: OK — {report['name']} ({report['joint_type']}, {report['joint_model']}), "
            f"{report['lines']} lines {report['band_hz'][0]:g}–{report['band_hz'][1]:g} Hz, measured "
            f"{', '.join(report['measured'])}; substructures "
            + ", ".join(f"{n} ({k} DOFs)" for n, k in report["substructures"].items()))
    typer.echo("ok")


def rotations_cmd(
    measured: Annotated[Path, typer.Argument(help="Measured translational FRFs (UFF58 / HDF5 / CSV).")],
    out: Annotated[Path, typer.Option("--out", help="The 2x2 (x, ry) receptance to write (.uff / .h5 / .csv).")],
    node: Annotated[int, typer.Option("--node", help="Node number of the contact point (labels of the result).")],
    method: Annotated[str, typer.Option("--method", help="extension | finite-difference")] = "extension",
    extension: Annotated[Optional[Path], typer.Option("--extension", help="Extension's beam model file (extension method).")] = None,
    joint_point: Annotated[Optional[str], typer.Option("--joint-point", help="Extension's named point fixed to the contact point.")] = None,
    points: Annotated[Optional[str], typer.Option("--points", help="Extension's two measured named points, NAME1,NAME2.")] = None,
    inner: Annotated[Optional[int], typer.Option("--inner", help="Finite differences: the second measured node.")] = None,
    spacing: Annotated[Optional[float], typer.Option("--spacing", help="Finite differences: distance between the nodes [m].")] = None,
    order: Annotated[str, typer.Option("--order", help="Finite differences: first-order | second-order.")] = "first-order",
    noise: Annotated[float, typer.Option("--noise", help="Relative measurement noise level for the amplification estimate.")] = 0.01,
    trials: Annotated[int, typer.Option("--trials", help="Noisy copies for the amplification estimate.")] = 20,
    fill: Annotated[str, typer.Option("--fill", help="error | reciprocity: complete a missing H[i,j] of a UFF58 "
                                      "file from H[j,i] (e.g. G11, G21, G22 measured, G12 not).")] = "error",
    as_json: Annotated[bool, typer.Option("--json", help="Machine-readable report on stdout.")] = False,
) -> None:
    """Rotational receptances at a contact point from translational measurements, with noise amplification.

    Extension method: a modelled extension fixed at the contact point, translations measured
    at two of its points. Finite differences: translations at the contact point and a point
    --spacing away. Reports how much measurement noise is amplified in h = x/F, n = θ/F, p = θ/M.
    Example: jointdb rotations ext.uff --extension ext.json --joint-point base --points p1,p2
    --node 3 --out holder.uff
    """
    from jointdb.cli._output import emit, message
    from jointdb.usecases import frf_format, read_frf_file, write_frf_file
    from jointdb.campaign._rotations import estimate_rotations

    frf_format(out, "--out")
    if not out.parent.is_dir():
        raise InputError(f"--out {out}: directory {out.parent} does not exist")
    if fill not in ("error", "reciprocity"):
        raise InputError(f"--fill {fill!r}: use error or reciprocity")
    try:
        frf = read_frf_file(measured, fill=fill)
    except InputError as exc:  # the reader names its Python argument; here it is a flag
        raise InputError(str(exc).replace("fill='reciprocity'", "--fill reciprocity")) from None
    ext = pts = None
    if method == "extension":
        from jointdb.fe import load_model

        if extension is None:
            raise InputError("--extension MODEL.json is required for the extension method")
        ext = load_model(extension)
        names = [p.strip() for p in (points or "").split(",") if p.strip()]
        if len(names) != 2:
            raise InputError(f"--points {points!r}: give the extension's two measured points as NAME1,NAME2")
        pts = (names[0], names[1])
    est = estimate_rotations(frf, method, node=node, extension=ext, joint_point=joint_point, points=pts,
                             inner=inner, spacing=spacing, order=order, noise=noise, trials=trials)
    write_frf_file(out, est.frf, round_freq=False)
    rows = est.rows()
    if as_json:
        report = {"out": str(out), "method": method, "noise_level": noise, "trials": trials,
                  "amplification": rows}
        if est.condition is not None:
            report["condition_median"] = float(__import__("numpy").median(est.condition))
        emit(report, as_json=True)
    else:
        message(f"{method}: wrote {out} ({est.frf.n_freq} lines, DOFs {node}x {node}ry)")
        message(f"noise amplification (RMS relative error / relative noise {noise:g}, {trials} trials):")
        emit(rows, columns=["entry", "meaning", "amplification_median", "amplification_p90"])
        worst = max(r["amplification_p90"] for r in rows)
        if worst > 10:
            message(f"warning: a {noise:.0%} measurement noise becomes up to {worst * noise:.0%} error in the "
                    "rotations; average more, widen the spacing or smooth before using them")


def register(app: typer.Typer) -> None:
    """Add ``campaign`` (init, check) and ``rotations`` to the app."""
    campaign = typer.Typer(help=CAMPAIGN_HELP, no_args_is_help=True)
    app.add_typer(campaign, name="campaign")

    campaign.command("init")(init_cmd)
    campaign.command("check")(check_cmd)
    app.command("rotations")(rotations_cmd)
