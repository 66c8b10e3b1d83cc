"""The store's protocols: what a joint store, a blob store and the store's helpers offer.

- :class:`JointStore` - what the application layer and the shells use of a joint
  database, local (:class:`jointdb.store.Repository`) or behind ``jointdb serve``
  (:class:`jointdb.client.RemoteRepository`); :func:`jointdb.store.open_store` opens one.
- :class:`LocalJointStore` - a :class:`JointStore` that also pages, reads raw
  measurements, answers idempotency keys, checks, collects and moves bundles: what the
  HTTP service and the ``jointdb db`` / ``joints export|import`` commands need of the
  database they hold (only :class:`~jointdb.store.Repository` today).
- :class:`BlobStoreProtocol` - content-addressed FRF blobs, in files
  (:class:`jointdb.store._blobs.BlobStore`) or in the database
  (:class:`jointdb.store._dbblobs.DatabaseBlobStore`).
- :class:`ReadAccess` / :class:`WriteAccess` - the narrow interfaces the query, bundle and
  maintenance helpers take instead of the repository (:class:`jointdb.store._access.Storage`).

All are :func:`typing.runtime_checkable`; ``tests/store/test_store_protocol.py`` checks that
each implementation has every method with the protocol's parameters.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Iterator, Mapping
from datetime import datetime
from typing import TYPE_CHECKING, Any, Protocol, TypeVar, runtime_checkable

if TYPE_CHECKING:  # pragma: no cover
    from sqlalchemy import Engine
    from sqlalchemy.orm import Session

    from jointdb.frf import FRF
    from jointdb.store._blobs import BlobInfo, PendingPut
    from jointdb.store._listing import JointPage
    from jointdb.store._part_records import PartVersion
    from jointdb.store._reports import Catalogued, CheckReport, VersionDiff
    from jointdb.store._types import Conditions, InterpolatedJoint, JointVersion, Match, Provenance

T = TypeVar("T")


@runtime_checkable
class BlobStoreProtocol(Protocol):
    """Content-addressed FRF blobs: stored once under their SHA-256, verified on every read.

    ``root`` names the store (a directory, or ``"<database> (table frf_blobs)"``).
    """

    root: Any
    #: True when ``put_pending(...).wait(session)`` writes the blob in the version's own transaction
    #: (nothing is left behind when the version is refused); False when the blob is made durable first
    writes_in_version_transaction: bool

    def put(self, frf: FRF) -> str:
        """Store ``frf`` durably (idempotent, read back and verified); its SHA-256 hex digest."""

    def put_pending(self, frf: FRF) -> PendingPut:
        """Start :meth:`put`; ``.wait(session)`` returns the digest once the blob is durable (a store
        that lives in the database writes it in ``session``, the transaction of its version)."""

    def get(self, digest: str) -> FRF:
        """The verified FRF (NotFoundError when missing, IntegrityError when corrupt)."""

    def exists(self, digest: str) -> bool:
        """Whether a blob is stored under ``digest`` (IntegrityError for a digest that is not hex)."""

    def verify(self, digest: str) -> str | None:
        """None when the blob is present and intact, else a one-line problem."""

    def walk(self) -> Iterator[BlobInfo]:
        """Every stored blob."""

    def temporaries(self) -> list:
        """Left-over temporary files of interrupted writes (none in the database)."""

    def restore_set_aside(self, is_referenced: Callable[[str], bool]) -> list[str]:
        """Put back blobs an interrupted ``gc`` set aside that a row references."""

    def age_seconds(self, path: Any) -> float:
        """Seconds since the blob at ``path`` (``BlobInfo.path``: a file, or the digest) was written or touched."""

    def remove(self, digest: str) -> None:
        """Delete one blob unconditionally (tests and repairs)."""

    def collect(self, digest: str, min_age_s: float, still_referenced: Callable[[str], bool]) -> bool:
        """Delete an unreferenced blob old enough without racing a writer; True when deleted."""


@runtime_checkable
class ReadAccess(Protocol):
    """What a helper that only reads needs of a store: its URL, read engine and blob store."""

    url: str
    read_engine: Engine
    blobs: BlobStoreProtocol


@runtime_checkable
class WriteAccess(ReadAccess, Protocol):
    """:class:`ReadAccess` and a write transaction retried after conflicts."""

    def retrying(self, fn: Callable[[Session], T]) -> T:
        """Run ``fn(session)`` in a write transaction; retry after rollback on conflicts."""


@runtime_checkable
class JointStore(Protocol):
    """A versioned joint catalogue (see :class:`jointdb.store.Repository` for each method)."""

    url: str

    def close(self) -> None:
        """Release the connections."""

    def catalogue(self, name: str, joint_type: str, frf: FRF, conditions: Conditions | Mapping[str, Any] | None,
                  model_kind: str, provenance: Provenance | Mapping[str, Any] | None = None,
                  quality: Mapping[str, float] | None = None, parent: int | None = None, *,
                  raw_frfs: Mapping[str, FRF] | None = None, author: str | None = None, label: str | None = None,
                  force: bool = False, allow_identical: bool = False) -> JointVersion:
        """Store a joint FRF as a new joint or a new version of one."""

    def catalogue_outcome(self, name: str, joint_type: str, frf: FRF, conditions, model_kind: str,
                          provenance=None, quality=None, parent: int | None = None, *, raw_frfs=None,
                          author: str | None = None, label: str | None = None, force: bool = False,
                          allow_identical: bool = False) -> Catalogued:
        """:meth:`catalogue`, saying whether a version was written: ``(version, created)``."""

    def get(self, name: str, version: int | None = None, at: datetime | str | None = None,
            label: str | None = None) -> JointVersion:
        """One version: pinned, by label, current at a time, or the latest not deprecated."""

    def history(self, name: str, *, damaged: list | None = None) -> list[JointVersion]:
        """All versions of a joint, oldest first."""

    def list_joints(self, joint_type: str | None = None, include_deprecated: bool = True, *,
                    damaged: list | None = None) -> list[JointVersion]:
        """The current version of every joint, by name."""

    def load_frf(self, version: JointVersion | str, number: int | None = None) -> FRF:
        """The verified joint FRF of a version."""

    def diff(self, name: str, version_a: int, version_b: int | None = None,
             other: str | None = None) -> VersionDiff:
        """Compare two versions (of one joint, or of ``name`` and ``other``)."""

    def nearest(self, joint_type: str, conditions: Conditions | Mapping[str, Any], k: int = 3,
                at: datetime | str | None = None, *, label: str | None = None, all_versions: bool = False,
                include_deprecated: bool = False) -> list[Match]:
        """The ``k`` versions of ``joint_type`` closest to ``conditions``."""

    def interpolate(self, matches, conditions: Conditions | Mapping[str, Any] | None = None, *,
                    method: str = "axes") -> InterpolatedJoint:
        """An interpolated joint between matches (dynamic stiffness)."""

    def label(self, name: str, version: int, label: str, author: str | None = None) -> JointVersion:
        """Point ``label`` of a joint at ``version``."""

    def deprecate(self, name: str, version: int | None = None, reason: str = "", author: str | None = None,
                  undo: bool = False) -> list[JointVersion]:
        """Mark a version (or the whole joint) deprecated, or undo it; the history afterwards."""

    def audit(self, name: str | None = None, limit: int = 100) -> list[dict[str, Any]]:
        """The newest audit-log entries (optionally of one joint)."""

    # parts of stacks (spindles, holders, tools; jointdb.store._parts, _part_records)
    def add_part(self, name: str, kind: str, payload: Mapping[str, Any], *, frf: FRF | None = None,
                 attributes: Mapping[str, Any] | None = None, provenance: Mapping[str, Any] | None = None,
                 author: str | None = None, label: str | None = None) -> PartVersion:
        """Catalogue a part as a new version (the latest one when identical)."""

    def get_part(self, name: str, version: int | None = None, label: str | None = None) -> PartVersion:
        """One part version (pinned, by label, or the latest), its record verified."""

    def resolve_part(self, ref: str) -> PartVersion:
        """The part version a ``name@version`` / ``name@label`` reference names."""

    def part_history(self, name: str) -> list[PartVersion]:
        """Every version of a part, oldest first."""

    def list_parts(self, kind: str | None = None, *, family: str | None = None,
                   machine: str | None = None) -> list[PartVersion]:
        """The latest version of every part (optionally of one kind, holder family or machine)."""

    def label_part(self, name: str, version: int, label: str, author: str | None = None) -> PartVersion:
        """Point ``label`` of a part at ``version``."""

    def load_part_frf(self, part: PartVersion) -> FRF:
        """A measured spindle's verified FRF set."""


@runtime_checkable
class LocalJointStore(JointStore, Protocol):
    """A :class:`JointStore` holding its database: paging, raw measurements, maintenance, bundles."""

    blobs: BlobStoreProtocol

    def list_page(self, joint_type: str | None = None, *, materials: Iterable[str] = (), label: str | None = None,
                  include_deprecated: bool = True, state: str | None = None, torque_min: float | None = None,
                  torque_max: float | None = None, preload_min: float | None = None,
                  preload_max: float | None = None, name_contains: str | None = None, after: str | None = None,
                  offset: int = 0, limit: int | None = 50) -> JointPage:
        """One page of the catalogue, in one SQL statement."""

    def load_raw(self, version: JointVersion, key: str) -> FRF:
        """One raw measurement FRF stored with a version."""

    def idempotent_answer(self, idempotency: tuple[str, str, str] | None) -> Catalogued | None:
        """The stored answer to an idempotency key, or None when the key is new."""

    def check(self, verify_blobs: bool = True) -> CheckReport:
        """Walk every row and blob; report missing or corrupt data."""

    def gc(self, min_age_s: float = 3600.0, dry_run: bool = False) -> list[str]:
        """Remove blobs no row references, older than ``min_age_s``."""

    def export(self, names: Iterable[str] | None, path: str | os.PathLike, *, sign_key=None) -> dict[str, Any]:
        """Write joints (all versions, labels, states) to one HDF5 bundle."""

    def import_(self, path, author: str | None = None, *, trusted_keys=(), require_signature: bool = False,
                force: bool = False) -> dict[str, Any]:
        """Import a bundle."""


def protocol_methods(protocol: type) -> tuple[str, ...]:
    """The methods a protocol declares (its own and inherited), by name."""
    names = set()
    for klass in protocol.__mro__:
        if klass in (Protocol, object) or not getattr(klass, "_is_protocol", False):
            continue
        names.update(n for n, v in vars(klass).items() if callable(v) and not n.startswith("_"))
    return tuple(sorted(names))

