"""Immutability in the database: triggers refuse UPDATE and DELETE of
joints, joint versions, joint states and audit-log rows.

SQLite: BEFORE UPDATE / BEFORE DELETE triggers that RAISE(ABORT, ...).
PostgreSQL: one PL/pgSQL function raising an exception, attached as a
BEFORE UPDATE OR DELETE row trigger to each table.

Revision ID: 0002
Revises: 0001
Create Date: 2026-11-21
"""

from __future__ import annotations

from alembic import op

revision = "0002"
down_revision = "0001"
branch_labels = None
depends_on = None

TABLES = ("joints", "joint_versions", "joint_states", "audit_log")


def upgrade() -> None:
    dialect = op.get_bind().dialect.name
    if dialect == "sqlite":
        for table in TABLES:
            for event in ("UPDATE", "DELETE"):
                op.execute(
                    f"CREATE TRIGGER {table}_no_{event.lower()} BEFORE {event} ON {table} "
                    f"BEGIN SELECT RAISE(ABORT, 'jointdb: {table} rows are immutable ({event} refused)'); END"
                )
    elif dialect == "postgresql":
        op.execute(
            """
            CREATE FUNCTION jointdb_refuse_change() RETURNS trigger LANGUAGE plpgsql AS $$
            BEGIN
                RAISE EXCEPTION 'jointdb: % rows are immutable (% refused)', TG_TABLE_NAME, TG_OP
                    USING ERRCODE = 'integrity_constraint_violation';
            END;
            $$
            """
        )
        for table in TABLES:
            op.execute(
                f"CREATE TRIGGER {table}_immutable BEFORE UPDATE OR DELETE ON {table} "
                "FOR EACH ROW EXECUTE FUNCTION jointdb_refuse_change()"
            )
    else:  # pragma: no cover - only the two supported backends
        raise NotImplementedError(f"no immutability triggers for {dialect}")


def downgrade() -> None:
    dialect = op.get_bind().dialect.name
    if dialect == "sqlite":
        for table in TABLES:
            for event in ("update", "delete"):
                op.execute(f"DROP TRIGGER IF EXISTS {table}_no_{event}")
    elif dialect == "postgresql":
        for table in TABLES:
            op.execute(f"DROP TRIGGER IF EXISTS {table}_immutable ON {table}")
        op.execute("DROP FUNCTION IF EXISTS jointdb_refuse_change()")
