"""The main job: catalogue → query → predict → stability lobes, on the bundled fixtures.

:func:`run_main_job` is what ``jointdb demo`` runs. It

1. identifies the joint of every bundled measurement campaign (IRC, docs/theory.md
   §2a) and catalogues each as a joint version: six tool–holder campaigns
   (clamping torque 40 / 80 / 120 N·m × carbide or steel tool in a steel
   holder) and six holder–spindle campaigns (HSK-A63 or BT40 taper × three
   drawbar forces);
2. reads the bundled new stack (a fluted carbide end mill at 100 N·m on an
   HSK-A63 spindle at 20 kN, whose bearings are softer in y than in x) and asks
   the database for the nearest joint at each of its two interfaces, reporting
   the chosen version, its distance, the other candidates and any extrapolation;
3. predicts the tool-tip FRF (three-component RC, docs/theory.md §4) with that joint,
   with rigid joints and, as a cross-check, with a joint interpolated between
   the nearest neighbours; writes it (UFF58, CSV) and a comparison plot;
4. computes milling stability lobes (zero-order approximation, docs/theory.md §5)
   from both predictions (x and y bending planes) and plots them;

printing what it does through ``say`` and writing everything into ``out_dir``.
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Callable
from contextlib import ExitStack
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from jointdb.errors import InputError

__all__ = ["JourneyResult", "run_main_job", "bundled_catalogue", "DEMO_CUT"]

#: Milling conditions of the demo: 4-flute end mill, aluminium 7075 (Altintas, Manufacturing
#: Automation: K_t = 796 MPa, K_r/K_t = 0.212), half immersion, down-milling.
DEMO_CUT = {"n_teeth": 4, "kt": 7.96e8, "kr": 0.212 * 7.96e8, "radial_immersion": 0.5, "down_milling": True}


@dataclass
class JourneyResult:
    """What the main job produced."""

    out_dir: Path
    db_url: str
    catalogued: list[dict[str, Any]] = field(default_factory=list)
    joints: list[dict[str, Any]] = field(default_factory=list)
    prediction: list[dict[str, Any]] = field(default_factory=list)
    interpolated: dict[str, Any] = field(default_factory=dict)
    lobes: dict[str, Any] = field(default_factory=dict)
    parts: list[dict[str, Any]] = field(default_factory=list)
    files: list[Path] = field(default_factory=list)


def bundled_catalogue(stack: ExitStack) -> Path:
    """Directory of the bundled campaigns (``jointdb/data/catalogue``), as a real path while ``stack`` is open."""
    ref = resources.files("jointdb").joinpath("data", "catalogue")
    if not ref.is_dir():
        raise InputError("the bundled catalogue jointdb/data/catalogue is missing from the installed package")
    return Path(stack.enter_context(resources.as_file(ref)))


def _write_json(path: Path, data: Any) -> Path:
    from jointdb.io._jsonable import to_jsonable
    from jointdb.io._atomic import atomic_path

    with atomic_path(path) as tmp:  # like every other output file: whole or not at all
        tmp.write_text(json.dumps(to_jsonable(data), indent=2) + "\n", encoding="utf-8")
    return path


def _write_csv(path: Path, rows: list[dict[str, Any]]) -> Path:
    import csv

    from jointdb.io._atomic import atomic_path

    with atomic_path(path) as tmp, tmp.open("w", newline="", encoding="utf-8") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(rows[0].keys()) if rows else ["empty"])
        writer.writeheader()
        writer.writerows(rows)
    return path


def _joint_types(campaigns: list[Path]) -> dict[str, int]:
    """Joint type → number of campaigns (read from the campaign files, in order of first appearance)."""
    counts: dict[str, int] = {}
    for path in campaigns:
        jt = str(json.loads(path.read_text(encoding="utf-8")).get("joint_type", "?"))
        counts[jt] = counts.get(jt, 0) + 1
    return counts


def _condition_columns(cond: dict[str, Any]) -> dict[str, Any]:
    """Flat condition columns of a catalogued campaign and a one-line description of them."""
    extra = dict(cond.get("extra") or {})
    cols: dict[str, Any] = {"preload_n": cond.get("preload_n"), "taper": extra.get("taper"),
                            "holder_family": extra.get("holder_family")}
    parts = ["+".join(cond.get("materials", []))]
    if cond.get("torque_nm") is not None:
        parts.append(f"{cond['torque_nm']:g} N·m")
    if extra.get("taper"):
        parts.append(str(extra["taper"]))
    if cond.get("preload_n") is not None:
        parts.append(f"drawbar {cond['preload_n'] / 1e3:g} kN")
    cols["condition"] = ", ".join(p for p in parts if p)
    return cols


def run_main_job(
    out_dir: Path,
    db_url: str | None = None,
    say: Callable[[str], None] = print,
    *,
    n_speeds: int = 400,
    speed_range_rpm: tuple[float, float] = (3000.0, 30000.0),
) -> JourneyResult:
    """Run the whole journey on the bundled fixtures and write its outputs into ``out_dir``.

    Parameters
    ----------
    out_dir
        Output folder (created). Files: ``catalogue.csv``, ``joint-choice.json``,
        ``joint-choice.png``, ``stack.json``, ``tip.uff``, ``tip.csv``, ``tip-vs-rigid.png``,
        ``lobes.csv``, ``lobes.png``, ``summary.json`` (and the SQLite database when
        ``db_url`` is None).
    db_url
        Joint database (SQLAlchemy URL or SQLite path). ``None``: a fresh SQLite
        file ``out_dir/joints.sqlite``. Running twice on the same database reuses
        identical versions instead of adding new ones.
    say
        Called with one line of text per step (the CLI passes a stderr writer).
    n_speeds
        Spindle speeds of the lobe diagram.
    speed_range_rpm
        Spindle-speed range of the lobe diagram.

    Returns
    -------
    JourneyResult
    """
    from jointdb.plots._stack import joints_legend
    from jointdb.store import Repository

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    url = db_url if db_url is not None else f"sqlite:///{(out / 'joints.sqlite').resolve()}"
    result = JourneyResult(out, url)
    with ExitStack() as stack:
        cat = bundled_catalogue(stack)
        repo = stack.enter_context(Repository(url))
        say(f"jointdb main job → {out}  (database: {url})")
        _catalogue(repo, cat, result, say)
        spec, resolutions = _query(repo, cat, result, say)
        tip = _predict(repo, spec, resolutions, result, say)
        band_summary = _lobes(spec, tip, result, say, n_speeds, speed_range_rpm, joints_legend(resolutions))
        summary = {
            "database": url,
            "catalogued": result.catalogued,
            "joints": result.joints,
            "parts": result.parts,
            "prediction": result.prediction,
            "interpolated_cross_check": result.interpolated,
            "notes": list(tip.pred.notes),
            "lobes": result.lobes,
            "interfaces": {j["interface"]: {"joint": j["joint"], "distance": j["distance"],
                                            "extrapolating": j["extrapolating"]} for j in result.joints},
            "planes": ["x", "y"],
            "band": band_summary or None,
        }
        result.files.append(_write_json(out / "summary.json", summary))
    say(f"done: {len(result.files)} files in {out}")
    return result


def _catalogue(repo, cat: Path, result: JourneyResult, say: Callable[[str], None]) -> None:
    """Step 1: identify and catalogue every bundled campaign (one row each, ``catalogue.csv``)."""
    from jointdb.usecases import _catalogue, _partfiles

    campaigns = sorted((cat / "campaigns").glob("*/campaign.json"))
    kinds = _joint_types(campaigns)
    say(f"[1/4] identify and catalogue {len(campaigns)} campaigns "
        f"({', '.join(f'{n} {t}' for t, n in kinds.items())}; IRC, docs/theory.md §2a)")
    for path in campaigns:
        outcome = _catalogue.catalogue_campaign(repo, path)
        row = {"joint_type": outcome.campaign.joint_type, **outcome.row(),
               **_condition_columns(outcome.campaign.conditions)}
        truth_file = path.parent / "truth.json"
        if truth_file.is_file() and "k_x_n_per_m" in row:  # synthetic campaign: compare with the true joint
            truth = json.loads(truth_file.read_text(encoding="utf-8"))
            row["k_x_error"] = row["k_x_n_per_m"] / truth["k"][0] - 1.0
            row["k_theta_error"] = row["k_theta_nm_per_rad"] / truth["k"][1] - 1.0
        result.catalogued.append(row)
        vs_truth = (f"  (true k: {row['k_x_error']:+.2%}, {row['k_theta_error']:+.2%})"
                    if "k_x_error" in row else "")
        say(f"      {row['joint']:<26} {row['condition']:<34} "
            f"k_x={row['k_x_n_per_m']:.3e} N/m  k_θ={row['k_theta_nm_per_rad']:.3e} N·m/rad  "
            f"c_x={row['c_x_ns_per_m']:.0f} N·s/m{vs_truth}  "
            f"{'new version' if row['new'] else 'identical to v' + str(outcome.version.version) + ', nothing written'}")
    result.files.append(_write_csv(result.out_dir / "catalogue.csv", result.catalogued))
    for part, created in _partfiles.catalogue_bundled_parts(repo, cat):  # what the stack is assembled from
        say(f"      part {part.ref:<30} {part.kind:<8} {_attributes(part.attributes)}  "
            f"{'new version' if created else 'identical, nothing written'}")


def _attributes(attributes: dict) -> str:
    return ", ".join(f"{k} {v:g}" if isinstance(v, float) else f"{k} {v}" for k, v in attributes.items()
                     if k != "description")


def _query(repo, cat: Path, result: JourneyResult, say: Callable[[str], None]):
    """Step 2: read the new stack and choose the nearest catalogued joint at each interface."""
    from jointdb.usecases import _partfiles, _parts, _stack
    from jointdb.plots._stack import save_joint_distances
    from jointdb.stack import stack_to_dict

    out = result.out_dir
    # the new stack, assembled from the catalogued parts by name and version (exactly the bundled stack file)
    doc = json.loads((cat / "demo-stack.json").read_text(encoding="utf-8"))
    for name, kind, source, _ in _partfiles.BUNDLED_PARTS:
        if source.startswith("stack:"):
            doc[kind] = {"part": f"{name}@{repo.get_part(name).version}"}
    spec = _parts.stack_from_document(doc, repo)
    result.parts = list(spec.parts)
    result.files.append(_write_json(out / "stack.json", stack_to_dict(spec)))
    say(f"[2/4] new stack: {spec.name}")
    say("      from catalogued parts: " + ", ".join(f"{p['slot']} {p['part']}" for p in spec.parts))
    say(f"      tool {spec.tool.length * 1e3:.0f} mm ({spec.gauge_length * 1e3:.0f} mm gauge, "
        f"{spec.insertion_length * 1e3:.0f} mm inserted), holder {spec.holder.length * 1e3:.0f} mm")
    resolutions = _stack.resolve_joints(spec, repo)
    for res in resolutions.values():
        row = res.row()
        result.joints.append({**row, "candidates": [list(c) for c in res.candidates]})
        if res.candidates:
            extrapolating = f"  EXTRAPOLATING: {', '.join(res.outside_range)}" if res.extrapolating else ""
            say(f"      {res.interface}: chose {res.name}@{res.version} at distance {res.distance:.3f} "
                f"({row['per_condition']}){extrapolating}")
            for name, version, dist in res.candidates[1:]:
                say(f"          next: {name}@{version} at {dist:.3f}")
        else:
            say(f"      {res.interface}: {row['joint']}")
        for w in res.warnings:
            say(f"      warning: {w}")
    result.files.append(_write_json(out / "joint-choice.json", result.joints))
    requested = {n: dict(c.conditions or {}) for n, c in spec.interfaces.items() if c.kind == "query"}
    result.files.append(save_joint_distances(out / "joint-choice.png", resolutions, conditions=requested))
    return spec, resolutions


#: The lobes use lines this many times finer than the prediction's: ZOA draws each lobe through the
#: FRF's lines, and at high speeds (low lobe numbers) 20 Hz lines are far apart in speed.
LOBE_REFINEMENT = 4


@dataclass
class _Tip:
    """The tool-tip prediction of the demo stack, on the lobes' fine lines and on the stack's own lines
    (every :data:`LOBE_REFINEMENT`-th fine line: one prediction serves both), with its uncertainty bands."""

    fine: Any            # Prediction on the fine lines
    pred: Any            # the same on the stack's lines
    same_y: bool
    lobe_band: Any = None
    band_summary: dict = field(default_factory=dict)


def _finer_lines(grid: np.ndarray, factor: int) -> np.ndarray:
    """``factor - 1`` lines evenly between each pair of ``grid`` lines; every ``factor``-th line is
    exactly a line of ``grid``."""
    return np.interp(np.arange(factor * (grid.size - 1) + 1) / factor, np.arange(grid.size), grid)


def _every_line(pred, step: int):
    """The prediction ``pred`` on every ``step``-th of its lines."""
    from jointdb.frf import FRF
    from jointdb.stack import Prediction

    def thin(frf):
        return FRF(frf.freq[::step], frf.values[::step], frf.outputs, frf.inputs, frf.quantity)

    return Prediction(thin(pred.tip), thin(pred.rigid), {k: v[::step] for k, v in pred.tip_rotation.items()},
                      pred.interfaces, pred.notes)


def _predict(repo, spec, resolutions, result: JourneyResult, say: Callable[[str], None]) -> _Tip:
    """Step 3: the tool-tip FRF with the chosen joints and with rigid ones, the cross-check with
    interpolated joints, the uncertainty bands; ``tip.uff``, ``tip.csv``, ``tip-vs-rigid.png``."""
    from jointdb import io
    from jointdb.usecases._demo_band import journey_bands
    from jointdb.plots._stack import joints_legend, save_tip_comparison
    from jointdb.stack import prediction_grid
    from jointdb.usecases._stack import predict_with_joints

    out = result.out_dir
    say("[3/4] predict the tool-tip FRF (three-component receptance coupling, docs/theory.md §4)")
    grid = prediction_grid(spec)
    fine = _finer_lines(grid, LOBE_REFINEMENT)
    lob = predict_with_joints(spec, resolutions, fine).prediction
    pred = _every_line(lob, LOBE_REFINEMENT)
    result.prediction = pred.summary()
    same_y = np.allclose(pred.tip.entry("1y", "1y"), pred.tip.entry("1x", "1x"))
    for row in result.prediction[:1] if same_y else result.prediction:
        say(f"      {row['direction']}{' (and y)' if same_y else ''}: peak {row['peak_m_per_n']:.3e} m/N at "
            f"{row['peak_hz']:.0f} Hz (rigid joints: {row['rigid_peak_m_per_n']:.3e} m/N at "
            f"{row['rigid_peak_hz']:.0f} Hz); most negative real part {row['min_real_m_per_n']:.3e} m/N")
    for note in pred.notes:
        say(f"      note: {note}")
    extra = _cross_check(repo, spec, resolutions, grid, result, say)
    io.write_uff58(out / "tip.uff", pred.tip, round_freq=True)
    io.write_frf_csv(out / "tip.csv", pred.tip)
    result.files += [out / "tip.uff", out / "tip.csv"]
    # the lobes (step 4) use the fine lines; their band is sampled on those lines too
    tip_band, lobe_band, band_summary = journey_bands(spec, resolutions, grid, say, lobe_grid=fine)
    result.files.append(save_tip_comparison(out / "tip-vs-rigid.png", pred, title=spec.name, extra=extra,
                                            label=joints_legend(resolutions), band=tip_band))
    return _Tip(lob, pred, same_y, lobe_band, band_summary)


def _cross_check(repo, spec, resolutions, grid, result: JourneyResult, say: Callable[[str], None]) -> list:
    """The same stack with the queried joints interpolated between the catalogued conditions (when a
    query had neighbours): ``[(legend, tip FRF)]`` for the comparison plot, or ``[]``."""
    from jointdb.usecases import _stack
    from jointdb.plots._stack import joints_legend

    queried = {n for n, r in resolutions.items() if r.kind == "query" and len(r.candidates) > 1}
    if not queried:
        return []
    ispec = spec.replace(interfaces={
        n: dataclasses.replace(c, interpolate=True, neighbours=2) if n in queried else c
        for n, c in spec.interfaces.items()
    })
    ires = _stack.resolve_joints(ispec, repo)
    ipred = _stack.predict_with_joints(ispec, ires, grid).prediction
    irow = ipred.summary()[0]
    result.interpolated = {"joints": {n: ires[n].description for n in queried}, **irow}
    say("      cross-check, both queried interfaces interpolated:" if len(queried) > 1 else "      cross-check:")
    for n in sorted(queried):
        say(f"          {ires[n].description}")
    say(f"          peak {irow['peak_m_per_n']:.3e} m/N at {irow['peak_hz']:.0f} Hz "
        f"(nearest joint: {result.prediction[0]['peak_m_per_n']:.3e} m/N at "
        f"{result.prediction[0]['peak_hz']:.0f} Hz)")
    return [(joints_legend({n: ires[n] for n in sorted(queried)}), ipred.tip)]


def _lobes(spec, tip: _Tip, result: JourneyResult, say: Callable[[str], None], n_speeds: int,
           speed_range_rpm: tuple[float, float], joints: str) -> dict:
    """Step 4: milling lobes (ZOA) with the catalogued and with rigid joints; ``lobes.csv``, ``lobes.png``
    (``joints``: the joint versions named in its caption). Returns the band summary (with the lobe
    band's when there is one)."""
    from jointdb.plots._lobes import plot_lobes
    from jointdb.stability import MillingCut, milling_lobes_zoa, refine_lobes

    out, same_y, band_summary = result.out_dir, tip.same_y, tip.band_summary
    cut = MillingCut(**DEMO_CUT)
    speeds = np.linspace(*speed_range_rpm, n_speeds)
    say(f"[4/4] milling stability lobes (zero-order approximation, docs/theory.md §5): {cut.n_teeth} teeth, "
        f"K_t={cut.kt:.3g} N/m², K_r={cut.kr:.3g} N/m², a_e/D={cut.radial_immersion:g}, "
        f"{'down' if cut.down_milling else 'up'}-milling, {n_speeds} speeds, refined near the minima and pockets")
    cross = bool(np.any(tip.pred.tip.values[:, 0, 1]))  # planes coupled by the spindle: use H[x,y], H[y,x]
    # more speeds near the envelope's minima and pockets (equal to the plain grid at its speeds),
    # from the prediction on the fine lines
    lobes = refine_lobes(lambda s: milling_lobes_zoa(tip.fine.tip, cut, cross_terms=cross, spindle_speed_rpm=s),
                         speeds)
    lobes_rigid = refine_lobes(
        lambda s: milling_lobes_zoa(tip.fine.rigid, cut, cross_terms=cross, spindle_speed_rpm=s), speeds)
    # on the nominal lobes' (refined) speeds, so that band and nominal limit are computed alike
    lobe_band = tip.lobe_band(cut, lobes.spindle_speed_rpm) if tip.lobe_band is not None else None
    best = int(np.nanargmax(np.where(np.isfinite(lobes.depth_m), lobes.depth_m, -np.inf)))
    result.lobes = {
        "method": lobes.method,
        "min_depth_m": lobes.min_depth_m,
        "min_depth_rigid_m": lobes_rigid.min_depth_m,
        "best_speed_rpm": float(lobes.spindle_speed_rpm[best]),
        "best_depth_m": float(lobes.depth_m[best]),
        "cut": DEMO_CUT,
        "planes": "x and y (tool-tip FRF 1x,1x and 1y,1y" + (", equal" if same_y else "") + ")",
    }
    say(f"      from the x and y planes of the tip FRF{' (y equal to x)' if same_y else ''}")
    say(f"      unconditionally stable below {lobes.min_depth_m * 1e3:.3f} mm "
        f"(with rigid joints: {lobes_rigid.min_depth_m * 1e3:.3f} mm); "
        f"best pocket {lobes.depth_m[best] * 1e3:.2f} mm at {lobes.spindle_speed_rpm[best]:.0f} rpm")
    result.files.append(_write_csv(out / "lobes.csv", lobes.table()))
    result.files.append(plot_lobes([lobes, lobes_rigid], out / "lobes.png",
                                   labels=["with catalogued joints", "rigid joints"],
                                   title=f"Stability lobes: {spec.name}", band=lobe_band, joints=joints,
                                   flute_length_m=sum(s.length for s in spec.tool.segments if s.fluted)))
    if lobe_band is not None:
        band_summary["lobes"] = lobe_band.to_json()
        lo, mid, hi = lobe_band.critical_depth_m * 1e3
        say(f"      critical depth 5–95 %: {lo:.3f} – {hi:.3f} mm (median {mid:.3f} mm, "
            f"{lobe_band.samples} samples of the tip band's terms)")
    return band_summary
