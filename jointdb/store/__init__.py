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

API (contract in /work/api-contracts.md, deviations documented here):

- ``Repository(url=None, *, blobs=None, auto_create=None)``
- ``.catalogue(name, joint_type, frf, conditions, model_kind, provenance=None,
  quality=None, parent=None, *, raw_frfs=None, author=None) -> JointVersion``
- ``.get(name, version=None, at=None, label=None) -> JointVersion``;
  ``.load_frf(version_or_name, number=None) -> FRF``; ``.load_raw(jv, key)``
- ``.history(name)``, ``.list_joints(joint_type=None)``, ``.label(name, version, label)``,
  ``.deprecate(name, version=None, reason="", undo=False)``, ``.audit(name=None)``
- ``.diff(name, version_a, version_b=None, other=None) -> VersionDiff``
- ``.export(names_or_None, path)``, ``.import_(path)``
- ``.nearest(joint_type, conditions, k=3, at=None) -> list[Match]``;
  ``.interpolate(matches, conditions=None) -> InterpolatedJoint``
- ``.check() -> CheckReport``, ``.gc(min_age_s=3600, dry_run=False)``
- ``upgrade(url, revision="head")``, ``downgrade(url, revision="-1")``, ``current_revision(url)``

Deviation from the contract: ``Conditions`` has a field order of
``(materials, preload_n, torque_nm, geometry, extra)`` as planned, and
``Match`` adds ``outside_range`` (which conditions extrapolate).
"""

from __future__ import annotations

from jointdb.store._blobs import BlobStore, file_sha256, frf_sha256, read_frf_file, write_frf_file
from jointdb.store._query import OutsideCatalogueWarning
from jointdb.store._repository import CheckReport, Repository, VersionDiff
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
    "Conditions",
    "Provenance",
    "JointVersion",
    "Match",
    "InterpolatedJoint",
    "VersionDiff",
    "CheckReport",
    "BlobStore",
    "OutsideCatalogueWarning",
    "MODEL_KINDS",
    "KNOWN_MATERIALS",
    "known_materials",
    "register_material",
    "frf_sha256",
    "file_sha256",
    "read_frf_file",
    "write_frf_file",
    "upgrade",
    "downgrade",
    "current_revision",
    "head_revision",
]


def upgrade(url: str | None = None, revision: str = "head") -> str | None:
    """Apply Alembic migrations to ``revision``; returns the new revision."""
    from jointdb.store import _db

    resolved = _db.resolve_url(url)
    read, write = _db.make_engines(resolved)
    try:
        _db.upgrade(write, revision)
        return _db.current_revision(read)
    finally:
        read.dispose()


def downgrade(url: str | None = None, revision: str = "-1") -> str | None:
    """Revert Alembic migrations to ``revision`` (``-1`` one step, ``base`` all)."""
    from jointdb.store import _db

    resolved = _db.resolve_url(url)
    read, write = _db.make_engines(resolved)
    try:
        _db.downgrade(write, revision)
        return _db.current_revision(read)
    finally:
        read.dispose()


def current_revision(url: str | None = None) -> str | None:
    """The schema revision of a database (None when it has none)."""
    from jointdb.store import _db

    read, _ = _db.make_engines(_db.resolve_url(url))
    try:
        return _db.current_revision(read)
    finally:
        read.dispose()


def head_revision() -> str:
    """The newest schema revision this jointdb knows."""
    from jointdb.store import _db

    return _db.head_revision()
