"""Parts of stacks as versioned records: ``parts``, ``part_versions``, ``part_labels``.

A part is a spindle (per machine: a beam model, or the measured FRF set of its nose as a
content-addressed blob), a holder (family, taper, bore) or a tool. Its versions are immutable
and guarded like the joints' history: SQLite triggers refuse UPDATE, DELETE and INSERT over an
existing row; PostgreSQL refuses UPDATE/DELETE (``jointdb_refuse_change`` of ``0002``) and
TRUNCATE (``jointdb_refuse_truncate`` of ``0003``; also on ``part_labels``), all enabled ALWAYS.
Every new part and part version gets an entry of the history chain (``0006``).

Revision ID: 0009
Revises: 0008
Create Date: 2026-11-26
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0009"
down_revision = "0008"
branch_labels = None
depends_on = None

HISTORY = ("parts", "part_versions")
KEYS = {
    "parts": "id = NEW.id OR name = NEW.name",
    "part_versions": "id = NEW.id OR uuid = NEW.uuid OR (part_id = NEW.part_id AND version = NEW.version)",
}
TRUNCATE_GUARDED = HISTORY + ("part_labels",)


def _create_tables() -> None:
    op.create_table(
        "parts",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("name", sa.String(length=200), nullable=False),
        sa.Column("kind", sa.String(length=20), nullable=False),
        sa.Column("created_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("created_by", sa.String(length=200), nullable=False),
        sa.CheckConstraint("kind IN ('spindle', 'holder', 'tool')", name=op.f("ck_parts_kind_known")),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_parts")),
        sa.UniqueConstraint("name", name=op.f("uq_parts_name")),
    )
    op.create_index(op.f("ix_parts_kind"), "parts", ["kind"], unique=False)
    op.create_table(
        "part_versions",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("part_id", sa.Integer(), nullable=False),
        sa.Column("version", sa.Integer(), nullable=False),
        sa.Column("uuid", sa.String(length=36), nullable=False),
        sa.Column("created_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("author", sa.String(length=200), nullable=False),
        sa.Column("machine", sa.String(length=200), nullable=True),
        sa.Column("family", sa.String(length=100), nullable=True),
        sa.Column("attributes", sa.JSON(), nullable=False),
        sa.Column("payload", sa.JSON(), nullable=False),
        sa.Column("blob_sha256", sa.String(length=64), nullable=True),
        sa.Column("provenance", sa.JSON(), nullable=False),
        sa.Column("parent_version", sa.Integer(), nullable=True),
        sa.Column("record_sha256", sa.String(length=64), nullable=False),
        sa.CheckConstraint("version >= 1", name=op.f("ck_part_versions_version_positive")),
        sa.CheckConstraint("parent_version IS NULL OR parent_version < version",
                           name=op.f("ck_part_versions_parent_before")),
        sa.ForeignKeyConstraint(["part_id"], ["parts.id"], ondelete="RESTRICT",
                                name=op.f("fk_part_versions_part_id_parts")),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_part_versions")),
        sa.UniqueConstraint("part_id", "version", name=op.f("uq_part_versions_part_id_version")),
        sa.UniqueConstraint("uuid", name=op.f("uq_part_versions_uuid")),
    )
    for col in ("part_id", "machine", "family", "blob_sha256"):
        op.create_index(op.f(f"ix_part_versions_{col}"), "part_versions", [col], unique=False)
    op.create_table(
        "part_labels",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("part_id", sa.Integer(), nullable=False),
        sa.Column("label", sa.String(length=100), nullable=False),
        sa.Column("version", sa.Integer(), nullable=False),
        sa.Column("updated_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("updated_by", sa.String(length=200), nullable=False),
        sa.ForeignKeyConstraint(["part_id", "version"], ["part_versions.part_id", "part_versions.version"],
                                ondelete="RESTRICT", name=op.f("fk_part_labels_part_id_part_versions")),
        sa.ForeignKeyConstraint(["part_id"], ["parts.id"], ondelete="RESTRICT",
                                name=op.f("fk_part_labels_part_id_parts")),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_part_labels")),
        sa.UniqueConstraint("part_id", "label", name=op.f("uq_part_labels_part_id_label")),
    )


def upgrade() -> None:
    _create_tables()
    dialect = op.get_bind().dialect.name
    if dialect == "sqlite":
        for table in HISTORY:
            for event in ("UPDATE", "DELETE"):
                op.execute(f"CREATE TRIGGER {table}_no_{event.lower()} BEFORE {event} ON {table} "
                           f"BEGIN SELECT RAISE(ABORT, 'jointdb: {table} rows are immutable ({event} refused)'); END")
            op.execute(f"CREATE TRIGGER {table}_no_replace BEFORE INSERT ON {table} "
                       f"WHEN EXISTS (SELECT 1 FROM {table} WHERE {KEYS[table]}) "
                       f"BEGIN SELECT RAISE(ABORT, 'jointdb: {table} rows are immutable "
                       "(INSERT over an existing row refused)'); END")
        return
    if dialect != "postgresql":  # pragma: no cover - only the two supported backends
        raise NotImplementedError(f"no immutability triggers for {dialect}")
    for table in HISTORY:
        op.execute(f"CREATE TRIGGER {table}_immutable BEFORE UPDATE OR DELETE ON {table} "
                   "FOR EACH ROW EXECUTE FUNCTION jointdb_refuse_change()")
        op.execute(f"ALTER TABLE {table} ENABLE ALWAYS TRIGGER {table}_immutable")
    for table in TRUNCATE_GUARDED:
        op.execute(f"CREATE TRIGGER {table}_no_truncate BEFORE TRUNCATE ON {table} "
                   "FOR EACH STATEMENT EXECUTE FUNCTION jointdb_refuse_truncate()")
        op.execute(f"ALTER TABLE {table} ENABLE ALWAYS TRIGGER {table}_no_truncate")


def downgrade() -> None:
    # the history chain keeps the entries of parts written meanwhile: a downgrade that drops their rows
    # breaks the chain, so it is refused while any part exists
    bind = op.get_bind()
    if bind.exec_driver_sql("SELECT count(*) FROM parts").scalar():
        from jointdb.errors import InputError

        raise InputError("the database holds catalogued parts; downgrading below 0009 would remove their history "
                         "(the history chain covers them), so it is refused")
    if bind.dialect.name == "sqlite":
        for table in HISTORY:
            for event in ("update", "delete", "replace"):
                op.execute(f"DROP TRIGGER IF EXISTS {table}_no_{event}")
    op.drop_table("part_labels")
    for col in ("part_id", "machine", "family", "blob_sha256"):
        op.drop_index(op.f(f"ix_part_versions_{col}"), table_name="part_versions")
    op.drop_table("part_versions")
    op.drop_index(op.f("ix_parts_kind"), table_name="parts")
    op.drop_table("parts")
