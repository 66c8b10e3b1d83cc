"""The query index's change log: ``query_changes`` holds ``(generation, joint_id)`` for every
transaction that changes what a nearest query can return (a new version, a state, a label, an
import), written in that transaction with the stamp's new generation (``joint_id`` NULL: every
joint may have changed, e.g. a rebuild). A reader holding the candidate arrays of generation
``g`` reads the joints changed since ``g`` and refetches only their rows
(:mod:`jointdb.store._nearest`); a gap in the log (pruned, or written by an older jointdb)
makes it refetch everything. Derived state like the rest of the query index (``0004``).

Revision ID: 0011
Revises: 0010
Create Date: 2026-11-26
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0011"
down_revision = "0010"
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.create_table(
        "query_changes",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("generation", sa.BigInteger(), nullable=False),
        sa.Column("joint_id", sa.Integer(), nullable=True),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_query_changes")),
    )
    op.create_index("ix_query_changes_generation", "query_changes", ["generation"])


def downgrade() -> None:
    op.drop_index("ix_query_changes_generation", table_name="query_changes")
    op.drop_table("query_changes")
