"""SQLAlchemy 2 models of the joint database (schema changes only via Alembic).

Tables
------
``joints``          identity: name (unique) and joint type. Immutable.
``joint_versions``  one immutable row per ``(joint, version)``: conditions, model
                    kind, DOF labels, frequency range, blob hash, provenance,
                    quality. ``UNIQUE(joint_id, version)`` backs the numbering.
``joint_states``    append-only state changes (``deprecated`` / ``active``) of a
                    joint or one of its versions; the latest row wins.
``labels``          mutable named pointers (``released``, ``default``) to versions.
``audit_log``       append-only: who did what, when.
``parts``, ``part_versions``  spindles, holders and tools of stacks (migration ``0009``):
                    immutable versions like the joints', with ``part_labels``.
``query_*``         derived (migration ``0004``): the ranking conditions and current
                    standing of every version, for the nearest query; rebuilt from
                    the tables above in the transactions that change them.

Immutability is enforced twice: here (a ``before_flush`` hook refuses updates
and deletes of immutable rows) and in the database (triggers created by the
migration ``0002`` refuse UPDATE and DELETE).
"""

from __future__ import annotations

from datetime import datetime, timezone
from typing import Any

from sqlalchemy import (
    JSON,
    BigInteger,
    Boolean,
    CheckConstraint,
    DateTime,
    Float,
    ForeignKey,
    ForeignKeyConstraint,
    Index,
    Integer,
    LargeBinary,
    MetaData,
    String,
    Text,
    UniqueConstraint,
    event,
)
from sqlalchemy.orm import DeclarativeBase, Mapped, Session, mapped_column
from sqlalchemy.types import TypeDecorator

from jointdb.errors import ConflictError

NAMING_CONVENTION = {
    "ix": "ix_%(column_0_label)s",
    "uq": "uq_%(table_name)s_%(column_0_N_name)s",
    "ck": "ck_%(table_name)s_%(constraint_name)s",
    "fk": "fk_%(table_name)s_%(column_0_N_name)s_%(referred_table_name)s",
    "pk": "pk_%(table_name)s",
}


class UTCDateTime(TypeDecorator):
    """Timezone-aware UTC datetimes on every backend (naive UTC text on SQLite)."""

    impl = DateTime(timezone=True)
    cache_ok = True

    def process_bind_param(self, value: datetime | None, dialect) -> datetime | None:
        if value is None:
            return None
        if value.tzinfo is None:
            raise ValueError("naive datetime given to the database; use timezone-aware UTC")
        value = value.astimezone(timezone.utc)
        if dialect.name == "sqlite":
            return value.replace(tzinfo=None)
        return value

    def process_result_value(self, value: datetime | None, dialect) -> datetime | None:
        if value is None:
            return None
        if value.tzinfo is None:
            return value.replace(tzinfo=timezone.utc)
        return value.astimezone(timezone.utc)


def utcnow() -> datetime:
    return datetime.now(timezone.utc)


class Base(DeclarativeBase):
    metadata = MetaData(naming_convention=NAMING_CONVENTION)


class JointRow(Base):
    __tablename__ = "joints"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    name: Mapped[str] = mapped_column(String(200), unique=True)
    joint_type: Mapped[str] = mapped_column(String(100), index=True)
    created_at: Mapped[datetime] = mapped_column(UTCDateTime())
    created_by: Mapped[str] = mapped_column(String(200))


class VersionRow(Base):
    __tablename__ = "joint_versions"
    __table_args__ = (
        UniqueConstraint("joint_id", "version"),
        CheckConstraint("version >= 1", name="version_positive"),
        CheckConstraint("parent_version IS NULL OR parent_version < version", name="parent_before"),
        CheckConstraint("preload_n IS NULL OR preload_n >= 0", name="preload_nonneg"),
        CheckConstraint("torque_nm IS NULL OR torque_nm >= 0", name="torque_nonneg"),
        CheckConstraint("n_freq >= 1", name="n_freq_positive"),
        Index("ix_joint_versions_joint_id_created_at", "joint_id", "created_at"),
    )

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    joint_id: Mapped[int] = mapped_column(ForeignKey("joints.id", ondelete="RESTRICT"))
    version: Mapped[int] = mapped_column(Integer)
    uuid: Mapped[str] = mapped_column(String(36), unique=True)
    created_at: Mapped[datetime] = mapped_column(UTCDateTime())
    author: Mapped[str] = mapped_column(String(200))
    # conditions
    materials: Mapped[list] = mapped_column(JSON)
    preload_n: Mapped[float | None] = mapped_column(Float)
    torque_nm: Mapped[float | None] = mapped_column(Float)
    geometry: Mapped[dict] = mapped_column(JSON)
    extra: Mapped[dict] = mapped_column(JSON)
    # model and FRF
    model_kind: Mapped[str] = mapped_column(String(50))
    dofs: Mapped[list] = mapped_column(JSON)
    quantity: Mapped[str] = mapped_column(String(20))
    n_freq: Mapped[int] = mapped_column(Integer)
    freq_min_hz: Mapped[float] = mapped_column(Float)
    freq_max_hz: Mapped[float] = mapped_column(Float)
    blob_sha256: Mapped[str] = mapped_column(String(64), index=True)
    raw_blobs: Mapped[dict] = mapped_column(JSON)
    # provenance
    input_files: Mapped[dict] = mapped_column(JSON)
    method: Mapped[str] = mapped_column(String(200))
    method_params: Mapped[dict] = mapped_column(JSON)
    software_version: Mapped[str] = mapped_column(String(50))
    parent_version: Mapped[int | None] = mapped_column(Integer)
    # quality and integrity
    quality: Mapped[dict] = mapped_column(JSON)
    record_sha256: Mapped[str] = mapped_column(String(64))


class StateRow(Base):
    __tablename__ = "joint_states"
    __table_args__ = (
        CheckConstraint("state IN ('active', 'deprecated')", name="state_known"),
        Index("ix_joint_states_joint_id_at", "joint_id", "at"),
    )

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    joint_id: Mapped[int] = mapped_column(ForeignKey("joints.id", ondelete="RESTRICT"))
    version: Mapped[int | None] = mapped_column(Integer)  # None: the whole joint
    state: Mapped[str] = mapped_column(String(20))
    reason: Mapped[str] = mapped_column(Text)
    author: Mapped[str] = mapped_column(String(200))
    at: Mapped[datetime] = mapped_column(UTCDateTime())


class LabelColumns:
    """The columns every label table has besides its owner (a joint's, a part's): a mutable
    named pointer at one version of the owner, and who moved it when."""

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    label: Mapped[str] = mapped_column(String(100))
    version: Mapped[int] = mapped_column(Integer)
    updated_at: Mapped[datetime] = mapped_column(UTCDateTime())
    updated_by: Mapped[str] = mapped_column(String(200))


class LabelRow(LabelColumns, Base):
    __tablename__ = "labels"
    __table_args__ = (
        UniqueConstraint("joint_id", "label"),
        Index("ix_labels_label", "label"),  # migration 0004: the query's --label
        ForeignKeyConstraint(
            ["joint_id", "version"], ["joint_versions.joint_id", "joint_versions.version"], ondelete="RESTRICT"
        ),
    )

    joint_id: Mapped[int] = mapped_column(ForeignKey("joints.id", ondelete="RESTRICT"))


class AuditRow(Base):
    __tablename__ = "audit_log"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    at: Mapped[datetime] = mapped_column(UTCDateTime(), index=True)
    actor: Mapped[str] = mapped_column(String(200))
    action: Mapped[str] = mapped_column(String(50))
    joint_name: Mapped[str | None] = mapped_column(String(200))
    version: Mapped[int | None] = mapped_column(Integer)
    details: Mapped[dict[str, Any]] = mapped_column(JSON)


class TokenRow(Base):
    """An API token of the HTTP service (migration 0005): only its SHA-256 is stored.

    ``name`` is the owner the audit log records for the token's writes; ``token_id``
    is the public part shown by ``jointdb tokens list``. Revoking sets ``revoked_at``
    (the row stays, so the audit trail keeps its owner).
    """

    __tablename__ = "api_tokens"
    __table_args__ = (CheckConstraint("role IN ('reader', 'writer', 'admin')", name="role_known"),)

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    token_id: Mapped[str] = mapped_column(String(32), unique=True)
    sha256: Mapped[str] = mapped_column(String(64), unique=True)
    name: Mapped[str] = mapped_column(String(200))
    role: Mapped[str] = mapped_column(String(20))
    created_at: Mapped[datetime] = mapped_column(UTCDateTime())
    created_by: Mapped[str] = mapped_column(String(200))
    expires_at: Mapped[datetime | None] = mapped_column(UTCDateTime())
    revoked_at: Mapped[datetime | None] = mapped_column(UTCDateTime())
    team: Mapped[str | None] = mapped_column(String(100))  # migration 0008: shares joint ownership


class WebSessionRow(Base):
    """A sign-in of the web catalogue (migration 0008): the cookie holds a random session id,
    the database only its SHA-256, the token it was opened with and its times. Revoking sets
    ``revoked_at``; a session ends with its token."""

    __tablename__ = "web_sessions"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    sha256: Mapped[str] = mapped_column(String(64), unique=True)
    token_id: Mapped[str] = mapped_column(ForeignKey("api_tokens.token_id", ondelete="CASCADE"), index=True)
    owner: Mapped[str] = mapped_column(String(200))
    created_at: Mapped[datetime] = mapped_column(UTCDateTime())
    last_seen_at: Mapped[datetime] = mapped_column(UTCDateTime())
    expires_at: Mapped[datetime] = mapped_column(UTCDateTime(), index=True)
    revoked_at: Mapped[datetime | None] = mapped_column(UTCDateTime())


class BlobRow(Base):
    """A content-addressed FRF blob kept in the database (migration 0005; ``blobs="database"``).

    ``data`` holds exactly the bytes of a blob file (:mod:`jointdb.store._blobs`: user block
    with the whole-file SHA-256, then HDF5), so reads verify the same three ways as files.
    ``touched_at`` is refreshed by every put, so ``gc`` spares a blob a writer is about to
    reference.
    """

    __tablename__ = "frf_blobs"

    sha256: Mapped[str] = mapped_column(String(64), primary_key=True)
    data: Mapped[bytes] = mapped_column(LargeBinary)
    size: Mapped[int] = mapped_column(Integer)
    created_at: Mapped[datetime] = mapped_column(UTCDateTime())
    touched_at: Mapped[datetime] = mapped_column(UTCDateTime())


class IdempotencyRow(Base):
    """The answer to one catalogue request made with an ``Idempotency-Key`` (migration 0007).

    Unique per (token owner, key); ``request_sha256`` is the hash of the request body, so the
    same key with another body is refused. Written in the transaction of the version it names.
    """

    __tablename__ = "idempotency_keys"
    __table_args__ = (UniqueConstraint("owner", "key"),)

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    owner: Mapped[str] = mapped_column(String(200))
    key: Mapped[str] = mapped_column(String(200))
    request_sha256: Mapped[str] = mapped_column(String(64))
    joint_name: Mapped[str] = mapped_column(String(200))
    version: Mapped[int] = mapped_column(Integer)
    status: Mapped[int] = mapped_column(Integer)
    created_at: Mapped[datetime] = mapped_column(UTCDateTime())


class PartRow(Base):
    """A part of a stack (migration 0009): a spindle, holder or tool, by name. Immutable."""

    __tablename__ = "parts"
    __table_args__ = (CheckConstraint("kind IN ('spindle', 'holder', 'tool')", name="kind_known"),)

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    name: Mapped[str] = mapped_column(String(200), unique=True)
    kind: Mapped[str] = mapped_column(String(20), index=True)
    created_at: Mapped[datetime] = mapped_column(UTCDateTime())
    created_by: Mapped[str] = mapped_column(String(200))


class PartVersionRow(Base):
    """One immutable version of a part (migration 0009): its attributes (``machine``; ``family``,
    ``taper``, ``bore_mm``), its payload (the stack-file object of the part, JSON) and, for a
    measured spindle, the content-addressed FRF blob of its nose receptances; provenance and the
    ``record_sha256`` that every read verifies."""

    __tablename__ = "part_versions"
    __table_args__ = (
        UniqueConstraint("part_id", "version"),
        CheckConstraint("version >= 1", name="version_positive"),
        CheckConstraint("parent_version IS NULL OR parent_version < version", name="parent_before"),
    )

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    part_id: Mapped[int] = mapped_column(ForeignKey("parts.id", ondelete="RESTRICT"), index=True)
    version: Mapped[int] = mapped_column(Integer)
    uuid: Mapped[str] = mapped_column(String(36), unique=True)
    created_at: Mapped[datetime] = mapped_column(UTCDateTime())
    author: Mapped[str] = mapped_column(String(200))
    machine: Mapped[str | None] = mapped_column(String(200), index=True)
    family: Mapped[str | None] = mapped_column(String(100), index=True)
    attributes: Mapped[dict] = mapped_column(JSON)
    payload: Mapped[dict] = mapped_column(JSON)
    blob_sha256: Mapped[str | None] = mapped_column(String(64), index=True)
    provenance: Mapped[dict] = mapped_column(JSON)
    parent_version: Mapped[int | None] = mapped_column(Integer)
    record_sha256: Mapped[str] = mapped_column(String(64))


class PartLabelRow(LabelColumns, Base):
    """A mutable named pointer (``released``, ``default``) at a part version (migration 0009)."""

    __tablename__ = "part_labels"
    __table_args__ = (
        UniqueConstraint("part_id", "label"),
        ForeignKeyConstraint(
            ["part_id", "version"], ["part_versions.part_id", "part_versions.version"], ondelete="RESTRICT"
        ),
    )

    part_id: Mapped[int] = mapped_column(ForeignKey("parts.id", ondelete="RESTRICT"))


IMMUTABLE = (JointRow, VersionRow, StateRow, AuditRow, PartRow, PartVersionRow)
#: Tables the database itself protects with UPDATE/DELETE triggers (migrations 0002, 0009).
IMMUTABLE_TABLES = ("joints", "joint_versions", "joint_states", "audit_log", "parts", "part_versions")


@event.listens_for(Session, "before_flush")
def _refuse_changes_to_immutable_rows(session: Session, flush_context, instances) -> None:
    for obj in session.deleted:
        if isinstance(obj, IMMUTABLE):
            raise ConflictError(
                f"{obj.__tablename__} rows are never deleted; deprecate instead (jointdb joints deprecate)"
            )
    for obj in session.dirty:
        if isinstance(obj, IMMUTABLE) and session.is_modified(obj, include_collections=False):
            raise ConflictError(
                f"{obj.__tablename__} rows are immutable; catalogue a new version instead of editing one"
            )


# --------------------------------------------------------------------------- derived: the query index
class QueryVersionRow(Base):
    """One row per catalogued version: its ranking conditions as typed columns and its current
    standing (deprecated; newest of its joint; newest not deprecated; ``listed``: the version
    :meth:`Repository.get` returns, one per joint). Derived from the history tables, rewritten
    in the same transaction as every change to them (migrations ``0004``, ``0010``;
    :mod:`jointdb.store._index`); not a history table, so UPDATE is allowed. ``name`` repeats
    the joint's (immutable) name so that a listing page is one range of ``ix_query_versions_listed_name``."""

    __tablename__ = "query_versions"
    __table_args__ = (
        Index("ix_query_versions_type_newest_active", "joint_type", "newest_active", "version_id", "packed",
              "materials"),  # covering for the default query
        Index("ix_query_versions_joint_id", "joint_id"),
        Index("ix_query_versions_listed_name", "listed", "name"),  # a listing page: one index range
        Index("ix_query_versions_type_listed_name", "joint_type", "listed", "name"),
    )

    version_id: Mapped[int] = mapped_column(ForeignKey("joint_versions.id", ondelete="RESTRICT"), primary_key=True)
    joint_id: Mapped[int] = mapped_column(Integer)
    joint_type: Mapped[str] = mapped_column(String(100))
    version: Mapped[int] = mapped_column(Integer)
    deprecated: Mapped[bool] = mapped_column(Boolean)
    newest: Mapped[bool] = mapped_column(Boolean)
    newest_active: Mapped[bool] = mapped_column(Boolean)
    listed: Mapped[bool] = mapped_column(Boolean)  # newest_active, or newest when every version is deprecated
    name: Mapped[str] = mapped_column(String(200))  # the joint's name (joint names never change)
    torque_nm: Mapped[float | None] = mapped_column(Float)
    preload_n: Mapped[float | None] = mapped_column(Float)
    materials: Mapped[str] = mapped_column(Text)  # JSON text of the sorted material list
    packed: Mapped[bytes] = mapped_column(LargeBinary)  # version_id, joint_id, version, torque, preload (_index)


class QueryGeometryRow(Base):
    """The geometry numbers of a version, one row per key (derived, with :class:`QueryVersionRow`)."""

    __tablename__ = "query_geometry"
    __table_args__ = {"sqlite_with_rowid": False}

    key: Mapped[str] = mapped_column(String(100), primary_key=True)
    version_id: Mapped[int] = mapped_column(ForeignKey("joint_versions.id", ondelete="RESTRICT"), primary_key=True)
    value: Mapped[float] = mapped_column(Float)
    bits: Mapped[bytes] = mapped_column(LargeBinary)  # value as little-endian float64


class QueryCountRow(Base):
    """How many joints the listing shows, per joint type and standing of the listed version: the
    ``total`` of an unfiltered (or type- or state-filtered) listing without counting rows. Derived
    with :class:`QueryVersionRow` in the same transactions (migration ``0010``)."""

    __tablename__ = "query_counts"

    joint_type: Mapped[str] = mapped_column(String(100), primary_key=True)
    deprecated: Mapped[bool] = mapped_column(Boolean, primary_key=True)
    joints: Mapped[int] = mapped_column(BigInteger)


class QueryChangeRow(Base):
    """The query index's change log (migration ``0011``): per transaction that changes what a
    nearest query can return, its stamp generation and each joint it touched (``joint_id`` NULL:
    any joint may have changed). Lets a reader holding older candidate arrays refetch only the
    rows of those joints (:func:`jointdb.store._index.note_change`). Derived, pruned state."""

    __tablename__ = "query_changes"
    __table_args__ = (Index("ix_query_changes_generation", "generation"),)

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    generation: Mapped[int] = mapped_column(BigInteger)
    joint_id: Mapped[int | None] = mapped_column(Integer, nullable=True)


class QueryStampRow(Base):
    """One row: a token fixed when the index is built and a generation counter increased by
    every transaction that changes what a query can return (versions, states, labels)."""

    __tablename__ = "query_stamp"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    token: Mapped[str] = mapped_column(String(36))
    generation: Mapped[int] = mapped_column(BigInteger)
