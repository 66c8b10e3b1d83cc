"""Query index: the ranking conditions and current standing of every version, as typed,
indexed columns, for the nearest query (derived state; see ``jointdb.store._index``).

``query_versions`` (one row per version), ``query_geometry`` (one row per version and
geometry key) and ``query_stamp`` (one row: token and generation) are built from the
history tables here (backfill) and kept current by the write transactions of
``catalogue``, ``label``, ``deprecate`` and ``import``. They are not history: the
guards of ``0002``/``0003`` do not cover them, and ``jointdb db check`` compares them
with the history they derive from. An index on ``labels(label)`` serves ``--label``.

Revision ID: 0004
Revises: 0003
Create Date: 2026-11-23
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0004"
down_revision = "0003"
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.create_table(
        "query_versions",
        sa.Column("version_id", sa.Integer(), nullable=False),
        sa.Column("joint_id", sa.Integer(), nullable=False),
        sa.Column("joint_type", sa.String(length=100), nullable=False),
        sa.Column("version", sa.Integer(), nullable=False),
        sa.Column("deprecated", sa.Boolean(), nullable=False),
        sa.Column("newest", sa.Boolean(), nullable=False),
        sa.Column("newest_active", sa.Boolean(), nullable=False),
        sa.Column("torque_nm", sa.Float(), nullable=True),
        sa.Column("preload_n", sa.Float(), nullable=True),
        sa.Column("materials", sa.Text(), nullable=False),
        sa.Column("packed", sa.LargeBinary(), nullable=False),
        sa.ForeignKeyConstraint(["version_id"], ["joint_versions.id"], ondelete="RESTRICT",
                                name=op.f("fk_query_versions_version_id_joint_versions")),
        sa.PrimaryKeyConstraint("version_id", name=op.f("pk_query_versions")),
    )
    # covering: a default query reads the index alone (SQLite), in version order
    op.create_index("ix_query_versions_type_newest_active", "query_versions",
                    ["joint_type", "newest_active", "version_id", "packed", "materials"])
    op.create_index("ix_query_versions_joint_id", "query_versions", ["joint_id"])
    op.create_table(
        "query_geometry",
        sa.Column("key", sa.String(length=100), nullable=False),
        sa.Column("version_id", sa.Integer(), nullable=False),
        sa.Column("value", sa.Float(), nullable=False),
        sa.Column("bits", sa.LargeBinary(), nullable=False),
        sa.ForeignKeyConstraint(["version_id"], ["joint_versions.id"], ondelete="RESTRICT",
                                name=op.f("fk_query_geometry_version_id_joint_versions")),
        sa.PrimaryKeyConstraint("key", "version_id", name=op.f("pk_query_geometry")),
        sqlite_with_rowid=False,  # clustered on (key, version_id): one B-tree search per lookup
    )
    op.create_table(
        "query_stamp",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("token", sa.String(length=36), nullable=False),
        sa.Column("generation", sa.BigInteger(), nullable=False),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_query_stamp")),
    )
    op.create_index("ix_labels_label", "labels", ["label"])
    from jointdb.store._index import rebuild

    rebuild(op.get_bind())


def downgrade() -> None:
    op.drop_index("ix_labels_label", table_name="labels")
    op.drop_table("query_stamp")
    op.drop_table("query_geometry")
    op.drop_index("ix_query_versions_joint_id", table_name="query_versions")
    op.drop_index("ix_query_versions_type_newest_active", table_name="query_versions")
    op.drop_table("query_versions")
