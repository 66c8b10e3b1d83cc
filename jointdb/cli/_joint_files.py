"""Joint files for the store commands: read what `jointdb identify` wrote, write what
`jointdb couple --joint` reads, and merge the conditions a file records with those
given as options (a conflict is refused unless ``--force``).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from jointdb.errors import InputError

#: ``joint_model`` of `jointdb identify` files -> model kind of the catalogue
_JOINT_MODEL_KINDS = {"planar": "spring-damper-planar", "n-point": "n-point-translational", "matrix": "full-matrix"}


def _numeric_metrics(data: Any, prefix: str = "") -> dict[str, float]:
    """Finite numeric scalars of a (nested) mapping, keys joined with '.'."""
    out: dict[str, float] = {}
    if not isinstance(data, dict):
        return out
    for key, value in data.items():
        name = f"{prefix}{key}"
        if isinstance(value, bool):
            continue
        if isinstance(value, (int, float)) and math.isfinite(float(value)):
            out[name] = float(value)
        elif isinstance(value, dict):
            out.update(_numeric_metrics(value, name + "."))
    return out


def _read_joint_file(path: Path, root: Path | None = None) -> tuple[Any, dict[str, Any], dict[str, str], dict[str, Any]]:
    """FRF, metadata, input-file hashes and raw measurement FRFs from a joint or campaign file.

    Accepts the HDF5 exchange file of ``jointdb identify`` (``format = jointdb-frf``,
    metadata ``joint_model``, ``joint_type``, ``conditions``, ``quality``,
    ``settings``), a jointdb FRF blob file, or a campaign JSON file (identified
    here first, as ``jointdb identify`` would). With ``root`` a campaign may only
    name files inside that folder (an unpacked upload; see :func:`load_campaign`).
    """
    import h5py

    from jointdb.store import file_sha256, read_frf_file

    if not path.is_file():
        raise InputError(f"{path}: no such file")
    hashes = {path.name: file_sha256(path)}
    if path.suffix.lower() == ".json":
        try:
            from jointdb.campaign import load_campaign
            from jointdb.campaign import identify_campaign, joint_attrs
        except ImportError:
            raise InputError(f"{path}: cataloguing straight from a campaign needs `jointdb identify`") from None
        campaign = load_campaign(path, root=root)
        outcome = identify_campaign(campaign)
        text = path.read_text(encoding="utf-8")
        for sibling in sorted(path.parent.iterdir()):
            if sibling.is_file() and sibling != path and f'"{sibling.name}"' in text:
                hashes[sibling.name] = file_sha256(sibling)
        if root is not None:  # the other files it names, by their place in the upload
            top = Path(root).resolve()
            for p in _campaign_files(campaign):
                if p.parent != path.resolve().parent and p.is_relative_to(top):
                    hashes[p.relative_to(top).as_posix()] = file_sha256(p)
        raw = {"measured": outcome.measured} if outcome.measured is not None else {}
        return outcome.result.joint, joint_attrs(outcome), hashes, raw
    try:
        with h5py.File(path, "r", locking=False) as f:
            fmt = f.attrs.get("format")
            fmt = fmt.decode() if isinstance(fmt, bytes) else str(fmt)
    except OSError as exc:
        raise InputError(f"{path}: not an HDF5 file ({exc})") from None
    if fmt == "jointdb-frf-blob":
        return read_frf_file(path), {}, hashes, {}
    from jointdb.io import read_frf_hdf5_full

    frf, meta = read_frf_hdf5_full(path)
    return frf, dict(meta or {}), hashes, {}


def _campaign_files(c) -> list[Path]:
    """Every file a campaign names (substructures, measurements, validation), once each."""
    paths = [s.path for s in c.substructures.values()] + list(c.measurements)
    if c.validation is not None:
        paths += [s.path for s in c.validation["substructures"].values()] + list(c.validation["measurements"])
    return list(dict.fromkeys(Path(p).resolve() for p in paths))


def _write_joint_file(path: Path, frf, meta: dict[str, Any]) -> None:
    """Write a joint FRF as the HDF5 exchange file of ``jointdb identify`` (readable by
    ``jointdb couple --joint`` and ``jointdb catalogue``), with ``meta`` as its metadata."""
    from jointdb.io import write_frf_hdf5

    kinds = {v: k for k, v in _JOINT_MODEL_KINDS.items()}
    meta = {"kind": "joint", "joint_model": kinds.get(meta.pop("model_kind", ""), ""), **meta}
    write_frf_hdf5(path, frf, json.loads(json.dumps(meta, default=str)))




def _differs(a: Any, b: Any) -> bool:
    if isinstance(a, (int, float)) and isinstance(b, (int, float)) and not isinstance(a, bool):
        return not math.isclose(float(a), float(b), rel_tol=1e-12, abs_tol=0.0)
    return a != b


def merge_conditions(path: Path, recorded: Any, given, force: bool):
    """The conditions to catalogue: those the joint file records, completed by the options.

    An option that contradicts a value the file records is refused (one line
    naming both values) unless ``force``; then the option wins.

    Raises
    ------
    InputError
        A conflict without ``force``, or invalid conditions in the file.
    """
    from jointdb.store import Conditions

    base = dict(recorded) if isinstance(recorded, dict) else {}
    try:
        stored = Conditions.from_dict(base)
    except InputError as exc:
        raise InputError(f"{path}: the conditions recorded in the file are invalid: {exc}") from None
    conflicts: list[str] = []

    def clash(field: str, option: str, in_file: Any, in_option: Any) -> None:
        conflicts.append(f"{field} = {in_file} but {option} gives {in_option}")

    if given.materials and stored.materials and sorted(given.materials) != sorted(stored.materials):
        clash("materials", "--material", "+".join(stored.materials), "+".join(given.materials))
    for field, option in (("preload_n", "--preload"), ("torque_nm", "--torque")):
        a, b = getattr(stored, field), getattr(given, field)
        if a is not None and b is not None and _differs(a, b):
            clash(field, option, f"{a:g}", f"{b:g}")
    for part, option in (("geometry", "--geometry"), ("extra", "--extra")):
        a_map, b_map = dict(getattr(stored, part)), dict(getattr(given, part))
        for key in sorted(set(a_map) & set(b_map)):
            if _differs(a_map[key], b_map[key]):
                clash(f"{part}.{key}", option, a_map[key], b_map[key])
    if conflicts and not force:
        raise InputError(f"{path} records {'; '.join(conflicts)}: leave the option out to keep the file's value, "
                         "or add --force to store the option's value")
    return Conditions(
        materials=given.materials or stored.materials,
        preload_n=given.preload_n if given.preload_n is not None else stored.preload_n,
        torque_nm=given.torque_nm if given.torque_nm is not None else stored.torque_nm,
        geometry={**dict(stored.geometry), **dict(given.geometry)},
        extra={**dict(stored.extra), **dict(given.extra)},
    )


def catalogue_inputs(joint_file: Path, given, *, joint_type: str | None = None, model_kind: str | None = None,
                     method: str | None = None, quality: dict[str, float] | None = None,
                     author: str | None = None, force: bool = False, root: Path | None = None) -> dict[str, Any]:
    """What ``jointdb catalogue`` (and the HTTP service's catalogue route) stores from a joint file.

    Reads the file, takes model kind, joint type, method, quality and conditions from it,
    completed by the given options (``given`` conditions are merged by
    :func:`merge_conditions`). With ``root`` (the HTTP service: an unpacked upload) a
    campaign file may only name files inside that folder. Returns the keyword arguments of
    :meth:`jointdb.store.Repository.catalogue` except ``name``, ``parent``, ``label``.

    Raises
    ------
    InputError
        A file without joint type or model kind (and none given), a conflict of
        conditions, or any value the catalogue would refuse.
    """
    from jointdb.store import Provenance
    from jointdb.store._types import check_joint_type, check_model_kind

    frf, meta, hashes, raw = _read_joint_file(joint_file, root)
    kind = model_kind or meta.get("model_kind") or _JOINT_MODEL_KINDS.get(str(meta.get("joint_model")))
    if not kind:
        raise InputError(f"{joint_file}: the file does not say its joint model; give --model-kind")
    jtype = joint_type or meta.get("joint_type")
    if not jtype:
        raise InputError(f"{joint_file}: the file does not say its joint type; give --type")
    q = _numeric_metrics(meta.get("quality"))
    q.update(quality or {})
    params = {k: meta[k] for k in ("settings", "interface", "campaign", "uncertainty") if k in meta}
    file_method = meta.get("method") or (f"irc-{meta['joint_model']}" if meta.get("joint_model") else None)
    prov = Provenance(
        method=method or str(file_method or "imported-file"),
        parameters=json.loads(json.dumps(params, default=str)),
        input_files=hashes,
        author=author or "",
    )
    conditions = merge_conditions(joint_file, meta.get("conditions"), given, force)
    return {"joint_type": check_joint_type(jtype), "frf": frf, "conditions": conditions,
            "model_kind": check_model_kind(kind, frf), "provenance": prov, "quality": q, "raw_frfs": raw}

