"""``jointdb campaign init`` / ``check``: write a campaign file from a folder of files, and check one deeply.

:func:`scaffold_campaign` looks at a folder of UFF58 files and beam model files
(``jointdb-beam-model/1`` JSON) and infers what it can:

- **measured assembly files**: UFF58 files whose responses are translations
  only (e.g. the tip response ``1x`` to forces at ``1x`` and ``2x``);
- **substructure B** (the free part, e.g. the tool): a model without clamps
  or supports that has a named point at the measured response node — that
  node is ``planar.b_tip``; B's interface point is its other point on which a
  force was applied (or its only other point);
- **substructure A** (the part fixed to the machine, e.g. the holder on the
  spindle): a UFF58 file holding a translation and a rotation at one node
  (rotations from ``jointdb rotations``), or a model with a clamp or
  supports and one named point;
- ``name`` from the folder name; ``joint_model`` = ``planar``.

What it cannot infer — the joint type and the conditions (materials, torque,
preload, geometry) — the caller supplies (the CLI asks, or takes flags).
Anything ambiguous raises :class:`~jointdb.errors.InputError` saying which
file to remove or which option to give.

:func:`check_campaign` reads a campaign file as ``identify`` would (every
field, every file, the frequency grids, the DOFs the joint model needs)
without identifying anything, and returns a short report.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from jointdb.errors import InputError
from jointdb.frf import Dof

__all__ = ["ScaffoldFiles", "find_campaign_files", "scaffold_campaign", "check_campaign"]

_UFF_SUFFIXES = (".uff", ".unv", ".uff58", ".uf", ".58")
_ROT = ("rx", "ry", "rz")


@dataclass(frozen=True)
class ScaffoldFiles:
    """What :func:`find_campaign_files` recognised in a folder (paths relative to it)."""

    measurements: tuple[str, ...]
    a_name: str
    a_entry: Mapping[str, Any]
    a_node: int
    b_name: str
    b_model: str
    b_node: int
    b_tip: int
    notes: tuple[str, ...]


def _uff_dofs(path: Path) -> tuple[tuple[Dof, ...], tuple[Dof, ...]]:
    from jointdb.io import read_frf_uff58

    try:
        frf = read_frf_uff58(path)
    except InputError as exc:
        raise InputError(f"{path.name}: {exc}") from None
    return tuple(frf.outputs), tuple(frf.inputs)


def _model(path: Path):
    from jointdb.fe import load_model

    try:
        return load_model(path)
    except InputError as exc:
        raise InputError(f"{path.name}: {exc}") from None


def _is_model_file(path: Path) -> bool:
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return False
    return isinstance(doc, dict) and str(doc.get("format", "")).startswith("jointdb-beam-model/")


def _grounded(model) -> bool:
    from jointdb.fe import Clamp, Support

    return any(isinstance(i, (Clamp, Support)) for i in model.ingredients)


def find_campaign_files(folder: Path) -> ScaffoldFiles:
    """Recognise measurements and substructures A and B among a folder's UFF58 and model files.

    Raises
    ------
    InputError
        No measurement, no or several candidates for A or B, or measurements that do not
        meet B's points (the message names the files).
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise InputError(f"{folder}: not a directory")
    uffs = sorted(p for p in folder.iterdir() if p.suffix.lower() in _UFF_SUFFIXES and p.is_file())
    models = sorted(p for p in folder.iterdir() if p.suffix.lower() == ".json" and _is_model_file(p))
    notes: list[str] = []
    measured: list[tuple[Path, tuple[Dof, ...], tuple[Dof, ...]]] = []
    a_uffs: list[tuple[Path, int]] = []
    for p in uffs:
        outs, ins = _uff_dofs(p)
        dirs_at = {}
        for d in (*outs, *ins):
            dirs_at.setdefault(d.node, set()).add(d.direction)
        rot_nodes = [n for n, ds in dirs_at.items() if ds & set(_ROT) and ds - set(_ROT)]
        if rot_nodes:
            if len(dirs_at) != 1:
                raise InputError(f"{p.name}: has rotations at node {rot_nodes[0]} and DOFs at other nodes; "
                                 "a substructure file should hold one contact point (translation + rotation)")
            a_uffs.append((p, rot_nodes[0]))
        elif any(d.direction in _ROT for d in (*outs, *ins)):
            raise InputError(f"{p.name}: rotations without translations at any node; cannot use it")
        else:
            measured.append((p, outs, ins))
    if not measured:
        raise InputError(f"{folder}: no measured assembly UFF58 file (translations only) found among "
                         f"{', '.join(p.name for p in uffs) or 'no UFF58 files'}")
    out_nodes = {d.node for _, outs, _ in measured for d in outs}
    in_nodes = {d.node for _, _, ins in measured for d in ins}
    loaded = [(p, _model(p)) for p in models]
    free = [(p, m) for p, m in loaded if not _grounded(m)]
    grounded = [(p, m) for p, m in loaded if _grounded(m)]
    b_cands = [(p, m) for p, m in free if any(pt.node in out_nodes for pt in m.points) and len(m.points) >= 2]
    if not b_cands:
        raise InputError(f"{folder}: no free-free model file (no clamp, no supports) with a named point at the "
                         f"measured response node(s) {sorted(out_nodes)}; substructure B (e.g. the tool) is missing")
    if len(b_cands) > 1:
        raise InputError(f"{folder}: several model files could be substructure B "
                         f"({', '.join(p.name for p, _ in b_cands)}); keep one (move validation models elsewhere)")
    b_path, b_model = b_cands[0]
    tips = [pt for pt in b_model.points if pt.node in out_nodes]
    if len(tips) != 1:
        raise InputError(f"{b_path.name}: several named points ({', '.join(pt.name for pt in tips)}) are measured "
                         "response nodes; cannot tell the tip")
    tip = tips[0]
    others = [pt for pt in b_model.points if pt.node != tip.node]
    forced = [pt for pt in others if pt.node in in_nodes]
    b_point = forced[0] if len(forced) == 1 else (others[0] if len(others) == 1 else None)
    if b_point is None:
        raise InputError(f"{b_path.name}: cannot tell which named point is the interface "
                         f"({', '.join(pt.name for pt in others)}); keep only the tip and the interface point")
    if not forced:
        notes.append(f"no force was applied at B's interface point {b_point.name!r} (node {b_point.node}); "
                     "the planar IRC needs G_12 (tip response to a force near the interface)")
    a_models = [(p, m) for p, m in grounded if p != b_path]
    if len(a_uffs) + len(a_models) == 0:
        raise InputError(f"{folder}: no substructure A: give a UFF58 file with a translation and a rotation at the "
                         "contact node (see `jointdb rotations`) or a model file with a clamp/supports")
    if len(a_uffs) + len(a_models) > 1:
        names = [p.name for p, _ in a_uffs] + [p.name for p, _ in a_models]
        raise InputError(f"{folder}: several candidates for substructure A ({', '.join(names)}); keep one")
    if a_uffs:
        a_path, a_node = a_uffs[0]
        a_entry: dict[str, Any] = {"uff58": a_path.name, "dofs": [f"{a_node}x", f"{a_node}ry"]}
    else:
        a_path, a_m = a_models[0]
        if len(a_m.points) != 1:
            raise InputError(f"{a_path.name}: substructure A's model needs exactly one named point (its contact), "
                             f"has {len(a_m.points)}")
        a_node = a_m.points[0].node
        a_entry = {"model": a_path.name, "dofs": [f"{a_node}x", f"{a_node}ry"]}
    extra_models = [p.name for p in models if p not in (b_path, a_path)]
    if extra_models:
        notes.append(f"ignored model file(s) {', '.join(extra_models)}")
    return ScaffoldFiles(
        measurements=tuple(p.name for p, _, _ in measured), a_name=a_path.stem, a_entry=a_entry, a_node=a_node,
        b_name=b_path.stem, b_model=b_path.name, b_node=b_point.node, b_tip=tip.node, notes=tuple(notes),
    )


def scaffold_campaign(folder: Path, *, joint_type: str, conditions: Mapping[str, Any],
                      name: str | None = None, description: str | None = None) -> tuple[dict, tuple[str, ...]]:
    """A ``jointdb-campaign/1`` document for the files in ``folder`` (see the module docstring).

    Parameters
    ----------
    folder
        Folder with the measured assembly UFF58 file(s), substructure A (UFF58 with rotations or a
        grounded model) and substructure B (free–free model).
    joint_type
        e.g. ``"tool-holder"`` or ``"holder-spindle"``.
    conditions
        ``materials``, ``torque_nm``, ``preload_n``, ``geometry``, ``extra`` (as in the campaign format).
    name
        Campaign / joint name (default: the folder name).

    Returns
    -------
    (dict, tuple[str, ...])
        The campaign document (paths relative to ``folder``) and notes for the user.

    Raises
    ------
    InputError
        See :func:`find_campaign_files`; an empty joint type.
    """
    from jointdb.store._types import Conditions, check_joint_type

    folder = Path(folder)
    jt = check_joint_type(joint_type)
    cond = Conditions.from_dict(dict(conditions)).to_dict()  # validates; normalises material names
    cond = {k: v for k, v in cond.items() if v not in (None, [], {})}
    files = find_campaign_files(folder)
    a_name = files.a_name if files.a_name != files.b_name else f"{files.a_name}-a"
    doc = {
        "format": "jointdb-campaign/1",
        "name": name or folder.resolve().name,
        "joint_type": jt,
        "description": description or f"scaffolded by `jointdb campaign init` from {folder.resolve().name}/",
        "conditions": cond,
        "joint_model": "planar",
        "substructures": {a_name: dict(files.a_entry), files.b_name: {"model": files.b_model}},
        "interface": {"a": a_name, "a_dofs": [f"{files.a_node}x", f"{files.a_node}ry"],
                      "b": files.b_name, "b_dofs": [f"{files.b_node}x", f"{files.b_node}ry"]},
        "measurements": list(files.measurements),
        "planar": {"b_tip": files.b_tip},
    }
    return doc, files.notes


def check_campaign(path: Path) -> dict[str, Any]:
    """Read and check a campaign file and every file it names, as ``identify`` would, without identifying.

    Returns
    -------
    dict
        ``name, joint_type, joint_model, conditions, lines, band_hz, measured`` (entries),
        ``substructures`` (name → DOF count) — for a short report.

    Raises
    ------
    InputError
        Naming the campaign file and the field (``campaign c.json: measurements[0]: ...``).
    NotFoundError
        The campaign file does not exist.
    """
    from jointdb.campaign._file import _err, load_campaign, load_substructure, merge_measurements
    from jointdb.store._types import Conditions, check_joint_type

    c = load_campaign(path)
    cpath = c.path
    try:
        check_joint_type(c.joint_type)
    except InputError as exc:
        raise _err(cpath, "joint_type", str(exc)) from None
    try:
        Conditions.from_dict(dict(c.conditions))
    except InputError as exc:
        raise _err(cpath, "conditions", str(exc)) from None
    meas = merge_measurements(cpath, "measurements", c.measurements, c.band)
    subs = {n: load_substructure(cpath, f"substructures.{n}", s, meas.freq) for n, s in c.substructures.items()}
    iface = c.interface
    for side in ("a", "b"):
        frf = subs[iface[side]]
        have = set(frf.outputs) | set(frf.inputs)
        missing = [str(d) for d in iface[f"{side}_dofs"] if d not in have]
        if missing:
            raise _err(cpath, f"interface.{side}_dofs", f"substructure {iface[side]!r} has no DOF(s) "
                       f"{', '.join(missing)} (it has {' '.join(str(d) for d in sorted(have, key=str))})")
    if c.joint_model == "planar":
        tip = c.model_options["b_tip"]
        b = iface["b_dofs"][0]
        need = [(Dof(tip, b.direction), Dof(tip, b.direction)), (Dof(tip, b.direction), b)]
        have = {(o, i) for o in meas.outputs for i in meas.inputs} | {(i, o) for o in meas.outputs
                                                                      for i in meas.inputs}
        missing = [f"H({o}, {i})" for o, i in need if (o, i) not in have]
        if missing:
            raise _err(cpath, "measurements", f"the planar model needs the tip FRFs {', '.join(missing)} "
                       f"(planar.b_tip = {tip}, interface.b_dofs[0] = {b}); measured: "
                       + ", ".join(f"H({o}, {i})" for o in meas.outputs for i in meas.inputs))
    return {
        "campaign": str(cpath), "name": c.name, "joint_type": c.joint_type, "joint_model": c.joint_model,
        "conditions": dict(c.conditions), "lines": int(meas.n_freq),
        "band_hz": [float(meas.freq[0]), float(meas.freq[-1])],
        "measured": [f"H({o}, {i})" for o in meas.outputs for i in meas.inputs],
        "substructures": {n: len(set(f.outputs) | set(f.inputs)) for n, f in subs.items()},
    }
