"""The joint database: versioned joint records, HDF5 blob store, nearest-joint query.

Library first; the ``jointdb catalogue / joints / query / db`` commands call it.

>>> from jointdb.store import Repository, Conditions, Provenance
>>> repo = Repository("/tmp/joints.sqlite")                    # doctest: +SKIP
>>> jv = repo.catalogue("T1-HSK63", "tool-holder", frf,
...                     Conditions(("tungsten-carbide", "steel"), torque_nm=40.0,
...                                geometry={"diameter_m": 0.02}),
...                     model_kind="spring-damper-planar",
...                     provenance=Provenance(method="irc-planar"),
...                     quality={"identification_residual": 1e-3})  # doctest: +SKIP
>>> repo.get("T1-HSK63", version=1); repo.load_frf(jv)            # doctest: +SKIP
>>> repo.nearest("tool-holder", Conditions(torque_nm=35.0), k=3)  # doctest: +SKIP

API (one protocol, :class:`JointStore`, which ``Repository`` and
:class:`jointdb.client.RemoteRepository` implement; :class:`LocalJointStore` adds what only a
local database offers; :func:`open_store` opens either from a path, URL or server address;
the blob stores implement :class:`BlobStoreProtocol`; see :mod:`jointdb.store._protocol`):

- ``Repository(url=None, *, blobs=None, auto_create=None)`` - ``url``: SQLAlchemy URL
  or SQLite path (default ``$JOINTDB_URL``, else ``$XDG_DATA_HOME/jointdb/jointdb.sqlite``);
  ``blobs``: blob directory (default ``$JOINTDB_BLOBS``, else ``<sqlite file>.blobs``;
  required for PostgreSQL). A missing SQLite file is created (atomically, with its
  schema) unless ``auto_create=False``; an existing file that is empty, not SQLite or
  not a jointdb database is refused, never re-created. PostgreSQL needs
  ``jointdb db upgrade`` first.
- ``.catalogue(name, joint_type, frf, conditions, model_kind, provenance=None,
  quality=None, parent=None, *, raw_frfs=None, author=None, label=None) -> JointVersion``
  (the label is set in the same transaction)
- ``.get(name, version=None, at=None, label=None) -> JointVersion`` (default: latest
  non-deprecated); ``.load_frf(jv)`` or ``.load_frf(name, number) -> FRF`` (verified);
  ``.load_raw(jv, key) -> FRF``
- ``.history(name)``, ``.list_joints(joint_type=None, include_deprecated=True)``,
  ``.list_page(joint_type=None, *, materials, label, state, torque_min, ..., after, limit) ->
  JointPage`` (one SQL statement per page, ``next`` cursor; damaged rows are reported in
  ``JointPage.damaged`` and by lists as :class:`DamagedRecordWarning`, never fatal to a list),
  ``.label(name, version, label)``, ``.deprecate(name, version=None, reason="", undo=False)``,
  ``.audit(name=None, limit=100)``
- ``.diff(name, version_a, version_b=None, other=None) -> VersionDiff``
- ``.export(names_or_None, path, *, sign_key=None) -> counts``,
  ``.import_(path, author=None, *, trusted_keys=(), require_signature=False) -> summary``
  (ConflictError on a conflicting version; identical content is a no-op; bundle hash
  and Ed25519 signatures: :mod:`jointdb.store._bundle`, :mod:`jointdb.store._signing`)
- ``.nearest(joint_type, conditions, k=3, at=None) -> list[Match]`` (distance defined in
  :mod:`jointdb.store._query`; warns :class:`OutsideCatalogueWarning`);
  ``.interpolate(matches, conditions=None, method="axes") -> InterpolatedJoint`` (``.frf``,
  ``.neighbours``; weights of the matches bracketing the request along its condition axes,
  :mod:`jointdb.store._interp`, or ``method="idw"`` inverse distance)
- every read verifies the version's record hash (IntegrityError on a mismatch)
- ``.check(verify_blobs=True) -> CheckReport`` (``.ok``, ``.problems``, ``.notes``; also
  missing immutability guards), ``.gc(min_age_s=3600, dry_run=False)``
- ``upgrade(url=None, revision="head")``, ``downgrade(url=None, revision="-1")``,
  ``current_revision(url=None)``, ``head_revision()``

Value types: ``Conditions(materials, preload_n, torque_nm, geometry, extra)`` (materials from
:func:`known_materials`; extend with ``JOINTDB_MATERIALS=a,b`` or :func:`register_material`),
``Provenance(method, parameters, input_files, software_version, author)``, ``JointVersion``,
``Match(version, distance, per_condition, extrapolating, outside_range)``, ``MODEL_KINDS``
(``spring-damper-planar``, ``n-point-translational``, ``full-matrix``).
Blob format and canonical hash: :mod:`jointdb.store._blobs`; bundle format:
:mod:`jointdb.store._bundle`; schema: :mod:`jointdb.store._models`.
"""

from __future__ import annotations

from jointdb.store._nearest import OutsideCatalogueWarning
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
    "PartVersion": "_parts", "PART_KINDS": "_parts",
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
    """Apply Alembic migrations to ``revision``; returns the new revision.

    A SQLite file that does not exist is created (atomically); an existing file
    must be a jointdb database (see :func:`jointdb.store._db.open_sqlite_target`).
    """
    return _migrate("upgrade", url, revision)


def downgrade(url: str | None = None, revision: str = "-1") -> str | None:
    """Revert Alembic migrations to ``revision`` (``-1`` one step, ``base`` all).

    Never creates a database (NotFoundError for a missing SQLite file). The
    command line asks for ``--yes`` first (see :func:`jointdb.store._db.downgrade_plan`).
    """
    return _migrate("downgrade", url, revision)


def current_revision(url: str | None = None) -> str | None:
    """The schema revision of a database (None when it has none, or when a SQLite file does not exist)."""
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
    """The newest schema revision this jointdb knows."""
    from jointdb.store import _db

    return _db.head_revision()
