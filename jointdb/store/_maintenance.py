"""Integrity check, garbage collection and version diffs."""

from __future__ import annotations

import contextlib
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
from sqlalchemy import select
from sqlalchemy.orm import Session

from jointdb.errors import IntegrityError, NotFoundError
from jointdb.frf import FRF
from jointdb.store._access import read_session
from jointdb.store._models import AuditRow, JointRow, PartRow, PartVersionRow, VersionRow, utcnow
from jointdb.store._records import DamagedJSON, check_record, current_actor
from jointdb.store._reports import CheckReport, VersionDiff
from jointdb.store._types import JointVersion

if TYPE_CHECKING:  # pragma: no cover
    from jointdb.store._protocol import ReadAccess, WriteAccess

#: what :func:`diff_versions` needs of a store: the verified FRF of a version
LoadFRF = Callable[[JointVersion], FRF]


def _references(s, strict: bool = False) -> dict[str, list[str]]:
    """blob sha -> list of "name vN" rows referencing it (in the session's snapshot).

    ``strict`` (garbage collection): a row whose ``raw_blobs`` column cannot be read is an
    IntegrityError, since the blobs it names cannot be known and must not be collected.
    """
    refs: dict[str, list[str]] = {}
    q = select(JointRow.name, VersionRow.version, VersionRow.blob_sha256, VersionRow.raw_blobs).join(
        JointRow, JointRow.id == VersionRow.joint_id
    )
    for name, version, blob, raw in s.execute(q):
        if strict and (isinstance(raw, DamagedJSON) or not isinstance(raw, (dict, type(None)))):
            raise IntegrityError(f"db gc refused: joint {name!r} v{version} has a damaged raw_blobs column, so the "
                                 "blobs it references are unknown; nothing was collected (run `jointdb db check`)")
        refs.setdefault(blob, []).append(f"{name} v{version}")
        for key, digest in (raw or {}).items():
            refs.setdefault(digest, []).append(f"{name} v{version} raw {key}")
    q = select(PartRow.name, PartVersionRow.version, PartVersionRow.blob_sha256).join(
        PartRow, PartRow.id == PartVersionRow.part_id).where(PartVersionRow.blob_sha256.is_not(None))
    for name, version, blob in s.execute(q):  # a measured spindle's FRF set (migration 0009)
        refs.setdefault(blob, []).append(f"part {name} v{version}")
    return refs


def _referenced(store: "ReadAccess") -> dict[str, list[str]]:
    """blob sha -> list of "name vN" rows referencing it."""
    with read_session(store) as s:
        return _references(s, strict=True)


def _part_problems(s, problems: list[str]) -> int:
    """Check every part version's record hash (migration 0009); the number of rows read."""
    from jointdb.store._part_records import verified_part

    parts = {p.id: p for p in s.scalars(select(PartRow))}
    n = 0
    for row in s.scalars(select(PartVersionRow).order_by(PartVersionRow.part_id, PartVersionRow.version)):
        n += 1
        try:
            verified_part(parts[row.part_id], row)
        except IntegrityError:
            problems.append(f"part {parts[row.part_id].name} v{row.version}: record hash mismatch "
                            "(row content was altered)")
    return n


@contextlib.contextmanager
def snapshot(store: "ReadAccess"):
    """One read-only transaction that sees a single snapshot of the whole database (PostgreSQL:
    REPEATABLE READ, READ ONLY; SQLite: one deferred read transaction, which WAL keeps consistent)."""
    conn = store.read_engine.connect()
    try:
        if conn.dialect.name == "postgresql":
            conn = conn.execution_options(isolation_level="REPEATABLE READ")
        with conn.begin():
            if conn.dialect.name == "postgresql":
                conn.exec_driver_sql("SET TRANSACTION READ ONLY")
            with Session(bind=conn) as s:
                yield s
    finally:
        conn.close()


def check(store: "ReadAccess", verify_blobs: bool = True, checkpoint: dict | None = None) -> CheckReport:
    """Walk every version row and every blob (see :meth:`Repository.check`).

    Problems reported: a row whose blob is missing or corrupt, a row whose
    record hash does not match its content, gaps or duplicates in a joint's
    version numbers, a missing or disabled immutability guard (trigger), a query-index
    row that differs from the history it is derived from, a history row that differs from
    (or is missing in) the history chain, and, given a verified ``checkpoint``
    (:func:`jointdb.store._chain.parse_checkpoint`), history that does not extend it.
    Everything is read in one snapshot (:func:`snapshot`), so concurrent writers cause no
    false alarms. Orphan blobs and left-over temporary files are listed but are not problems
    (``jointdb db gc`` removes them); ``notes`` says what the backend cannot guard.
    """
    from jointdb.store._chain import chain_problems
    from jointdb.store._guards import missing_guards
    from jointdb.store._index import index_problems

    n_rows = 0
    with snapshot(store) as s:
        conn = s.connection()
        problems, notes = missing_guards(conn)
        problems += chain_problems(conn, checkpoint)  # first: it names the first entry that differs
        problems += index_problems(conn)  # the derived query index against the history it comes from
        joints = {j.id: j for j in s.scalars(select(JointRow))}
        numbers: dict[int, list[int]] = {}
        for row in s.scalars(select(VersionRow).order_by(VersionRow.joint_id, VersionRow.version)):
            n_rows += 1
            joint = joints[row.joint_id]
            numbers.setdefault(row.joint_id, []).append(row.version)
            try:
                check_record(joint.name, joint.joint_type, row)
            except IntegrityError:
                problems.append(f"{joint.name} v{row.version}: record hash mismatch (row content was altered)")
        n_rows += _part_problems(s, problems)
        refs = _references(s)
    for joint_id, nums in numbers.items():
        if nums != list(range(1, len(nums) + 1)):
            problems.append(f"{joints[joint_id].name}: version numbers {nums} are not 1..{len(nums)}")
    n_blobs = 0
    for digest, users in sorted(refs.items()):
        n_blobs += 1
        if verify_blobs:
            problem = store.blobs.verify(digest)
        else:
            try:
                problem = None if store.blobs.exists(digest) else f"blob {digest} is missing"
            except IntegrityError as exc:  # a digest that is not hex
                problem = str(exc)
        if problem:
            problems.append(f"{', '.join(users)}: {problem}")
    orphans = tuple(b.sha256 for b in store.blobs.walk() if b.sha256 not in refs)
    temps = tuple(str(p) for p in store.blobs.temporaries())
    return CheckReport(n_rows, n_blobs, tuple(problems), orphans, temps, tuple(notes))


def gc(store: "WriteAccess", min_age_s: float = 3600.0, dry_run: bool = False) -> list[str]:
    """Delete blobs that no row references, and stale temporary files.

    Only files older than ``min_age_s`` are touched: a blob that a running
    ``catalogue`` has just written (its row not yet committed) is younger, and
    one it found already stored was refreshed (``BlobStore.put`` touches it).
    A candidate is renamed aside before the final database and age check, so a
    writer can never reference a blob between that check and the deletion
    (see ``BlobStore.collect``).
    """
    refs = _referenced(store)
    if not dry_run:  # blobs an interrupted gc had set aside and a row references go back first
        store.blobs.restore_set_aside(lambda d: d in refs)
    removed: list[str] = []
    for blob in list(store.blobs.walk()):
        if blob.sha256 in refs or store.blobs.age_seconds(blob.path) < min_age_s:
            continue
        if dry_run:
            removed.append(blob.sha256)
        elif store.blobs.collect(blob.sha256, min_age_s, lambda d: d in _referenced(store)):
            # collect() moves the blob aside, then re-checks the database and the age
            removed.append(blob.sha256)
    for tmp in store.blobs.temporaries():
        if store.blobs.age_seconds(tmp) >= min_age_s:
            removed.append(str(tmp))
            if not dry_run:
                tmp.unlink(missing_ok=True)
    if removed and not dry_run:
        now = utcnow()

        def write(s):
            s.add(AuditRow(at=now, actor=current_actor(), action="gc", joint_name=None, version=None,
                           details={"removed": len(removed)}))

        store.retrying(write)
    return removed


def _conditions_flat(v: JointVersion) -> dict[str, Any]:
    c = v.conditions
    out: dict[str, Any] = {
        "materials": "+".join(c.materials),
        "preload_n": c.preload_n,
        "torque_nm": c.torque_nm,
    }
    out.update({f"geometry.{k}": x for k, x in c.geometry.items()})
    out.update({f"extra.{k}": x for k, x in c.extra.items()})
    return out


def frf_difference(a: FRF, b: FRF) -> tuple[list[dict[str, Any]], list[str]]:
    """Per common entry, ``max_f |H_b − H_a| / max_f |H_a|`` on a's grid within the overlap."""
    notes: list[str] = []
    lo = max(a.freq[0], b.freq[0])
    hi = min(a.freq[-1], b.freq[-1])
    if lo > hi:
        return [], ["frequency ranges do not overlap; no FRF comparison"]
    a_band = a.band(lo, hi)
    if a.n_freq != b.n_freq or not np.array_equal(a.freq, b.freq):
        notes.append(f"grids differ; b interpolated onto a's lines in {lo:g}-{hi:g} Hz")
        b = b.resample(a_band.freq)
    a = a_band
    outs = [d for d in a.outputs if d in set(b.outputs)]
    ins = [d for d in a.inputs if d in set(b.inputs)]
    missing = sorted(set(map(str, a.outputs)) ^ set(map(str, b.outputs)))
    if missing:
        notes.append(f"DOFs in only one version: {' '.join(missing)}")
    if not outs or not ins:
        return [], notes + ["no common DOFs"]
    ha = a.block(outs, ins)
    hb = b.block(outs, ins)
    peak = np.max(np.abs(ha), axis=0)
    delta = np.max(np.abs(hb - ha), axis=0)
    rel = np.where(peak > 0, delta / np.where(peak > 0, peak, 1.0), np.where(delta > 0, np.inf, 0.0))
    rows = [
        {"output": str(o), "input": str(i), "max_rel_diff": float(rel[p, q])}
        for p, o in enumerate(outs)
        for q, i in enumerate(ins)
    ]
    return rows, notes


def diff_versions(load_frf: LoadFRF, a: JointVersion, b: JointVersion) -> VersionDiff:
    """What differs between versions ``a`` and ``b``: conditions, fields, and per FRF entry the
    largest relative difference (:func:`frf_difference`; FRFs read with ``load_frf``)."""
    ca, cb = _conditions_flat(a), _conditions_flat(b)
    conditions = {k: (ca.get(k), cb.get(k)) for k in sorted(set(ca) | set(cb)) if ca.get(k) != cb.get(k)}
    fields = {}
    for attr in ("joint_type", "model_kind", "dofs", "n_freq", "freq_min_hz", "freq_max_hz", "state"):
        va, vb = getattr(a, attr), getattr(b, attr)
        if va != vb:
            fields[attr] = (va, vb)
    pa, pb = a.provenance, b.provenance
    for attr in ("method", "parameters", "input_files", "software_version", "author"):
        va, vb = getattr(pa, attr), getattr(pb, attr)
        if va != vb:
            fields[f"provenance.{attr}"] = (va, vb)
    if dict(a.quality) != dict(b.quality):
        fields["quality"] = (dict(a.quality), dict(b.quality))
    same = a.blob_sha256 == b.blob_sha256
    if same:
        rows: list[dict[str, Any]] = [
            {"output": o, "input": i, "max_rel_diff": 0.0} for o in a.dofs for i in a.dofs
        ]
        notes: list[str] = ["identical FRF blob"]
    else:
        try:
            rows, notes = frf_difference(load_frf(a), load_frf(b))
        except (IntegrityError, NotFoundError):
            raise
    worst = max((r["max_rel_diff"] for r in rows), default=None)
    return VersionDiff(
        a=f"{a.name} v{a.version}",
        b=f"{b.name} v{b.version}",
        conditions=conditions,
        fields=fields,
        frf_entries=tuple(rows),
        max_relative_difference=worst,
        same_blob=same,
        notes=tuple(notes),
    )
