"""The versioned joint repository: immutable joint versions, labels, states and an audit log."""

from __future__ import annotations

import os
import re
import warnings
from collections.abc import Iterable, Mapping
from datetime import datetime
from typing import Any

from sqlalchemy import func, select
from sqlalchemy.orm import Session

from jointdb.errors import InputError, IntegrityError, NotFoundError
from jointdb.frf import FRF
from jointdb.store import _db
from jointdb.store._access import Storage, joint_row
from jointdb.store._blobformat import frf_sha256
from jointdb.store._catalogue import idempotent_answer, identity_of, precheck, write_version
from jointdb.store._labels import LabelsAndStates
from jointdb.store._parts import PartsStore
from jointdb.store._reports import Catalogued, CheckReport, VersionDiff
from jointdb.store._models import JointRow, LabelRow, StateRow, VersionRow
from jointdb.store._listing import JointPage, list_page
from jointdb.store._records import (
    DamagedRecordWarning,
    DamagedVersion,
    as_utc,
    current_actor,
    load_stored_json,
    state_of,
    to_version,
)
from jointdb.store._types import (
    Conditions,
    JointVersion,
    Provenance,
    as_conditions,
    as_provenance,
    as_quality,
    check_joint_type,
    check_label,
    check_model_kind,
    check_name,
)

_HEX64 = re.compile(r"[0-9a-f]{64}")


def _report_damaged(found: list[DamagedVersion], into: list | None) -> None:
    """Damaged versions a list skipped: into the caller's list, or as one warning naming them."""
    if into is not None:
        into.extend(found)
    elif found:
        warnings.warn("skipped damaged versions (run `jointdb db check`): "
                      + "; ".join(d.describe() for d in found[:10]), DamagedRecordWarning, stacklevel=3)


class Repository(LabelsAndStates, PartsStore):
    """A joint database: SQL rows (SQLite or PostgreSQL) plus an HDF5 blob store.

    Parameters
    ----------
    url
        Database URL or SQLite path; default ``JOINTDB_URL`` or the per-user
        SQLite file (see :mod:`jointdb.store._db`).
    blobs
        Blob directory; default ``JOINTDB_BLOBS`` or ``<sqlite file>.blobs``. The value
        ``"database"`` keeps the blobs in the database itself (table ``frf_blobs``,
        :mod:`jointdb.store._dbblobs`), so that several hosts need only the database.
    auto_create
        Create a missing SQLite file (atomically, with the schema), or migrate
        an empty PostgreSQL schema. Default: True for SQLite, False for
        PostgreSQL (run ``jointdb db upgrade`` on a shared server). An existing
        SQLite file that is empty, not SQLite or not a jointdb database is
        always refused (InputError), never re-created.

    Raises
    ------
    NotFoundError
        A missing SQLite file without ``auto_create``.
    InputError
        Unusable target (directory, foreign file, unreachable server, missing
        driver, outdated schema).
    IntegrityError
        A damaged SQLite file.
    """

    def __init__(
        self,
        url: str | os.PathLike | None = None,
        *,
        blobs: str | os.PathLike | None = None,
        auto_create: bool | None = None,
        check_schema: bool = True,
    ):
        self.url = _db.resolve_url(url)
        self.is_sqlite = _db.is_sqlite(self.url)
        auto = self.is_sqlite if auto_create is None else bool(auto_create)
        if self.is_sqlite:  # refuse a directory, an empty or foreign file; create a missing one only if asked
            _db.open_sqlite_target(self.url, create=auto and check_schema)
        self.read_engine, self.write_engine = _db.make_engines(self.url)  # a missing driver first
        # a JSON column that does not decode (a damaged file) reads as DamagedJSON instead of raising in the
        # middle of a result: each read then refuses that one row by name (check_record). Set before the
        # first connection: psycopg registers the loader on connect, SQLite's JSON type reads it per query.
        self.read_engine.dialect._json_deserializer = load_stored_json
        try:
            from jointdb.store._dbblobs import open_blob_store

            self.blobs = open_blob_store(self.url, blobs, self.write_engine)  # a directory, or "database"
            #: what the query, bundle and maintenance helpers are given (never the repository itself)
            self.storage = Storage(self.url, self.read_engine, self.write_engine, self.blobs)
            with _db.db_errors(self.url):
                if check_schema:
                    _db.ensure_schema(self.read_engine, self.write_engine, auto)
        except BaseException:
            self.read_engine.dispose()
            raise

    # ----------------------------------------------------------------- admin
    def close(self) -> None:
        self.read_engine.dispose()

    def __enter__(self) -> "Repository":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"Repository({self.url!r}, blobs={str(self.blobs.root)!r})"

    def _read(self) -> Session:
        return self.storage.read()

    def _write(self) -> Session:
        return self.storage.write()

    def _retrying(self, fn):
        """Run ``fn(session)`` in a write transaction; retry after rollback on conflicts
        (:meth:`jointdb.store._access.Storage.retrying`)."""
        return self.storage.retrying(fn)

    # ------------------------------------------------------------- catalogue
    @_db.with_db_errors
    def catalogue(
        self,
        name: str,
        joint_type: str,
        frf: FRF,
        conditions: Conditions | Mapping[str, Any] | None,
        model_kind: str,
        provenance: Provenance | Mapping[str, Any] | None = None,
        quality: Mapping[str, float] | None = None,
        parent: int | None = None,
        *,
        raw_frfs: Mapping[str, FRF] | None = None,
        author: str | None = None,
        label: str | None = None,
        force: bool = False,
        allow_identical: bool = False,
    ) -> JointVersion:
        """Store a joint FRF as a new joint (version 1) or a new version of one.

        The blob is encoded and verified first and made durable while the row is
        prepared; the row is committed after the blob is durable, in one
        write transaction in which the next version number is taken (behind
        ``UNIQUE(joint_id, version)``; retried after rollback on a conflict;
        :mod:`jointdb.store._catalogue`).

        A new version is the same joint re-identified (:mod:`jointdb.store._identity`):
        its materials, preload, torque, geometry, model kind and DOFs must match those
        the latest version recorded (values it did not record may be filled in); a
        contradiction is refused unless ``force`` (the audit entry then lists each change).
        Content identical to the latest version (same FRF, conditions, model kind) writes
        nothing and returns that version, unless ``allow_identical``
        (:meth:`catalogue_outcome` says which happened).

        ``label`` (optional) is pointed at the new version in the same
        transaction: both happen or neither.

        Raises
        ------
        InputError
            Bad name, type, conditions, model kind / DOF structure, provenance,
            quality or label; nothing is written.
        ConflictError
            The name exists with another joint type; ``parent`` does not exist; or the
            conditions contradict the latest version (without ``force``).
        """
        return self.catalogue_outcome(name, joint_type, frf, conditions, model_kind, provenance, quality, parent,
                                      raw_frfs=raw_frfs, author=author, label=label, force=force,
                                      allow_identical=allow_identical).version

    @_db.with_db_errors
    def catalogue_outcome(self, name: str, joint_type: str, frf: FRF, conditions, model_kind: str,
                          provenance=None, quality=None, parent: int | None = None, *, raw_frfs=None,
                          author: str | None = None, label: str | None = None, force: bool = False,
                          allow_identical: bool = False,
                          idempotency: tuple[str, str, str] | None = None) -> Catalogued:
        """:meth:`catalogue`, saying whether a version was written: ``Catalogued(version, created)``.

        ``created`` is False when the content was identical to the latest version (nothing
        written; ``version`` is that version). ``idempotency``: ``(owner, key, request_sha256)``
        of a request made with an idempotency key: a key already answered returns its stored
        answer (the same version; InputError when it answered another request), otherwise the
        answer is stored in the version's own transaction.
        """
        name = check_name(name)
        joint_type = check_joint_type(joint_type)
        if not isinstance(frf, FRF):
            raise InputError(f"frf must be a jointdb.frf.FRF, got {type(frf).__name__}")
        kind = check_model_kind(model_kind, frf)
        cond = as_conditions(conditions)
        prov = as_provenance(provenance)
        qual = as_quality(quality)
        raw = dict(raw_frfs or {})
        for key, value in raw.items():
            if not isinstance(value, FRF):
                raise InputError(f"raw measurement {key!r} must be an FRF")
        if parent is not None and (isinstance(parent, bool) or int(parent) < 1):
            raise InputError(f"parent version must be a version number >= 1, got {parent!r}")
        actor = current_actor(author or prov.author or None)
        label = check_label(label) if label is not None else None
        known = self.idempotent_answer(idempotency)
        if known is not None:
            return known
        with self.read_engine.connect() as conn:  # refuse conflicts before writing any blob
            precheck(conn, name, joint_type, parent, identity_of(frf, cond, kind, frf_sha256(frf)), force)
        # encoded, verified and written now, made durable (fsync, rename, directory fsync) while the
        # row is prepared; the transaction commits only after pending.wait(): never a row without its blob
        pending = self.blobs.put_pending(frf)
        try:
            blob = pending.digest
            raw_blobs = {str(k): self.blobs.put(v) for k, v in sorted(raw.items())}

            def write(session: Session):
                out = write_version(session, name=name, joint_type=joint_type, frf=frf, cond=cond, kind=kind,
                                    prov=prov, qual=qual, parent=parent, actor=actor, label=label, blob=blob,
                                    raw_blobs=raw_blobs, move_label=self._move_label, force=force,
                                    allow_identical=allow_identical, idempotency=idempotency)
                pending.wait()  # the blob is durable before the row that references it commits
                return out

            out = self._retrying(write)
        finally:
            pending.join()
        return Catalogued(out.version or self.get(out.name, out.number), out.created)

    @_db.with_db_errors
    def idempotent_answer(self, idempotency: tuple[str, str, str] | None) -> Catalogued | None:
        """The stored answer to ``(owner, key, request_sha256)``, or None when the key is new.

        Raises
        ------
        InputError
            The key was used by the same owner for another request.
        """
        if idempotency is None:
            return None
        with self.read_engine.connect() as conn:
            answer = idempotent_answer(conn, idempotency)
        if answer is None:
            return None
        return Catalogued(self.get(answer[0], answer[1]), answer[2] == 201)

    # ------------------------------------------------------------------ reads
    @staticmethod
    def _joint(session: Session, name: str) -> JointRow:
        return joint_row(session, name)

    def _states(self, session: Session, joint_id: int, at: datetime | None) -> list[StateRow]:
        q = select(StateRow).where(StateRow.joint_id == joint_id)
        if at is not None:
            q = q.where(StateRow.at <= at)
        return list(session.scalars(q))

    def _labels(self, session: Session, joint_id: int) -> dict[int, list[str]]:
        out: dict[int, list[str]] = {}
        for lab in session.scalars(select(LabelRow).where(LabelRow.joint_id == joint_id)):
            out.setdefault(lab.version, []).append(lab.label)
        return out

    @_db.with_db_errors
    def get(
        self,
        name: str,
        version: int | None = None,
        at: datetime | str | None = None,
        label: str | None = None,
    ) -> JointVersion:
        """One version of a joint: pinned (``version``), by ``label``, current at
        time ``at``, or (default) the latest version that is not deprecated
        (the latest one if all are).

        Raises
        ------
        NotFoundError
            Unknown joint, version or label, or no version existed at ``at``
            (also when the pinned ``version`` was catalogued after ``at``).
        InputError
            ``label`` combined with ``version`` or ``at`` (labels are current pointers).
        """
        at = as_utc(at)
        if label is not None and (version is not None or at is not None):
            raise InputError("a label names one version now; do not combine it with --version or --at")
        with self._read() as s:
            joint = self._joint(s, name)
            labels = self._labels(s, joint.id)
            if label is not None:
                label = check_label(label)  # a NUL would reach PostgreSQL, which refuses it
                lab = s.scalar(select(LabelRow).where(LabelRow.joint_id == joint.id, LabelRow.label == label))
                if lab is None:
                    have = sorted({x for v in labels.values() for x in v})
                    raise NotFoundError(f"joint {name!r} has no label {label!r} (labels: {', '.join(have) or 'none'})")
                version = lab.version
            q = select(VersionRow).where(VersionRow.joint_id == joint.id)
            if version is not None:
                # beyond the database's integers (PostgreSQL would refuse the query) no version exists
                row = s.scalar(q.where(VersionRow.version == int(version))) if 0 < int(version) < 2**31 else None
                if row is None:
                    n = s.scalar(select(func.max(VersionRow.version)).where(VersionRow.joint_id == joint.id))
                    raise NotFoundError(f"joint {name!r} has no version {version} (versions 1..{n or 0})")
                if at is not None and row.created_at > at:
                    raise NotFoundError(f"joint {name!r} version {version} did not exist yet at {at.isoformat()} "
                                        f"(catalogued {row.created_at.isoformat(timespec='seconds')})")
                states = self._states(s, joint.id, at)
                return to_version(joint, row, state_of(row.version, states), labels.get(row.version, ()))
            if at is not None:
                q = q.where(VersionRow.created_at <= at)
            rows = list(s.scalars(q.order_by(VersionRow.version.desc())))
            if not rows:
                raise NotFoundError(f"joint {name!r} had no version at {at.isoformat() if at else 'all'}")
            states = self._states(s, joint.id, at)
            for row in rows:
                if state_of(row.version, states) == "active":
                    return to_version(joint, row, "active", labels.get(row.version, ()))
            row = rows[0]
            return to_version(joint, row, "deprecated", labels.get(row.version, ()))

    @_db.with_db_errors
    def history(self, name: str, *, damaged: list | None = None) -> list[JointVersion]:
        """All versions of a joint, oldest first, with their current state and labels.

        A version whose stored row is damaged is left out and reported: appended to ``damaged``
        (a list, as :class:`jointdb.store._records.DamagedVersion`) when given, else in a
        :class:`DamagedRecordWarning`.
        """
        with self._read() as s:
            joint = self._joint(s, name)
            labels = self._labels(s, joint.id)
            states = self._states(s, joint.id, None)
            rows = s.scalars(select(VersionRow).where(VersionRow.joint_id == joint.id).order_by(VersionRow.version))
            out, bad = [], []
            for r in rows:
                try:
                    out.append(to_version(joint, r, state_of(r.version, states), labels.get(r.version, ())))
                except IntegrityError as exc:
                    bad.append(DamagedVersion(joint.name, r.version, str(exc).split(": ", 1)[-1]))
        _report_damaged(bad, damaged)
        return out

    @_db.with_db_errors
    def list_page(self, joint_type: str | None = None, *, materials: Iterable[str] = (), label: str | None = None,
                  include_deprecated: bool = True, state: str | None = None, torque_min: float | None = None,
                  torque_max: float | None = None, preload_min: float | None = None,
                  preload_max: float | None = None, name_contains: str | None = None, after: str | None = None,
                  offset: int = 0, limit: int | None = 50) -> JointPage:
        """One page of the catalogue: the current version of each joint that passes the filters,
        by name, in one SQL statement (see :mod:`jointdb.store._listing`).

        ``after`` is the ``next`` cursor of the previous page; ``limit=None`` lists all. Damaged
        rows do not stop the list: they are in ``JointPage.damaged``.

        Raises
        ------
        InputError
            A bad filter (type, material, label, bounds, name part), cursor, offset or limit.
        """
        with self.read_engine.connect() as conn:
            return list_page(conn, joint_type=joint_type, materials=materials, label=label,
                             include_deprecated=include_deprecated, state=state, torque_min=torque_min,
                             torque_max=torque_max, preload_min=preload_min, preload_max=preload_max,
                             name_contains=name_contains, after=after, offset=offset, limit=limit)

    @_db.with_db_errors
    def list_joints(self, joint_type: str | None = None, include_deprecated: bool = True, *,
                    damaged: list | None = None) -> list[JointVersion]:
        """The current version (as :meth:`get`) of every joint, by name (one SQL statement).

        Damaged rows are left out and reported as in :meth:`history`.
        """
        page = self.list_page(joint_type, include_deprecated=include_deprecated, limit=None)
        _report_damaged(list(page.damaged), damaged)
        return list(page.items)

    @_db.with_db_errors
    def load_frf(self, version: JointVersion | str, number: int | None = None) -> FRF:
        """The joint FRF of a version, read from its blob and verified against its hash.

        ``load_frf(jv)`` or ``load_frf("name", 3)``.

        Raises
        ------
        IntegrityError
            The blob is corrupt; NotFoundError when it is missing.
        """
        jv = version if isinstance(version, JointVersion) else self.get(version, number)
        return self._blob(jv, jv.blob_sha256, "FRF blob")

    def _blob(self, jv: JointVersion, digest: str, what: str) -> FRF:
        """A blob of ``jv``; a corrupt or missing one is named by its version, never by a server path."""
        if not isinstance(digest, str) or not _HEX64.fullmatch(digest):  # never echoed, never used in a path
            raise IntegrityError(f"{jv.name} v{jv.version}: the digest of its {what} is not a SHA-256 hex digest; "
                                 "refusing to use it - run `jointdb db check`")
        try:
            return self.blobs.get(digest)
        except IntegrityError:
            raise IntegrityError(f"{jv.name} v{jv.version}: its {what} {digest} is corrupt or unreadable; refusing "
                                 "to use it - run `jointdb db check`") from None
        except NotFoundError:
            raise NotFoundError(f"{jv.name} v{jv.version}: its {what} {digest} is missing from the blob store - "
                                "run `jointdb db check`") from None

    @_db.with_db_errors
    def load_raw(self, version: JointVersion, key: str) -> FRF:
        """One raw measurement FRF stored with a version."""
        if key not in version.raw_blobs:
            raise NotFoundError(f"{version.name} v{version.version} has no raw measurement {key!r}")
        return self._blob(version, version.raw_blobs[key], f"raw measurement {key!r}")

    # -------------------------------------------------------------- diff, etc.
    @_db.with_db_errors
    def diff(self, name: str, version_a: int, version_b: int | None = None, other: str | None = None) -> VersionDiff:
        """Compare two versions (of one joint, or of ``name`` and ``other``)."""
        from jointdb.store._maintenance import diff_versions

        a = self.get(name, version_a)
        b = self.get(other or name, version_b) if (version_b is not None or other) else self.get(name)
        return diff_versions(self.load_frf, a, b)

    @_db.with_db_errors
    def check(self, verify_blobs: bool = True) -> CheckReport:
        """Walk every row and blob; report missing or corrupt data (``jointdb db check``)."""
        from jointdb.store._maintenance import check

        return check(self.storage, verify_blobs)

    @_db.with_db_errors
    def gc(self, min_age_s: float = 3600.0, dry_run: bool = False) -> list[str]:
        """Remove blobs no row references (and stale temporaries) older than ``min_age_s``."""
        from jointdb.store._maintenance import gc

        return gc(self.storage, min_age_s, dry_run)

    @_db.with_db_errors
    def nearest(self, joint_type: str, conditions: Conditions | Mapping[str, Any], k: int = 3,
                at: datetime | str | None = None, *, label: str | None = None, all_versions: bool = False,
                include_deprecated: bool = False):
        """The ``k`` versions of ``joint_type`` closest to ``conditions``: by default each joint's
        newest version that is not deprecated; ``label`` (only versions carrying it),
        ``all_versions``, ``include_deprecated`` widen or narrow that; see :mod:`jointdb.store._query`."""
        from jointdb.store._query import nearest

        return nearest(self.storage, joint_type, conditions, k, as_utc(at), label=label, all_versions=all_versions,
                       include_deprecated=include_deprecated)

    @_db.with_db_errors
    def interpolate(self, matches, conditions: Conditions | Mapping[str, Any] | None = None, *,
                    method: str = "axes"):
        """An interpolated joint between matches (dynamic stiffness; ``method`` ``"axes"`` or ``"idw"``);
        see :mod:`jointdb.store._query`."""
        from jointdb.store._query import interpolate

        return interpolate(self.load_frf, matches, conditions, method=method)

    @_db.with_db_errors
    def export(self, names: Iterable[str] | None, path: str | os.PathLike, *, sign_key=None) -> dict[str, Any]:
        """Write joints (all versions, provenance, labels, states) to one HDF5 bundle.

        ``sign_key``: an Ed25519 private key (``jointdb.store._signing.load_private_key``)
        to sign the bundle with.
        """
        from jointdb.store._bundle import export_bundle

        return export_bundle(self.storage, names, path, sign_key)

    @_db.with_db_errors
    def import_(self, path, author: str | None = None, *, trusted_keys=(),
                require_signature: bool = False, force: bool = False) -> dict[str, Any]:
        """Import a bundle (a path or a verified ``Bundle``); identical versions are no-ops,
        conflicting ones raise ConflictError, and so does a new version that is not the same
        joint as the one before it (unless ``force``); any ``trusted_keys`` (or
        ``require_signature``) refuse a bundle not signed by one of them (Ed25519 public keys)."""
        from jointdb.store._bundle import import_bundle

        return import_bundle(self.storage, path, author, trusted_keys, require_signature, force)
