"""The history chain: an append-only hash chain over every history row (``history_chain``).

One entry per row of ``joints``, ``joint_versions``, ``joint_states`` and ``audit_log``
(see :mod:`jointdb.store._chain`): ``(seq, kind, row id, content hash, head)``. The table is
guarded like the history it covers: SQLite triggers refuse UPDATE, DELETE and INSERT over an
existing entry; PostgreSQL refuses UPDATE/DELETE (``jointdb_refuse_change`` of ``0002``) and
TRUNCATE (``jointdb_refuse_truncate`` of ``0003``), enabled ALWAYS. The chain of an existing
database is built here over its rows, kind by kind in id order.

Revision ID: 0006
Revises: 0005
Create Date: 2026-11-25
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0006"
down_revision = "0005"
branch_labels = None
depends_on = None

TABLE = "history_chain"


def upgrade() -> None:
    op.create_table(
        TABLE,
        sa.Column("seq", sa.BigInteger(), autoincrement=False, nullable=False),
        sa.Column("kind", sa.String(length=20), nullable=False),
        sa.Column("row_id", sa.Integer(), nullable=False),
        sa.Column("content_sha256", sa.String(length=64), nullable=False),
        sa.Column("head_sha256", sa.String(length=64), nullable=False),
        sa.PrimaryKeyConstraint("seq", name=op.f("pk_history_chain")),
        sa.UniqueConstraint("kind", "row_id", name=op.f("uq_history_chain_kind_row_id")),
    )
    bind = op.get_bind()
    if bind.dialect.name == "sqlite":
        for event in ("UPDATE", "DELETE"):
            op.execute(f"CREATE TRIGGER {TABLE}_no_{event.lower()} BEFORE {event} ON {TABLE} "
                       f"BEGIN SELECT RAISE(ABORT, 'jointdb: {TABLE} rows are immutable ({event} refused)'); END")
        op.execute(f"CREATE TRIGGER {TABLE}_no_replace BEFORE INSERT ON {TABLE} "
                   f"WHEN EXISTS (SELECT 1 FROM {TABLE} WHERE seq = NEW.seq OR (kind = NEW.kind AND row_id = NEW.row_id)) "
                   f"BEGIN SELECT RAISE(ABORT, 'jointdb: {TABLE} rows are immutable "
                   "(INSERT over an existing row refused)'); END")
    else:
        op.execute(f"CREATE TRIGGER {TABLE}_immutable BEFORE UPDATE OR DELETE ON {TABLE} "
                   "FOR EACH ROW EXECUTE FUNCTION jointdb_refuse_change()")
        op.execute(f"CREATE TRIGGER {TABLE}_no_truncate BEFORE TRUNCATE ON {TABLE} "
                   "FOR EACH STATEMENT EXECUTE FUNCTION jointdb_refuse_truncate()")
        for trigger in ("immutable", "no_truncate"):
            op.execute(f"ALTER TABLE {TABLE} ENABLE ALWAYS TRIGGER {TABLE}_{trigger}")
    from jointdb.store._chain import build_chain

    build_chain(bind)


def downgrade() -> None:
    bind = op.get_bind()
    if bind.dialect.name == "sqlite":
        for event in ("update", "delete", "replace"):
            op.execute(f"DROP TRIGGER IF EXISTS {TABLE}_no_{event}")
    else:
        op.execute(f"DROP TRIGGER IF EXISTS {TABLE}_immutable ON {TABLE}")
        op.execute(f"DROP TRIGGER IF EXISTS {TABLE}_no_truncate ON {TABLE}")
    op.drop_table(TABLE)
