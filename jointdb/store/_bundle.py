"""Portable HDF5 bundles: export joints with all versions, import them elsewhere.

Bundle layout (``format = "jointdb-bundle"``, ``format_version = 2``)::

    /                      attrs: format, format_version, exported_at, software_version,
                                  bundle_sha256, [signature, signer_public_key]
    /joints/jNNNN          attrs: name, joint_type, created_at, created_by,
                                  labels (JSON {label: version}), states (JSON list)
    /joints/jNNNN/vNNNN    attrs: record (JSON, the full version record incl.
                                  provenance), record_sha256
        frf/               the joint FRF in the blob layout (jointdb.store._blobs)
        raw/<key>/         raw measurement FRFs, same layout

``bundle_sha256`` covers every joint's name, type, creation, labels, states and
record hashes (:func:`jointdb.store._bundle_read.manifest_sha256`); each record
hash covers the record including its FRF hashes. ``signature`` (optional) is an
Ed25519 signature of that hash (:mod:`jointdb.store._signing`), so an edit with
every hash recomputed is still refused by ``--require-signature``. A hash only
detects damage; only a signature from a trusted key says who exported it.

Import reads and verifies the whole bundle first
(:func:`jointdb.store._bundle_read.read_bundle`: every hash, every field with
the catalogue's own rules, the signature), then compares with the target
database: a version that exists there with the same uuid and record hash is a
no-op; a version number that exists with different content, a joint name with
another joint type, or a gap in the numbering raises :class:`ConflictError`
and nothing is written. Every new version must be the same joint as the version
before it (the target's latest one, or the bundle's previous one): a contradiction of a
defining condition (:mod:`jointdb.store._identity`) is refused unless ``force``, and
the import's audit entry then lists each change. Labels are imported only where the target has no such
label yet. Format version 1 bundles (no bundle hash) are still read, but their
labels and states are covered by no hash.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterable
from datetime import datetime
from types import SimpleNamespace
from typing import TYPE_CHECKING, Any

from sqlalchemy import select

from jointdb.errors import ConflictError, InputError, IntegrityError
from jointdb.io._atomic import atomic_path
from jointdb.store._access import joint_row, read_session
from jointdb.store._blobformat import write_frf_group
from jointdb.store._bundle_read import FORMAT, FORMAT_VERSION, Bundle, manifest_sha256, read_bundle
from jointdb.store._identity import describe, identity_changes
from jointdb.store._index import refresh_joints
from jointdb.store._models import AuditRow, JointRow, LabelRow, StateRow, VersionRow, utcnow
from jointdb.store._records import check_record, current_actor, record_dict, row_from_record

if TYPE_CHECKING:  # pragma: no cover
    from jointdb.store._protocol import ReadAccess, WriteAccess


def export_bundle(store: "ReadAccess", names: Iterable[str] | None, path: str | os.PathLike,
                  sign_key=None) -> dict[str, Any]:
    """Write the named joints (all when ``names`` is None) to ``path``; returns counts.

    ``sign_key``: an Ed25519 private key (:func:`jointdb.store._signing.load_private_key`)
    to sign the bundle hash with. Every record hash is checked before writing.
    """
    import h5py

    from jointdb import __version__

    with read_session(store) as s:
        if names is None:
            joints = list(s.scalars(select(JointRow).order_by(JointRow.name)))
        else:
            joints = [joint_row(s, n) for n in dict.fromkeys(names)]
        if not joints:
            raise InputError("nothing to export: no joints selected")
        plan = []
        for j in joints:
            rows = list(s.scalars(select(VersionRow).where(VersionRow.joint_id == j.id).order_by(VersionRow.version)))
            labels = {lab.label: lab.version for lab in s.scalars(select(LabelRow).where(LabelRow.joint_id == j.id))}
            states = [
                {"version": st.version, "state": st.state, "reason": st.reason, "author": st.author,
                 "at": st.at.isoformat(timespec="microseconds")}
                for st in s.scalars(select(StateRow).where(StateRow.joint_id == j.id).order_by(StateRow.id))
            ]
            records = []
            for r in rows:
                check_record(j.name, j.joint_type, r)  # IntegrityError: nothing is written
                records.append((record_dict(j.name, j.joint_type, r), r.record_sha256))
            plan.append((j, records, labels, states))
    digest = manifest_sha256([
        {"name": j.name, "joint_type": j.joint_type, "created_at": j.created_at.isoformat(timespec="microseconds"),
         "created_by": j.created_by, "labels": labels, "states": states,
         "versions": [{"record": rec, "digest": d} for rec, d in records]}
        for j, records, labels, states in plan
    ])
    signature = None
    if sign_key is not None:
        from jointdb.store._signing import fingerprint, sign_digest

        signature = sign_digest(sign_key, digest)
    n_versions = 0
    with atomic_path(path) as tmp, h5py.File(tmp, "w") as f:  # a failure leaves no partial file
        f.attrs["format"] = FORMAT
        f.attrs["format_version"] = FORMAT_VERSION
        f.attrs["exported_at"] = utcnow().isoformat()
        f.attrs["software_version"] = __version__
        f.attrs["bundle_sha256"] = digest
        if signature is not None:
            f.attrs["signature"], f.attrs["signer_public_key"] = signature
        root = f.create_group("joints")
        for i, (j, records, labels, states) in enumerate(plan):
            g = root.create_group(f"j{i:04d}")
            g.attrs["name"] = j.name
            g.attrs["joint_type"] = j.joint_type
            g.attrs["created_at"] = j.created_at.isoformat(timespec="microseconds")
            g.attrs["created_by"] = j.created_by
            g.attrs["labels"] = json.dumps(labels, sort_keys=True)
            g.attrs["states"] = json.dumps(states)
            for record, record_digest in records:
                vg = g.create_group(f"v{record['version']:04d}")
                vg.attrs["record"] = json.dumps(record, sort_keys=True)
                vg.attrs["record_sha256"] = record_digest
                write_frf_group(vg.create_group("frf"), store.blobs.get(record["blob_sha256"]), record["blob_sha256"])
                for key, raw_digest in record["raw_blobs"].items():
                    rg = vg.require_group("raw").create_group(key)
                    write_frf_group(rg, store.blobs.get(raw_digest), raw_digest)
                n_versions += 1
    out: dict[str, Any] = {"joints": len(plan), "versions": n_versions, "bundle_sha256": digest}
    if signature is not None:
        out["signed_by"] = fingerprint(bytes.fromhex(signature[1]))
    return out


def _plan(session, joints: list[dict[str, Any]], force: bool = False) -> list[tuple[dict, list[dict], list]]:
    """Which versions are new, and the forced changes among them; ConflictError on any
    contradiction with the database (or, without ``force``, of a defining condition)."""
    plan = []
    for j in joints:
        row = session.scalar(select(JointRow).where(JointRow.name == j["name"]))
        existing: dict[int, VersionRow] = {}
        if row is not None:
            if row.joint_type != j["joint_type"]:
                raise ConflictError(
                    f"joint {j['name']!r} is a {row.joint_type} joint here but {j['joint_type']} in the bundle"
                )
            existing = {v.version: v for v in session.scalars(select(VersionRow).where(VersionRow.joint_id == row.id))}
        new = []
        for v in j["versions"]:
            rec = v["record"]
            have = existing.get(rec["version"])
            if have is not None:
                if have.uuid != rec["uuid"] or have.record_sha256 != v["digest"]:
                    raise ConflictError(
                        f"joint {j['name']!r} version {rec['version']} already exists here with different content "
                        f"(uuid {have.uuid} here, {rec['uuid']} in the bundle); nothing imported"
                    )
                continue
            other = session.scalar(select(VersionRow).where(VersionRow.uuid == rec["uuid"]))
            if other is not None:
                raise ConflictError(f"version uuid {rec['uuid']} already exists here under another joint or number")
            new.append(v)
        if new and new[0]["record"]["version"] != len(existing) + 1:
            raise ConflictError(
                f"joint {j['name']!r}: the bundle continues at version {new[0]['record']['version']} but this "
                f"database has versions 1..{len(existing)} with other content"
            )
        plan.append((j, new, _forced(j["name"], existing.get(len(existing)), new, force)))
    return plan


def _as_identity(record: dict[str, Any]) -> SimpleNamespace:
    c = record["conditions"]
    return SimpleNamespace(version=record["version"], materials=c["materials"], preload_n=c["preload_n"],
                           torque_nm=c["torque_nm"], geometry=c["geometry"], model_kind=record["model_kind"],
                           dofs=record["dofs"])


def _forced(name: str, latest: VersionRow | None, new: list[dict], force: bool) -> list[dict[str, Any]]:
    """Each new version against the one before it (this database's latest, then the bundle's own).

    Returns the changes a ``force`` lets through (for the audit entry).

    Raises
    ------
    ConflictError
        A defining condition changes and ``force`` is not given.
    """
    forced = []
    prev = latest
    for v in new:
        rec = _as_identity(v["record"])
        if prev is not None:
            changes, _ = identity_changes(prev, vars(rec))
            if changes and not force:
                raise ConflictError(f"bundle: joint {name!r} v{rec.version} is not the same joint as v{prev.version} "
                                    f"({describe(changes, prev.version)}); nothing imported (--force imports it)")
            forced += [{**c, "version": rec.version, "of_version": prev.version} for c in changes]
        prev = rec
    return forced


def import_bundle(store: "WriteAccess", bundle: "Bundle | str | os.PathLike", author: str | None = None,
                  trusted_keys=(), require_signature: bool = False, force: bool = False) -> dict[str, Any]:
    """Import a bundle (module docstring); returns counts of new and unchanged versions.

    ``bundle``: a path, or a :class:`Bundle` already read with :func:`read_bundle`
    (the command line reads it before opening, and maybe creating, the database).
    """
    if not isinstance(bundle, Bundle):
        bundle = read_bundle(bundle, trusted_keys, require_signature)
    elif require_signature and not bundle.signature_verified:
        raise IntegrityError(f"{bundle.path}: the bundle is not signed by a trusted key")
    joints = bundle.joints
    path = bundle.path
    with read_session(store) as s:
        plan = _plan(s, joints, force)  # refuse conflicts before touching anything
    for _, new, _ in plan:
        for v in new:
            store.blobs.put(v["frf"])
            for raw in v["raw"].values():
                store.blobs.put(raw)
    actor = current_actor(author)
    summary: dict[str, Any] = {"joints": len(joints), "new_versions": 0, "unchanged_versions": 0, "labels_skipped": [],
                               "signed_by": bundle.signer, "signature_verified": bundle.signature_verified}

    def write(s) -> None:
        summary["new_versions"] = summary["unchanged_versions"] = 0
        summary["labels_skipped"] = []
        now = utcnow()
        touched: list[int] = []
        for j, new, forced in _plan(s, joints, force):
            row = s.scalar(select(JointRow).where(JointRow.name == j["name"]))
            if row is None:
                row = JointRow(name=j["name"], joint_type=j["joint_type"],
                               created_at=datetime.fromisoformat(j["created_at"]), created_by=j["created_by"])
                s.add(row)
                s.flush()
            for v in new:
                s.add(row_from_record(v["record"], row.id))
            s.flush()
            touched.append(row.id)
            summary["new_versions"] += len(new)
            summary["unchanged_versions"] += len(j["versions"]) - len(new)
            have_labels = {lab.label: lab.version for lab in s.scalars(select(LabelRow).where(LabelRow.joint_id == row.id))}
            for label, version in j["labels"].items():
                if label in have_labels:
                    if have_labels[label] != int(version):
                        summary["labels_skipped"].append(f"{j['name']}:{label}")
                    continue
                s.add(LabelRow(joint_id=row.id, label=label, version=int(version), updated_at=now, updated_by=actor))
            have_states = {
                (st.version, st.state, st.at.isoformat(timespec="microseconds"))
                for st in s.scalars(select(StateRow).where(StateRow.joint_id == row.id))
            }
            for st in j["states"]:
                key = (st["version"], st["state"], datetime.fromisoformat(st["at"]).isoformat(timespec="microseconds"))
                if key not in have_states:
                    s.add(StateRow(joint_id=row.id, version=st["version"], state=st["state"], reason=st["reason"],
                                   author=st["author"], at=datetime.fromisoformat(st["at"])))
            if new:
                s.add(AuditRow(at=now, actor=actor, action="import", joint_name=j["name"], version=None,
                               details={"bundle": os.fspath(path), "bundle_sha256": bundle.digest,
                                        "signed_by": bundle.signer if bundle.signature_verified else None,
                                        "versions": [v["record"]["version"] for v in new],
                                        **({"forced": forced} if forced else {})}))
        s.flush()
        refresh_joints(s, touched)  # the query index, in the same transaction

    store.retrying(write)
    return summary
