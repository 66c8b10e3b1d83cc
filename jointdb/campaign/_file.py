"""Measurement campaign files for ``jointdb identify`` and ``jointdb couple``.

A campaign (JSON, ``"format": "jointdb-campaign/1"``) names the substructures
(beam model files or UFF58 files with DOF labels), the interface (contact
DOFs), the measured assembly UFF58 files, the joint model and its options.
Paths are relative to the campaign file. Everything is read and checked
before anything is computed or written; problems raise
:class:`~jointdb.errors.InputError` naming the field and file.

Example (planar tool–holder joint)::

    {
      "format": "jointdb-campaign/1",
      "name": "th-demo", "joint_type": "tool-holder",
      "conditions": {"torque_nm": 30, "materials": ["steel", "carbide"]},
      "joint_model": "planar",
      "substructures": {
        "holder": {"uff58": "holder.uff", "dofs": ["3x", "3ry"]},
        "tool":   {"model": "tool.json"}
      },
      "interface": {"a": "holder", "a_dofs": ["3x", "3ry"], "b": "tool", "b_dofs": ["2x", "2ry"]},
      "measurements": ["assembly.uff"],
      "planar": {"b_tip": 1},
      "options": {"smoothing": null, "regularisation": "none", "fit_band": [100, 2000]},
      "validation": {"substructures": {"tool": {"model": "tool_short.json"}},
                     "measurements": ["validation.uff"]}
    }

This module is the application layer of the two commands (it spans files
and numerics); the CLI module stays thin.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from jointdb.schemas._jsonfile import read_json_file
from jointdb.schemas._limits import check_lines
from jointdb.errors import InputError
from jointdb.frf import FRF, Dof, Quantity, dofs

FORMAT = "jointdb-campaign/1"
JOINT_MODELS = ("planar", "n-point", "matrix")


@dataclass(frozen=True)
class Substructure:
    """One substructure of a campaign.

    Attributes
    ----------
    name
        Its name in the campaign (``substructures.<name>``).
    kind
        ``"model"`` (a beam model file) or ``"uff58"`` (a measured FRF file).
    path
        The file.
    dofs
        The DOFs to use from it, or None for all.
    """

    name: str
    kind: str  # "model" | "uff58"
    path: Path
    dofs: tuple[Dof, ...] | None = None


def file_hashes(c: "Campaign") -> dict[str, str]:
    """SHA-256 of the campaign file and of every file it names, keyed by path relative to the campaign file.

    The one rule of the catalogue's provenance (``input_files``, :mod:`jointdb.usecases`):
    ``campaign.json``, ``assembly.uff``, ``../../models/tool.json`` — the same keys whether
    the campaign is read where the user keeps it or unpacked from an uploaded archive (where
    the relative path is the path inside the archive, never the server's folder).

    Parameters
    ----------
    c
        The campaign.

    Returns
    -------
    dict
        Relative path → SHA-256 (hex), sorted by path.
    """
    import hashlib

    paths = [c.path] + [s.path for s in c.substructures.values()] + list(c.measurements)
    if c.validation is not None:
        paths += [s.path for s in c.validation["substructures"].values()] + list(c.validation["measurements"])
    base = c.path.resolve().parent
    out = {}
    for p in dict.fromkeys(Path(x).resolve() for x in paths):
        out[Path(os.path.relpath(p, base)).as_posix()] = hashlib.sha256(p.read_bytes()).hexdigest()
    return dict(sorted(out.items()))


@dataclass(frozen=True)
class Campaign:
    """A parsed, checked campaign file (no FRFs loaded yet); format in the module docstring.

    Attributes
    ----------
    path
        The campaign file.
    name, joint_type
        The campaign's name and the joint type it identifies.
    conditions
        The conditions of the joint (dict form of :class:`jointdb.store.Conditions`).
    joint_model
        ``"planar"``, ``"n-point"`` or ``"matrix"``.
    substructures
        Name → :class:`Substructure`.
    interface
        The interface: ``a``, ``a_dofs``, ``b``, ``b_dofs`` (substructure names, contact DOFs).
    measurements
        The measured assembly files.
    band
        ``(f_min, f_max)`` [Hz] used, or None for all lines.
    model_options
        The joint model's own section (``b_tip`` for planar, ``internal`` for n-point,
        ``measured`` for matrix).
    options
        Options of the identification (``smoothing``, ``regularisation``, ``fit_band``, ...).
    validation
        A validation assembly (its substructures and measurements), or None.
    couple
        What ``jointdb couple`` computes (joint, outputs, inputs).
    """

    path: Path
    name: str
    joint_type: str
    conditions: Mapping[str, Any]
    joint_model: str
    substructures: Mapping[str, Substructure]
    interface: Mapping[str, Any]
    measurements: tuple[Path, ...]
    band: tuple[float, float] | None
    model_options: Mapping[str, Any]
    options: Mapping[str, Any]
    validation: Mapping[str, Any] | None
    couple: Mapping[str, Any] = field(default_factory=dict)


def _err(campaign: Path, where: str, what: str) -> InputError:
    return InputError(f"campaign {campaign.name}: {where}: {what}")


def _dof_list(cpath: Path, where: str, value: Any) -> tuple[Dof, ...]:
    if not isinstance(value, list) or not value:
        raise _err(cpath, where, "must be a non-empty list of DOF labels like \"3x\"")
    try:
        return dofs(value)
    except InputError as exc:
        raise _err(cpath, where, str(exc)) from None


def _file(cpath: Path, where: str, value: Any, root: Path | None = None) -> Path:
    if not isinstance(value, str) or not value:
        raise _err(cpath, where, "must be a file name")
    if root is not None:
        return _confined_file(cpath, where, value, root)
    p = (cpath.parent / value).resolve()
    if not p.is_file():
        raise _err(cpath, where, f"file '{value}' not found (looked in {cpath.parent})")
    return p


def _inside(path: str, root: str) -> bool:
    return path == root or path.startswith(root.rstrip(os.sep) + os.sep)


def _confined_file(cpath: Path, where: str, value: str, root: Path) -> Path:
    """A file the campaign names, which must lie inside ``root`` (an unpacked upload): no absolute
    path, no '..' leading out of it, no symbolic link; messages never show where ``root`` is."""
    from pathlib import PurePosixPath, PureWindowsPath

    if (any(ord(ch) < 32 or ord(ch) == 127 for ch in value) or "\\" in value
            or PurePosixPath(value).is_absolute() or PureWindowsPath(value).drive):
        raise _err(cpath, where, "an absolute path (or one with a backslash or control character) is not "
                                 "accepted; name a file inside the archive by its path relative to the campaign file")
    top = os.path.realpath(root)
    joined = os.path.normpath(os.path.join(os.path.realpath(cpath.parent), value))
    # lexically too: a path that climbs above the archive's top and comes back in (through the name
    # of the folder it was unpacked into) names a place outside the archive all the same
    inner = os.path.normpath(os.path.join(os.path.relpath(os.path.realpath(cpath.parent), top), value))
    if not _inside(joined, top) or inner == ".." or inner.startswith(".." + os.sep):
        # the value itself is not repeated: it may name a server path
        raise _err(cpath, where, "the path leads outside the uploaded archive; put that file into the "
                                 "archive at this path relative to the campaign file")
    if os.path.realpath(joined) != joined:
        raise _err(cpath, where, "the path goes through a symbolic link; put the file itself in the archive")
    if not os.path.isfile(joined):
        raise _err(cpath, where, f"file '{value[:80]}' is not in the uploaded archive")
    return Path(joined)


def _substructures(cpath: Path, where: str, raw: Any, root: Path | None = None) -> dict[str, Substructure]:
    if not isinstance(raw, dict) or not raw:
        raise _err(cpath, where, "must map substructure names to {\"model\": file} or {\"uff58\": file}")
    out = {}
    for name, spec in raw.items():
        w = f"{where}.{name}"
        if not isinstance(spec, dict):
            raise _err(cpath, w, "must be an object with \"model\" or \"uff58\"")
        unknown = set(spec) - {"model", "uff58", "dofs", "provenance"}
        if unknown:
            raise _err(cpath, w, f"unknown field(s) {', '.join(sorted(unknown))}")
        if ("model" in spec) == ("uff58" in spec):
            raise _err(cpath, w, "give exactly one of \"model\" (beam model JSON) or \"uff58\" (FRF file)")
        kind = "model" if "model" in spec else "uff58"
        d = _dof_list(cpath, f"{w}.dofs", spec["dofs"]) if "dofs" in spec else None
        out[str(name)] = Substructure(str(name), kind, _file(cpath, f"{w}.{kind}", spec[kind], root), d)
    return out


def _conditions(cpath: Path, raw: Any) -> dict[str, Any]:
    """The joint's conditions: torque and preload finite and >= 0, materials a list of names."""
    if raw is None:
        return {}
    if not isinstance(raw, dict):
        raise _err(cpath, "conditions", "must be an object such as {\"torque_nm\": 30, \"materials\": [...]}")
    for key in ("torque_nm", "preload_n"):
        if key in raw:
            v = raw[key]
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise _err(cpath, f"conditions.{key}", f"must be a finite number, got {v!r}")
            if v < 0:
                raise _err(cpath, f"conditions.{key}", f"must be >= 0, got {v:g}")
    mats = raw.get("materials")
    if mats is not None and not (isinstance(mats, list) and all(isinstance(m, str) and m.strip() for m in mats)):
        raise _err(cpath, "conditions.materials", f"must be a list of material names, got {mats!r}")
    if mats is not None:
        from jointdb.store._types import normalise_material  # the catalogue's list (extensible)

        for k, m in enumerate(mats):
            try:
                normalise_material(m)
            except InputError as exc:
                raise _err(cpath, f"conditions.materials[{k}]", str(exc)) from None
    return dict(raw)


def _model_options(cpath: Path, model: str, raw: dict, interface: dict) -> dict:
    """The options of the joint model (``planar``, ``n_point`` or ``matrix``), checked against the interface."""
    a_dofs, b_dofs = interface["a_dofs"], interface["b_dofs"]
    key = {"planar": "planar", "n-point": "n_point", "matrix": "matrix"}[model]
    mopts = raw.get(key) or {}
    if model == "planar":
        if len(a_dofs) != 2 or a_dofs[0].node != a_dofs[1].node or b_dofs[0].node != b_dofs[1].node:
            raise _err(cpath, "interface", "the planar model needs one point per side: a translation and a rotation")
        if not isinstance(mopts.get("b_tip"), int):
            raise _err(cpath, "planar.b_tip", "must be the node number of B's free end (tip)")
    elif model == "n-point":
        mopts = dict(mopts, internal=_dof_list(cpath, "n_point.internal", mopts.get("internal")))
    else:
        m = mopts.get("measured")
        if not isinstance(m, list) or not all(isinstance(x, list) and len(x) == 2 for x in m):
            raise _err(cpath, "matrix.measured", "must be a list of [substructure, DOF] pairs")
        for i, (n, _) in enumerate(m):
            if n not in (interface["a"], interface["b"]):
                raise _err(cpath, f"matrix.measured[{i}]", f"substructure {n!r} is not part of the interface")
        mopts = dict(mopts, measured=[(n, Dof.parse(d)) for n, d in m])
    return mopts


def _validation(cpath: Path, validation: Any, subs: dict, root: "str | os.PathLike | None") -> dict | None:
    """The held-out validation set: substructures that replace some of the campaign's, and measurements."""
    if validation is not None:
        vsubs = _substructures(cpath, "validation.substructures", validation.get("substructures"), root)
        for n in vsubs:
            if n not in subs:
                raise _err(cpath, f"validation.substructures.{n}", "replaces no substructure of the campaign")
        vm = validation.get("measurements")
        if not isinstance(vm, list) or not vm:
            raise _err(cpath, "validation.measurements", "must be a non-empty list of UFF58 files")
        validation = {
            "substructures": vsubs,
            "measurements": tuple(_file(cpath, f"validation.measurements[{i}]", m, root) for i, m in enumerate(vm)),
        }
    return validation


def load_campaign(path: "str | Path", *, root: "str | Path | None" = None) -> Campaign:
    """Read and check a campaign file (structure, names, DOFs, that files exist).

    Parameters
    ----------
    path
        The campaign file; the files it names are relative to it.
    root
        Confine the campaign to this folder (an unpacked upload, as the HTTP service
        does): every file it names must lie inside ``root``, named by a relative path
        without symbolic links; absolute paths and '..' leading out are refused before
        anything is opened. Default: no confinement (the user's own files).

    Returns
    -------
    Campaign

    Raises
    ------
    NotFoundError
        If the campaign file does not exist.
    InputError
        Naming the exact field, e.g. ``campaign c.json: interface.a: unknown substructure 'holdr'``.
    """
    cpath = Path(path)
    if root is not None and not _inside(os.path.realpath(cpath), os.path.realpath(root)):
        raise InputError(f"campaign {cpath.name} is not inside the uploaded archive")
    raw = read_json_file(cpath, "campaign file")
    if not isinstance(raw, dict):
        raise InputError(f"campaign {cpath.name}: the top level must be a JSON object")
    if raw.get("format") != FORMAT:
        raise _err(cpath, "format", f"must be \"{FORMAT}\", got {raw.get('format')!r}")
    # structure, JSON types and single-field ranges: the published schema (docs/schemas/campaign.schema.json);
    # what follows checks what a schema cannot (cross references, files, DOFs in the files)
    from jointdb.schemas import validate

    validate("campaign", raw, f"campaign {cpath.name}")
    model = raw.get("joint_model")
    if model not in JOINT_MODELS:
        raise _err(cpath, "joint_model", f"must be one of {', '.join(JOINT_MODELS)}, got {model!r}")
    subs = _substructures(cpath, "substructures", raw.get("substructures"), root)
    iface = raw["interface"]
    for side in ("a", "b"):
        if iface.get(side) not in subs:
            raise _err(cpath, f"interface.{side}", f"unknown substructure {iface.get(side)!r} (have: {', '.join(subs)})")
    a_dofs = _dof_list(cpath, "interface.a_dofs", iface.get("a_dofs"))
    b_dofs = _dof_list(cpath, "interface.b_dofs", iface.get("b_dofs"))
    if len(a_dofs) != len(b_dofs):
        raise _err(cpath, "interface", f"{len(a_dofs)} a_dofs but {len(b_dofs)} b_dofs; they are paired")
    interface = {"a": iface["a"], "a_dofs": a_dofs, "b": iface["b"], "b_dofs": b_dofs}
    meas_raw = raw.get("measurements", [])
    meas = tuple(_file(cpath, f"measurements[{i}]", m, root) for i, m in enumerate(meas_raw))
    band = raw.get("band")
    if band is not None:
        if not (isinstance(band, list) and len(band) == 2
                and all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in band)
                and 0 <= band[0] < band[1]):
            raise _err(cpath, "band", "must be [fmin, fmax] in Hz with fmin < fmax")
        band = (float(band[0]), float(band[1]))
    mopts = _model_options(cpath, model, raw, interface)
    opts = raw.get("options") or {}
    validation = _validation(cpath, raw.get("validation"), subs, root)
    couple = raw.get("couple") or {}
    conditions = _conditions(cpath, raw.get("conditions", {}))
    return Campaign(
        path=cpath, name=str(raw.get("name", cpath.stem)), joint_type=str(raw.get("joint_type", "")),
        conditions=conditions, joint_model=model, substructures=subs, interface=interface,
        measurements=meas, band=band, model_options=mopts, options=opts, validation=validation, couple=couple,
    )


# ------------------------------------------------------------------ loading
def _read_uff(cpath: Path, where: str, path: Path) -> FRF:
    from jointdb.io import read_frf_uff58

    try:
        return read_frf_uff58(path, Quantity.RECEPTANCE, fill="reciprocity")
    except InputError as exc:
        raise _err(cpath, where, f"{path.name}: {exc}") from None


def merge_measurements(cpath: Path, where: str, files: tuple[Path, ...], band) -> FRF:
    """Read measured UFF58 files (receptance), merge their entries, check one frequency grid."""
    if not files:
        raise _err(cpath, where, "no measured assembly files given")
    parts = [_read_uff(cpath, f"{where}[{i}]", f) for i, f in enumerate(files)]
    if band is not None:
        parts = [p.band(*band) for p in parts]
    ref = parts[0]
    for i, p in enumerate(parts[1:], 1):
        if p.freq.shape != ref.freq.shape or not np.allclose(p.freq, ref.freq, rtol=1e-9, atol=1e-9):
            raise _err(cpath, f"{where}[{i}]", f"{files[i].name} has {p.n_freq} lines {p.freq[0]:g}–{p.freq[-1]:g} Hz "
                       f"but {files[0].name} has {ref.n_freq} lines {ref.freq[0]:g}–{ref.freq[-1]:g} Hz")
    entries: dict[tuple[Dof, Dof], np.ndarray] = {}
    for p in parts:
        for i, o in enumerate(p.outputs):
            for j, n in enumerate(p.inputs):
                entries.setdefault((o, n), p.values[:, i, j])
    outs = list(dict.fromkeys(o for o, _ in entries))
    ins = list(dict.fromkeys(n for _, n in entries))
    vals = np.zeros((ref.n_freq, len(outs), len(ins)), dtype=complex)
    for i, o in enumerate(outs):
        for j, n in enumerate(ins):
            v = entries.get((o, n), entries.get((n, o)))
            if v is None:
                raise _err(cpath, where, f"no measurement of H({o}, {n}) in any file, nor of its reciprocal")
            vals[:, i, j] = v
    dead = [(o, n) for i, o in enumerate(outs) for j, n in enumerate(ins) if not np.any(vals[:, i, j])]
    if dead:
        o, n = dead[0]
        raise _err(cpath, where, f"measured H({o}, {n}) is zero at every line (a dead or missing channel?)")
    return FRF(ref.freq, vals, outs, ins, Quantity.RECEPTANCE)


def load_substructure(cpath: Path, where: str, sub: Substructure, freq: np.ndarray) -> FRF:
    """A substructure's receptance on ``freq``: a model's FRF at all named points, or a UFF58 file."""
    if sub.kind == "model":
        from jointdb.fe import load_model

        try:
            model = load_model(sub.path)
            frf = model.frf(freq)
        except InputError as exc:
            raise _err(cpath, f"{where}.model", f"{sub.path.name}: {exc}") from None
    else:
        frf = _read_uff(cpath, f"{where}.uff58", sub.path)
        if frf.freq.shape != freq.shape or not np.allclose(frf.freq, freq, rtol=1e-9, atol=1e-9):
            try:
                frf = frf.band(freq[0] - 1e-9, freq[-1] + 1e-9)
            except InputError:
                pass
            if frf.freq.shape != freq.shape or not np.allclose(frf.freq, freq, rtol=1e-9, atol=1e-9):
                raise _err(cpath, f"{where}.uff58", f"{sub.path.name} has {frf.n_freq} lines "
                           f"{frf.freq[0]:g}–{frf.freq[-1]:g} Hz; the measurements have {freq.size} lines "
                           f"{freq[0]:g}–{freq[-1]:g} Hz (same grid needed)")
    if sub.dofs is not None:
        have = set(frf.outputs) | set(frf.inputs)
        missing = [str(d) for d in sub.dofs if d not in have]
        if missing:
            raise _err(cpath, f"{where}.dofs", f"{sub.path.name} has no DOF(s) {', '.join(missing)}")
    return frf


def grid_for_couple(c: Campaign) -> np.ndarray:
    """Frequency grid for ``couple``: the measurements', or ``couple.frequency`` {min, max, step}."""
    spec = c.couple.get("frequency")
    if spec is not None:
        try:
            f0, f1, df = float(spec["min"]), float(spec["max"]), float(spec["step"])
        except (KeyError, TypeError, ValueError):
            raise _err(c.path, "couple.frequency", "must be {\"min\": Hz, \"max\": Hz, \"step\": Hz}") from None
        if not (math.isfinite(f0) and math.isfinite(f1) and math.isfinite(df) and 0 < f0 < f1 and df > 0):
            raise _err(c.path, "couple.frequency", "needs finite 0 < min < max and step > 0")
        try:
            check_lines((f1 - f0) / df + 1, "couple.frequency.step")
        except InputError as exc:
            raise InputError(f"campaign {c.path.name}: {exc}") from None
        return np.arange(f0, f1 + 0.5 * df, df)
    if not c.measurements:
        raise _err(c.path, "couple.frequency", "no measurements to take the grid from; give {min, max, step}")
    return merge_measurements(c.path, "measurements", c.measurements, c.band).freq
