"""The listing's head: ``query_versions.listed`` flags the version each joint lists (the newest
active one, else the newest: what ``Repository.get`` returns) and ``query_versions.name`` repeats
the joint's name, so that a page of the catalogue listing is one range of the index
``(listed, name)`` (or ``(joint_type, listed, name)``) — O(page) rows whatever the catalogue's
size, instead of a join and sort over every joint. ``query_counts`` holds the number of listed
joints per joint type and standing (deprecated or not), so that the total of an unfiltered,
type- or state-filtered listing is read, not counted.

The columns and the counts are derived state like the rest of the query index (``0004``): filled here from
the history tables and kept current by the same write transactions; ``jointdb db check``
compares them with history.

Revision ID: 0010
Revises: 0009
Create Date: 2026-11-26
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0010"
down_revision = "0009"
branch_labels = None
depends_on = None


def upgrade() -> None:
    with op.batch_alter_table("query_versions") as batch:
        batch.add_column(sa.Column("listed", sa.Boolean(), nullable=False, server_default=sa.false()))
        batch.add_column(sa.Column("name", sa.String(length=200), nullable=False, server_default=""))
    op.execute("UPDATE query_versions SET name = (SELECT joints.name FROM joints "
               "WHERE joints.id = query_versions.joint_id)")
    # listed: the newest active version, or the newest when the joint has no active version
    op.execute("UPDATE query_versions SET listed = (newest_active OR (newest AND NOT EXISTS ("
               "SELECT 1 FROM query_versions AS q2 WHERE q2.joint_id = query_versions.joint_id "
               "AND q2.newest_active)))")
    with op.batch_alter_table("query_versions") as batch:
        batch.alter_column("listed", server_default=None)
        batch.alter_column("name", server_default=None)
    op.create_index("ix_query_versions_listed_name", "query_versions", ["listed", "name"])
    op.create_index("ix_query_versions_type_listed_name", "query_versions", ["joint_type", "listed", "name"])
    op.create_table(
        "query_counts",
        sa.Column("joint_type", sa.String(length=100), nullable=False),
        sa.Column("deprecated", sa.Boolean(), nullable=False),
        sa.Column("joints", sa.BigInteger(), nullable=False),
        sa.PrimaryKeyConstraint("joint_type", "deprecated", name=op.f("pk_query_counts")),
    )
    op.execute("INSERT INTO query_counts (joint_type, deprecated, joints) SELECT joint_type, deprecated, "
               "COUNT(*) FROM query_versions WHERE listed GROUP BY joint_type, deprecated")


def downgrade() -> None:
    op.drop_table("query_counts")
    op.drop_index("ix_query_versions_type_listed_name", table_name="query_versions")
    op.drop_index("ix_query_versions_listed_name", table_name="query_versions")
    with op.batch_alter_table("query_versions") as batch:
        batch.drop_column("name")
        batch.drop_column("listed")
