"""The joint database: versioned joint records, HDF5 blob store, nearest-joint query.

Library first; the ``jointdb catalogue / joints / query / db`` commands call it. Every
catalogued joint is an immutable version with its conditions, provenance and the SHA-256 of
its FRF; every read verifies the record hash (:class:`~jointdb.errors.IntegrityError` on a
mismatch). SQLAlchemy and h5py are imported on first use of a name that needs them.

Stores
------
   Repository              -- SQLite or PostgreSQL rows plus an HDF5 blob store (examples there)
   JointStore              -- the store protocol that ``Repository`` and
                              :class:`jointdb.client.RemoteRepository` implement
   LocalJointStore         -- ``JointStore`` plus what only a local database offers
   open_store              -- the store a path, database URL or server address names
   owned_store             -- :func:`open_store` in a ``with`` block
   BlobStore               -- content-addressed FRF blobs in a directory
   BlobStoreProtocol       -- the protocol both blob stores implement

Records
-------
   Conditions              -- materials, preload, torque, geometry a joint was identified under
   Provenance              -- method, parameters, input files, software version, author
   JointVersion            -- one immutable catalogued version
   Catalogued              -- a version and whether this call wrote it
   MODEL_KINDS             -- ``spring-damper-planar``, ``n-point-translational``, ``full-matrix``
   KNOWN_MATERIALS         -- the built-in interface material names
   known_materials         -- built-in names plus ``JOINTDB_MATERIALS``
   register_material       -- accept a new material name for this process

Parts (spindles, holders, tools)
--------------------------------
   PartVersion             -- one immutable version of a part: payload, attributes, provenance
   PART_KINDS              -- ``spindle``, ``holder``, ``tool``

Queries and listings
--------------------
   Match                   -- one answer of ``Repository.nearest``: version, distance, extrapolation
   InterpolatedJoint       -- a joint FRF interpolated between catalogued neighbours
   OutsideCatalogueWarning -- a request outside the catalogued range of a condition
   UnvariedConditionWarning -- a note: a machine condition the catalogue never varied
   JointPage               -- one page of ``Repository.list_page`` with its ``next`` cursor
   DamagedVersion          -- a version a listing skipped, and why
   DamagedRecordWarning    -- a list skipped damaged rows
   VersionDiff             -- differences between two versions
   CheckReport             -- result of ``Repository.check``

Blob files
----------
   frf_sha256              -- SHA-256 of the canonical form of an FRF
   file_sha256             -- SHA-256 of a file's bytes
   write_frf_file          -- one FRF in the blob layout; returns its content hash
   read_frf_file           -- read it back, checksum and content hash verified

Bundle signatures (Ed25519)
---------------------------
   create_key_pair         -- write a new key pair (``NAME``, ``NAME.pub``)
   load_private_key        -- a private key to sign an exported bundle with
   load_public_key         -- a public key to trust when importing one

Schema migrations
-----------------
   upgrade                 -- apply Alembic migrations to a revision
   downgrade               -- revert Alembic migrations
   current_revision        -- the schema revision of a database
   head_revision           -- the newest schema revision this jointdb knows

Formats: blobs and the canonical hash :mod:`jointdb.store._blobs`; bundles
:mod:`jointdb.store._bundle` (Ed25519 signatures :mod:`jointdb.store._signing`); the SQL
schema :mod:`jointdb.store._models`; the nearest-joint distance :mod:`jointdb.store._query`.
"""

from __future__ import annotations

from jointdb.store._nearest import OutsideCatalogueWarning, UnvariedConditionWarning
from jointdb.store._records import DamagedRecordWarning, DamagedVersion
from jointdb.store._types import (
    KNOWN_MATERIALS,
    MODEL_KINDS,
    Conditions,
    InterpolatedJoint,
    JointVersion,
    Match,
    Provenance,
    known_materials,
    register_material,
)

__all__ = [
    "Repository",
    "PartVersion",
    "PART_KINDS",
    "Conditions",
    "Provenance",
    "JointVersion",
    "Match",
    "InterpolatedJoint",
    "VersionDiff",
    "CheckReport",
    "BlobStore",
    "OutsideCatalogueWarning",
    "UnvariedConditionWarning",
    "DamagedRecordWarning",
    "DamagedVersion",
    "JointPage",
    "MODEL_KINDS",
    "KNOWN_MATERIALS",
    "known_materials",
    "register_material",
    "frf_sha256",
    "file_sha256",
    "read_frf_file",
    "write_frf_file",
    "JointStore",
    "LocalJointStore",
    "BlobStoreProtocol",
    "open_store",
    "owned_store",
    "Catalogued",
    "create_key_pair",
    "load_private_key",
    "load_public_key",
    "upgrade",
    "downgrade",
    "current_revision",
    "head_revision",
]

#: Loaded on first use (SQLAlchemy, h5py): ``jointdb query`` needs neither of them to rank.
_LAZY = {
    "Repository": "_repository", "CheckReport": "_reports", "VersionDiff": "_reports",
    "BlobStore": "_blobs", "file_sha256": "_blobs", "frf_sha256": "_blobs", "read_frf_file": "_blobs",
    "write_frf_file": "_blobs", "JointPage": "_listing", "Catalogued": "_reports",
    "JointStore": "_protocol", "LocalJointStore": "_protocol", "BlobStoreProtocol": "_protocol",
    "open_store": "_open", "owned_store": "_open",
    "create_key_pair": "_signing", "load_private_key": "_signing", "load_public_key": "_signing",
    "PartVersion": "_part_records", "PART_KINDS": "_part_records",
}


def __getattr__(name: str):
    if name in _LAZY:
        import importlib

        value = getattr(importlib.import_module(f"jointdb.store.{_LAZY[name]}"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'jointdb.store' has no attribute {name!r}")


def _migrate(step: str, url: str | None, revision: str) -> str | None:
    from alembic.util.exc import CommandError

    from jointdb.errors import InputError
    from jointdb.store import _db

    resolved = _db.resolve_url(url)
    sqlite = _db.is_sqlite(resolved)
    if sqlite and _db.open_sqlite_target(resolved, create=step == "upgrade", revision=revision):
        return current_revision(resolved)  # a new file, created at `revision`
    read, write = _db.make_engines(resolved)
    try:
        with _db.db_errors(resolved):
            try:
                getattr(_db, step)(write, revision)
            except CommandError as exc:
                raise InputError(f"cannot {step} to {revision!r}: {exc}") from None
            return _db.current_revision(read)
    finally:
        read.dispose()


def upgrade(url: str | None = None, revision: str = "head") -> str | None:
    """Apply Alembic migrations to ``revision``.

    A SQLite file that does not exist is created (atomically); an existing file
    must be a jointdb database (see :func:`jointdb.store._db.open_sqlite_target`).

    Parameters
    ----------
    url
        Database URL or SQLite path (default ``JOINTDB_URL`` or the per-user file).
    revision
        Target revision (``"head"``: the newest).

    Returns
    -------
    str or None
        The revision after the upgrade.
    """
    return _migrate("upgrade", url, revision)


def downgrade(url: str | None = None, revision: str = "-1") -> str | None:
    """Revert Alembic migrations to ``revision`` (``-1`` one step, ``base`` all).

    Never creates a database (NotFoundError for a missing SQLite file). The
    command line asks for ``--yes`` first (see :func:`jointdb.store._db.downgrade_plan`).

    Parameters
    ----------
    url
        Database URL or SQLite path (default ``JOINTDB_URL`` or the per-user file).
    revision
        Target revision.

    Returns
    -------
    str or None
        The revision after the downgrade (None at ``base``).
    """
    return _migrate("downgrade", url, revision)


def current_revision(url: str | None = None) -> str | None:
    """The schema revision of a database.

    Parameters
    ----------
    url
        Database URL or SQLite path (default ``JOINTDB_URL`` or the per-user file).

    Returns
    -------
    str or None
        None when it has none, or when a SQLite file does not exist (nothing is created).
    """
    from jointdb.store import _db

    resolved = _db.resolve_url(url)
    if _db.is_sqlite(resolved):
        if not _db.check_sqlite_file(_db.sqlite_path(resolved)):
            return None  # nothing is created to answer
        _db.check_jointdb_sqlite(_db.sqlite_path(resolved))  # a foreign file is refused, not touched
    read, _ = _db.make_engines(resolved)
    try:
        with _db.db_errors(resolved):
            return _db.current_revision(read)
    finally:
        read.dispose()


def head_revision() -> str:
    """The newest schema revision this jointdb knows.

    Returns
    -------
    str
        An Alembic revision id.
    """
    from jointdb.store import _db

    return _db.head_revision()
