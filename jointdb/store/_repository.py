"""The versioned joint repository: immutable joint versions, labels, states and an audit log."""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import Any

from sqlalchemy.orm import Session

from jointdb.errors import InputError
from jointdb.frf import FRF
from jointdb.store import _db
from jointdb.store._access import Storage
from jointdb.store._blobformat import frf_sha256
from jointdb.store._catalogue import idempotent_answer, identity_of, precheck, write_version
from jointdb.store._labels import LabelsAndStates
from jointdb.store._reads import VersionReads
from jointdb.store._whole import WholeRepository
from jointdb.store._parts import PartsStore
from jointdb.store._reports import Catalogued
from jointdb.store._records import current_actor, load_stored_json
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


class Repository(VersionReads, WholeRepository, LabelsAndStates, PartsStore):
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
    check_schema
        Refuse a database whose schema revision is not this jointdb's (default True).
        False skips the check and creates nothing (a missing SQLite file is then refused).
    pool_size
        PostgreSQL: connections kept open (up to half as many again in a burst);
        default SQLAlchemy's 5 + 10. Ignored for SQLite.

    Raises
    ------
    NotFoundError
        A missing SQLite file without ``auto_create``.
    InputError
        Unusable target (directory, foreign file, unreachable server, missing
        driver, outdated schema).
    IntegrityError
        A damaged SQLite file.

    Examples
    --------
    A new SQLite catalogue; a spring–damper tool–holder joint catalogued as version 1, read
    back by name and its FRF loaded (verified against its SHA-256):

    >>> import os, tempfile
    >>> import numpy as np
    >>> from jointdb.coupling import spring_damper_joint
    >>> from jointdb.store import Conditions, Provenance, Repository
    >>> repo = Repository(os.path.join(tempfile.mkdtemp(), "joints.sqlite"))
    >>> freq = np.linspace(100.0, 2000.0, 20)                                    # Hz
    >>> joint = spring_damper_joint(freq, k=[2e7, 5e5], c=[50.0, 1.0], dofs_=["1x", "1ry"])
    >>> jv = repo.catalogue("th-80nm", "tool-holder", joint,
    ...                     Conditions(("carbide", "steel"), torque_nm=80.0),
    ...                     model_kind="spring-damper-planar", provenance=Provenance(method="irc-planar"))
    >>> jv.name, jv.version, jv.conditions.materials, jv.dofs
    ('th-80nm', 1, ('tungsten-carbide', 'steel'), ('1x', '1ry'))
    >>> repo.get("th-80nm").record_sha256 == jv.record_sha256
    True
    >>> repo.load_frf(jv).allclose(joint)
    True
    >>> repo.catalogue("th-80nm", "tool-holder", joint, Conditions(("carbide", "steel"), torque_nm=80.0),
    ...                model_kind="spring-damper-planar").version           # identical content: no new version
    1
    >>> repo.close()
    """

    def __init__(
        self,
        url: str | os.PathLike | None = None,
        *,
        blobs: str | os.PathLike | None = None,
        auto_create: bool | None = None,
        check_schema: bool = True,
        pool_size: int | None = None,
    ):
        self.url = _db.resolve_url(url)
        self.is_sqlite = _db.is_sqlite(self.url)
        auto = self.is_sqlite if auto_create is None else bool(auto_create)
        if self.is_sqlite:  # refuse a directory, an empty or foreign file; create a missing one only if asked
            _db.open_sqlite_target(self.url, create=auto and check_schema)
        self.read_engine, self.write_engine = _db.make_engines(self.url, pool_size)  # a missing driver first
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

        Parameters
        ----------
        name
            The joint's name (letters, digits, ``._-``; e.g. ``"th-er32-carbide-80nm"``).
        joint_type
            ``"tool-holder"``, ``"holder-spindle"``, ...
        frf
            The joint receptance (:class:`~jointdb.frf.FRF`, ``(n_freq, n, n)``).
        conditions
            :class:`Conditions` (or a mapping of its fields) it was identified under.
        model_kind
            One of :data:`MODEL_KINDS` (its DOF structure is checked against ``frf``).
        provenance
            :class:`Provenance` (method, parameters, input file hashes, author).
        quality
            Named quality numbers (e.g. ``{"identification_residual": 1e-3}``).
        parent
            Version number of this joint the new one derives from.
        raw_frfs
            Raw measurement FRFs to store with the version, by key.
        author
            Who catalogues it (default: the provenance's author, else ``JOINTDB_AUTHOR``, else the
            login name).
        label
            A label to point at the new version.
        force
            Accept conditions that contradict the latest version (listed in the audit entry).
        allow_identical
            Write a new version even when the content equals the latest one.

        Returns
        -------
        JointVersion
            The new version, or the latest one when nothing was written.

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
        written; ``version`` is that version).

        Parameters
        ----------
        name, joint_type, frf, conditions, model_kind, provenance, quality, parent, raw_frfs, author, label, force, allow_identical
            As :meth:`catalogue`.
        idempotency
            ``(owner, key, request_sha256)`` of a request made with an idempotency key: a key
            already answered returns its stored answer (the same version; InputError when it
            answered another request), otherwise the answer is stored in the version's own
            transaction.

        Returns
        -------
        Catalogued
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
        if not self.blobs.writes_in_version_transaction:  # refuse conflicts before writing a blob file
            with self.read_engine.connect() as conn:  # (a database blob is written with the row, or not at all)
                precheck(conn, name, joint_type, parent, identity_of(frf, cond, kind, frf_sha256(frf)), force)
        # a blob file is encoded, verified and written now, made durable (fsync, rename, directory fsync)
        # while the row is prepared; a database blob is encoded and verified on a worker meanwhile and
        # inserted by pending.wait(session); the transaction commits only after it: never a row without its blob
        # the raw measurements' blobs the same way: a refused version leaves none of them in the database
        pending = [self.blobs.put_pending(frf)]
        try:
            raw_items = sorted(raw.items())
            for _, v in raw_items:  # appended one by one: a failure still joins those already started
                pending.append(self.blobs.put_pending(v))
            blob = pending[0].digest
            raw_blobs = {str(k): p.digest for (k, _), p in zip(raw_items, pending[1:])}

            def write(session: Session):
                out = write_version(session, name=name, joint_type=joint_type, frf=frf, cond=cond, kind=kind,
                                    prov=prov, qual=qual, parent=parent, actor=actor, label=label, blob=blob,
                                    raw_blobs=raw_blobs, move_label=self._move_label, force=force,
                                    allow_identical=allow_identical, idempotency=idempotency)
                for p in pending:  # each blob is durable before (file) or with (database) the row
                    p.wait(session)
                return out

            out = self._retrying(write)
        finally:
            for p in pending:
                p.join()
        return Catalogued(out.version or self.get(out.name, out.number), out.created)

    @_db.with_db_errors
    def idempotent_answer(self, idempotency: tuple[str, str, str] | None) -> Catalogued | None:
        """The stored answer to ``(owner, key, request_sha256)``, or None when the key is new.

        Parameters
        ----------
        idempotency
            ``(owner, key, request_sha256)``, or None (then None is returned).

        Returns
        -------
        Catalogued or None
            The version the first request with this key catalogued, and whether it was new.

        Raises
        ------
        InputError
            This owner already sent this key with a different request body.
        """
        if idempotency is None:
            return None
        with self.read_engine.connect() as conn:
            answer = idempotent_answer(conn, idempotency)
        if answer is None:
            return None
        return Catalogued(self.get(answer[0], answer[1]), answer[2] == 201)
