"""CLI for the joint database: ``catalogue``, ``joints ...``, ``query`` (``db ...``: :mod:`jointdb.cli._db`).

Thin: parse options, call :mod:`jointdb.store`, render with :func:`jointdb.cli._output.emit`.
Every command takes ``--db URL`` (or a SQLite path; default ``JOINTDB_URL`` or
the per-user database) and ``--json``.
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path
from typing import Annotated, Any, Optional

import typer

from jointdb.cli._output import emit, message
from jointdb.cli._target import BlobsOpt, DbOpt, JsonOpt, check_db_target, open_local_repo, open_repo, refuse_server
from jointdb.errors import InputError, IntegrityError, NotFoundError

def _check_output(path: Path | None) -> None:
    """Refuse an output file whose directory does not exist before any work (or warning) is done."""
    if path is not None and not path.parent.is_dir():
        raise InputError(f"cannot write {path}: directory {path.parent} does not exist")
    if path is not None and path.is_dir():
        raise InputError(f"cannot write {path}: it is a directory")


def _pairs(items: list[str] | None, what: str, numeric: bool = True) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for item in items or []:
        if "=" not in item:
            raise InputError(f"{what} {item!r} must look like key=value")
        key, value = item.split("=", 1)
        key = key.strip()
        if numeric:
            try:
                out[key] = float(value)
            except ValueError:
                raise InputError(f"{what} {key}: {value!r} is not a number (SI units)") from None
        else:
            try:
                out[key] = json.loads(value)
            except json.JSONDecodeError:
                out[key] = value
    return out


def _conditions(materials, preload, torque, geometry, extra=None):
    from jointdb.store import Conditions

    mats: list[str] = []
    for m in materials or []:
        mats.extend(x for x in m.replace("+", ",").split(",") if x.strip())
    return Conditions(
        materials=tuple(mats),
        preload_n=preload,
        torque_nm=torque,
        geometry=_pairs(geometry, "--geometry"),
        extra=_pairs(extra, "--extra", numeric=False),
    )


#: columns of version tables for people (``--json`` has every field)
_TABLE = ["name", "version", "state", "labels", "materials", "torque_nm", "preload_n"]


def _refuse_damaged(damaged: list) -> None:
    """After a list was printed: exit 5 naming the versions it left out because their rows are damaged."""
    if damaged:
        names = ", ".join(f"{d.name} v{d.version}" for d in damaged[:10]) + (" ..." if len(damaged) > 10 else "")
        raise IntegrityError(f"{len(damaged)} damaged version(s) left out of the list: {names} "
                             f"({damaged[0].reason.split(';')[0]}); run `jointdb db check`")


def _version_row(v) -> dict[str, Any]:
    return v.summary()


def _version_detail(v) -> dict[str, Any]:
    c, p = v.conditions, v.provenance
    return {
        "name": v.name,
        "joint_type": v.joint_type,
        "version": v.version,
        "state": v.state,
        "labels": ", ".join(v.labels) or None,
        "uuid": v.uuid,
        "created_at": v.created_at.isoformat(),
        "materials": " + ".join(c.materials) or None,
        "preload_n": c.preload_n,
        "torque_nm": c.torque_nm,
        "geometry": json.dumps(c.geometry) if c.geometry else None,
        "extra": json.dumps(c.extra) if c.extra else None,
        "model_kind": v.model_kind,
        "dofs": " ".join(v.dofs),
        "frequency_hz": f"{v.freq_min_hz:g} - {v.freq_max_hz:g} ({v.n_freq} lines)",
        "blob_sha256": v.blob_sha256,
        "method": p.method,
        "parameters": json.dumps(p.parameters) if p.parameters else None,
        "input_files": json.dumps(p.input_files) if p.input_files else None,
        "software_version": p.software_version,
        "author": p.author,
        "parent_version": v.parent_version,
        "quality": json.dumps(dict(v.quality)) if v.quality else None,
    }


def catalogue(
    joint_file: Annotated[Path, typer.Argument(help="Identified joint (HDF5 file from `jointdb identify`) or a campaign JSON file.")],
    name: Annotated[str, typer.Option("--name", help="Joint name (new joint, or new version of it).")],
    joint_type: Annotated[Optional[str], typer.Option("--type", help="Joint type, e.g. tool-holder (default: from the file).")] = None,
    material: Annotated[Optional[list[str]], typer.Option("--material", help="Interface material (repeat, or a+b).")] = None,
    preload: Annotated[Optional[float], typer.Option("--preload", help="Preload [N].")] = None,
    torque: Annotated[Optional[float], typer.Option("--torque", help="Tightening torque [N·m].")] = None,
    geometry: Annotated[Optional[list[str]], typer.Option("--geometry", help="Geometry number key=value in SI, e.g. diameter_m=0.02 (repeat).")] = None,
    extra: Annotated[Optional[list[str]], typer.Option("--extra", help="Free-form condition key=value (repeat).")] = None,
    model_kind: Annotated[Optional[str], typer.Option("--model-kind", help="spring-damper-planar | n-point-translational | full-matrix (default: from the file).")] = None,
    method: Annotated[Optional[str], typer.Option("--method", help="Identification method (default: from the file).")] = None,
    quality: Annotated[Optional[list[str]], typer.Option("--quality", help="Quality metric key=value (repeat).")] = None,
    parent: Annotated[Optional[int], typer.Option("--parent", help="Version this one corrects (default: latest).")] = None,
    author: Annotated[Optional[str], typer.Option("--author", help="Author (default: $JOINTDB_AUTHOR or login).")] = None,
    label: Annotated[Optional[str], typer.Option("--label", help="Also point this label at the new version.")] = None,
    force: Annotated[bool, typer.Option("--force", help="Store the options' conditions even where they contradict the values the file records, or those of the joint's previous version (the audit log records the change).")] = False,
    allow_identical: Annotated[bool, typer.Option("--allow-identical", help="Add a version even when the latest one already holds the same FRF and conditions.")] = False,
    db: DbOpt = None,
    blobs: BlobsOpt = None,
    as_json: JsonOpt = False,
) -> None:
    """Catalogue an identified joint FRF as a new immutable version.

    The conditions the file records are kept; options fill in what it does not
    record, and an option that contradicts the file is refused unless --force.
    A new version must be the same joint as the previous one: materials, preload,
    torque, geometry, model kind and DOFs it recorded must not change (values it did
    not record may be filled in); a change is refused unless --force.
    A file identical to the joint's latest version (same FRF and conditions) is
    reported as "identical to vN" and nothing is written, unless --allow-identical.
    The version and its --label are written together or not at all.
    Example: jointdb catalogue joint.h5 --name T1-HSK63 --type tool-holder
    --material carbide --material steel --torque 40 --geometry diameter_m=0.02
    """
    from jointdb.usecases import catalogue_inputs
    from jointdb.store._types import check_label, check_name

    args = catalogue_inputs(joint_file, _conditions(material, preload, torque, geometry, extra),
                            joint_type=joint_type, model_kind=model_kind, method=method,
                            quality=_pairs(quality, "--quality"), author=author, force=force)
    # everything the library would refuse is refused before the database is opened (or created)
    check_name(name)
    if label is not None:
        label = check_label(label)
    if parent is not None and parent < 1:
        raise InputError(f"--parent must be a version number >= 1, got {parent}")
    repo = open_repo(db, blobs, create=True)
    jv, created = repo.catalogue_outcome(name, parent=parent, author=author, label=label, force=force,
                                         allow_identical=allow_identical, **args)
    if not created:
        message(f"{jv.name}: identical to v{jv.version} (same FRF and conditions); nothing written "
                "(--allow-identical adds a version anyway)")
        if label is not None:
            message(f"--label not applied; `jointdb joints label {jv.name} {jv.version} {label}` "
                    "points it at that version")
        emit(_version_detail(jv), as_json=as_json, title=f"{jv.name} v{jv.version}")
        return
    message(f"catalogued {jv.name} v{jv.version} ({jv.blob_sha256[:12]})")
    emit(_version_detail(jv), as_json=as_json, title=f"{jv.name} v{jv.version}")


def query(
    joint_type: Annotated[str, typer.Option("--type", help="Joint type to search (types are never mixed).")],
    material: Annotated[Optional[list[str]], typer.Option("--material", help="Interface material (repeat, or a+b).")] = None,
    preload: Annotated[Optional[float], typer.Option("--preload", help="Preload [N].")] = None,
    torque: Annotated[Optional[float], typer.Option("--torque", help="Tightening torque [N·m].")] = None,
    geometry: Annotated[Optional[list[str]], typer.Option("--geometry", help="Geometry key=value in SI (repeat).")] = None,
    k: Annotated[int, typer.Option("-k", help="Number of nearest versions.")] = 3,
    at: Annotated[Optional[str], typer.Option("--at", help="Query the catalogue as it was at this ISO time.")] = None,
    label: Annotated[Optional[str], typer.Option("--label", help="Only versions carrying this label, e.g. released.")] = None,
    all_versions: Annotated[bool, typer.Option("--all-versions", help="Rank every version, not only the newest of each joint.")] = False,
    include_deprecated: Annotated[bool, typer.Option("--include-deprecated", help="Also rank deprecated versions (excluded by default).")] = False,
    interpolate: Annotated[Optional[Path], typer.Option("--interpolate", help="Also write the joint interpolated between the matches that bracket the request along its conditions (dynamic stiffness, barycentric weights) to this HDF5 file.")] = None,
    out: Annotated[Optional[Path], typer.Option("--out", help="Write the matches (one row each) to .csv, .json or .h5.")] = None,
    db: DbOpt = None,
    blobs: BlobsOpt = None,
    as_json: JsonOpt = False,
) -> None:
    """Find the k catalogued joints closest to given conditions (distance per condition).

    By default each joint's newest version that is not deprecated ranks.
    Example: jointdb query --type tool-holder --material carbide+steel --torque 35 -k 3 --label released
    """
    from jointdb.cli._options import check_out

    _check_output(interpolate)
    check_out(out, (".csv", ".json", ".h5", ".hdf5"))
    req = _conditions(material, preload, torque, geometry)
    selection = {"label": label, "all_versions": all_versions, "include_deprecated": include_deprecated}
    from jointdb.store._light import nearest_in_file, nearest_on_postgres, postgres_target, sqlite_target

    remote = db is None and bool(__import__("os").environ.get("JOINTDB_SERVER"))
    fast = interpolate is None and at is None and not remote
    light = sqlite_target(db) if fast else None
    pg = postgres_target(db) if fast and light is None else None
    repo = None if light is not None or pg is not None else open_repo(db, blobs)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        if light is not None:  # a SQLite file: rank without loading SQLAlchemy (fast start)
            matches = nearest_in_file(light, joint_type, req, k=k, **selection)
        elif pg is not None:  # PostgreSQL: psycopg directly, likewise
            matches = nearest_on_postgres(pg, joint_type, req, k=k, **selection)
        else:
            matches = repo.nearest(joint_type, req, k=k, at=at, **selection)
    damaged = [w for w in caught if w.category.__name__ == "DamagedRecordWarning"]  # no store import here
    for w in caught if not damaged else ():  # with damaged versions, one error line says it (below)
        message(f"warning: {w.message}")
    rows = []
    for m in matches:
        row = {"name": m.version.name, "version": m.version.version, "distance": m.distance}
        row.update({f"d_{key}": val for key, val in m.per_condition.items()})
        c = m.version.conditions
        row.update({"materials": "+".join(c.materials) or None, "torque_nm": c.torque_nm,
                    "preload_n": c.preload_n, "extrapolating": m.extrapolating,
                    "state": m.version.state, "labels": ", ".join(m.version.labels) or None})
        rows.append(row)
    result: Any = rows
    if out is not None:
        from jointdb.cli._output import write_rows

        write_rows(out, rows, kind="matches", meta={"joint_type": joint_type, "request": req.to_dict()})
        message(f"wrote {out} ({len(rows)} matches)")
    if interpolate is not None:
        from jointdb.usecases import write_joint_file

        ij = repo.interpolate(matches, req)
        write_joint_file(interpolate, ij.frf, {
            "model_kind": matches[0].version.model_kind, "joint_type": ij.joint_type,
            "conditions": req.to_dict(), "interpolated": True, "method": "interpolated-dynamic-stiffness",
            "neighbours": [{"name": n, "version": v, "weight": w} for n, v, w in ij.neighbours]})
        message(f"{ij.describe()} -> {interpolate}")
        if as_json:
            result = {"matches": rows, "interpolated": {"file": str(interpolate), "label": ij.label,
                      "neighbours": [{"name": n, "version": v, "weight": w} for n, v, w in ij.neighbours]}}
    d_cols = [c for c in (rows[0] if rows else {}) if c.startswith("d_")]
    emit(result, as_json=as_json, title=f"nearest {joint_type} joints (distance = sqrt(sum d_i^2))",
         columns=["name", "version", *(["state"] if include_deprecated else []), "distance", *d_cols,
                  *[c for c in ("materials", "torque_nm", "preload_n", "labels")
                    if any(r.get(c) is not None for r in rows)],
                  *(["extrapolating"] if any(r.get("extrapolating") for r in rows) else [])])
    if damaged:  # the matches shown are the intact ones; exit 5 naming what was skipped
        raise IntegrityError(" ".join(str(damaged[0].message).split()))


def list_(
    joint_type: Annotated[Optional[str], typer.Option("--type", help="Only this joint type.")] = None,
    db: DbOpt = None, blobs: BlobsOpt = None, as_json: JsonOpt = False,
) -> None:
    """List joints with their current version. Example: jointdb joints list --type tool-holder"""
    damaged: list = []
    emit([_version_row(v) for v in open_repo(db, blobs).list_joints(joint_type, damaged=damaged)], as_json=as_json,
         title="joints", columns=["name", "type", "version", "state", "materials", "torque_nm"])
    _refuse_damaged(damaged)


def show(
    name: Annotated[str, typer.Argument(help="Joint name.")],
    version: Annotated[Optional[int], typer.Option("--version", help="Pinned version number.")] = None,
    at: Annotated[Optional[str], typer.Option("--at", help="Version current at this ISO time.")] = None,
    label: Annotated[Optional[str], typer.Option("--label", help="Version a label points at.")] = None,
    frf_out: Annotated[Optional[Path], typer.Option("--frf-out", help="Write the joint FRF (verified) to this HDF5 file.")] = None,
    db: DbOpt = None, blobs: BlobsOpt = None, as_json: JsonOpt = False,
) -> None:
    """Show one version (latest, pinned, at a time, or by label). Example: jointdb joints show T1 --version 2"""
    _check_output(frf_out)
    repo = open_repo(db, blobs)
    jv = repo.get(name, version=version, at=at, label=label)
    if frf_out is not None:
        from jointdb.usecases import write_joint_file

        write_joint_file(frf_out, repo.load_frf(jv), {
            "model_kind": jv.model_kind, "joint_type": jv.joint_type, "conditions": jv.conditions.to_dict(),
            "catalogue": {"name": jv.name, "version": jv.version, "uuid": jv.uuid, "blob_sha256": jv.blob_sha256},
            "quality": dict(jv.quality)})
        message(f"wrote {jv.name} v{jv.version} FRF to {frf_out}")
    from jointdb.cli._joint_summary import constant_kc, kc_rows_for_people, readable

    kc = constant_kc(repo.load_frf(jv))
    detail = _version_detail(jv)
    if as_json:
        emit(detail | {"constant_kc": kc}, as_json=True)
        return
    emit({k: readable(v) for k, v in detail.items()}, title=f"{jv.name} v{jv.version}")
    if kc is not None:
        kc_rows = kc_rows_for_people(kc)
        emit(kc_rows, columns=list(dict.fromkeys(c for r in kc_rows for c in r)), title=f"constant k, c per DOF: {kc['method']} "
             f"({kc['band_hz'][0]:g}–{kc['band_hz'][1]:g} Hz, {kc['n_lines']} lines)")


def history(name: Annotated[str, typer.Argument(help="Joint name.")],
            db: DbOpt = None, blobs: BlobsOpt = None, as_json: JsonOpt = False) -> None:
    """All versions of a joint, oldest first. Example: jointdb joints history T1"""
    damaged: list = []
    emit([_version_row(v) for v in open_repo(db, blobs).history(name, damaged=damaged)], as_json=as_json,
         title=f"history of {name}", columns=_TABLE + ["created_at"])
    _refuse_damaged(damaged)


def diff(
    name: Annotated[str, typer.Argument(help="Joint name.")],
    version_a: Annotated[int, typer.Argument(help="First version.")],
    version_b: Annotated[Optional[int], typer.Argument(help="Second version (default: current).")] = None,
    other: Annotated[Optional[str], typer.Option("--other", help="Compare with a version of another joint.")] = None,
    db: DbOpt = None, blobs: BlobsOpt = None, as_json: JsonOpt = False,
) -> None:
    """Differences of conditions, metadata and FRF (max relative difference per entry).

    Example: jointdb joints diff T1 1 2
    """
    d = open_repo(db, blobs).diff(name, version_a, version_b, other)
    if as_json:
        emit(d, as_json=True)
        return
    rows = [{"what": k, "a": a, "b": b} for k, (a, b) in {**d.conditions, **d.fields}.items()]
    emit(rows or "no differences in conditions or metadata", title=f"{d.a} vs {d.b}")
    emit(list(d.frf_entries), columns=["output", "input", "max_rel_diff"], title="FRF: max |Hb-Ha| / peak |Ha|")
    for note in d.notes:
        message(note)


def label_(
    name: Annotated[str, typer.Argument(help="Joint name.")],
    version: Annotated[int, typer.Argument(help="Version the label should point at.")],
    label: Annotated[str, typer.Argument(help="Label, e.g. released.")],
    author: Annotated[Optional[str], typer.Option("--author")] = None,
    db: DbOpt = None, blobs: BlobsOpt = None, as_json: JsonOpt = False,
) -> None:
    """Point a label at a version (create or move it). Example: jointdb joints label T1 2 released"""
    jv = open_repo(db, blobs).label(name, version, label, author=author)
    emit({k: v for k, v in _version_row(jv).items() if k in _TABLE}, as_json=as_json)


def deprecate(
    name: Annotated[str, typer.Argument(help="Joint name.")],
    version: Annotated[Optional[int], typer.Option("--version", help="Only this version (default: the whole joint).")] = None,
    reason: Annotated[str, typer.Option("--reason", help="Why (kept in the record).")] = "",
    undo: Annotated[bool, typer.Option("--undo", help="Mark active again.")] = False,
    author: Annotated[Optional[str], typer.Option("--author")] = None,
    db: DbOpt = None, blobs: BlobsOpt = None, as_json: JsonOpt = False,
) -> None:
    """Deprecate a joint or version (nothing is deleted). Example: jointdb joints deprecate T1 --version 1 --reason 'loose bolt'"""
    hist = open_repo(db, blobs).deprecate(name, version, reason=reason, author=author, undo=undo)
    emit([_version_row(v) for v in hist], as_json=as_json, title=f"history of {name}", columns=_TABLE)


def export(
    bundle: Annotated[Path, typer.Argument(help="Bundle file to write (HDF5).")],
    names: Annotated[Optional[list[str]], typer.Argument(help="Joint names (default: all).")] = None,
    sign: Annotated[Optional[Path], typer.Option("--sign", help="Sign the bundle with this Ed25519 private key (`jointdb keys create`).")] = None,
    db: DbOpt = None, blobs: BlobsOpt = None, as_json: JsonOpt = False,
) -> None:
    """Export joints with all versions, provenance, labels and states to one portable HDF5 bundle.

    Example: jointdb joints export lab.h5 T1 T2 --sign lab-key
    """
    key = None
    if sign is not None:
        from jointdb.store._signing import load_private_key

        key = load_private_key(sign)  # before anything is read or written
    counts = open_local_repo(db, blobs, "joints export").export(names or None, bundle, sign_key=key)
    emit({"bundle": str(bundle), **counts}, as_json=as_json)


def import_(
    bundle: Annotated[Path, typer.Argument(help="Bundle file written by `jointdb joints export`.")],
    author: Annotated[Optional[str], typer.Option("--author")] = None,
    require_signature: Annotated[bool, typer.Option("--require-signature", help="Refuse a bundle not signed by a --trust key.")] = False,
    trust: Annotated[Optional[list[Path]], typer.Option("--trust", help="Trusted Ed25519 public key (NAME.pub; repeat); the bundle must be signed by one of them.")] = None,
    force: Annotated[bool, typer.Option("--force", help="Import versions that change a defining condition of the version before them (the audit log records the change).")] = False,
    db: DbOpt = None, blobs: BlobsOpt = None, as_json: JsonOpt = False,
) -> None:
    """Import a bundle: identical versions are no-ops, conflicting ones are refused.

    Any --trust key means the signature is verified: an unsigned or badly signed bundle
    is refused. Without --trust the signature is not checked and no signer is shown.
    A new version that is not the same joint as the one before it is refused unless --force.

    The whole bundle (hashes, fields, labels, states, signature) is verified
    before the database is opened, so a refused bundle creates nothing.
    Example: jointdb joints import lab.h5 --require-signature --trust lab-key.pub --db other.sqlite
    """
    from jointdb.store._bundle_read import read_bundle
    from jointdb.store._signing import load_public_key

    keys = [load_public_key(p) for p in trust or []]
    refuse_server(db, "joints import")
    check_db_target(db, create=True)  # a bad --db is reported before the bundle is read
    verified = read_bundle(bundle, keys, require_signature)
    summary = open_repo(db, blobs, create=True).import_(verified, author=author, force=force)
    for note in verified.notes:  # after the import: a refusal stays one line
        message(note)
    summary["labels_skipped"] = ", ".join(summary["labels_skipped"]) or None
    emit(summary, as_json=as_json)


#: ``jointdb joints ...``: the command name and the function that implements it
JOINTS_COMMANDS = (
    ("list", list_),
    ("show", show),
    ("history", history),
    ("diff", diff),
    ("label", label_),
    ("deprecate", deprecate),
    ("export", export),
    ("import", import_),
)


def register(app: typer.Typer) -> None:
    """Add ``catalogue``, ``query``, ``joints ...`` and ``keys ...`` to the app (``db ...`` is in :mod:`jointdb.cli._db`)."""
    from jointdb.cli import _keys

    joints = typer.Typer(help="List, inspect, label, deprecate, diff, export and import catalogued joints.",
                         no_args_is_help=True)
    app.add_typer(joints, name="joints")
    app.command("catalogue")(catalogue)
    app.command("query")(query)
    for name, command in JOINTS_COMMANDS:
        joints.command(name)(command)
    _keys.register(app)
