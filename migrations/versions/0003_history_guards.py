"""History guards: refuse REPLACE/UPSERT over history rows, TRUNCATE, and (where the
role can) dropping or disabling the guards themselves.

SQLite
    ``INSERT OR REPLACE`` / ``REPLACE INTO`` delete the conflicting row without
    firing DELETE triggers, so each history table gets a BEFORE INSERT trigger
    that raises when a row with the same key (id, or a unique key) exists.
    An UPSERT (``ON CONFLICT DO UPDATE``) is refused by the same trigger before
    its UPDATE would be. SQLite has no way to refuse ``DROP TRIGGER`` or
    ``DROP TABLE`` to whoever can write the file: ``jointdb db check`` reports a
    missing guard.
PostgreSQL
    BEFORE TRUNCATE statement triggers on the history tables and ``labels``;
    all guard triggers are set ``ENABLE ALWAYS`` so that
    ``session_replication_role = replica`` does not switch them off. When the
    migrating role is a superuser, two event triggers (``sql_drop`` and
    ``ddl_command_end``) refuse dropping a history table and any DDL that
    leaves a guard trigger missing or not ``ALWAYS`` enabled (``DROP TRIGGER``,
    ``ALTER TABLE ... DISABLE TRIGGER``, ``DROP FUNCTION ... CASCADE``,
    ``DROP SCHEMA ... CASCADE``); their function lives in the schema
    ``jointdb_guard`` so that dropping the guarded schema cannot remove it. Only
    the event triggers' owner (a superuser) can drop them, which the downgrade
    of this revision does. Without a superuser no event trigger is created and
    ``jointdb db check`` reports a missing or disabled guard.

Revision ID: 0003
Revises: 0002
Create Date: 2026-12-02
"""

from __future__ import annotations

from alembic import op

revision = "0003"
down_revision = "0002"
branch_labels = None
depends_on = None

HISTORY = ("joints", "joint_versions", "joint_states", "audit_log")
#: SQLite: the keys a REPLACE could collide on, per table.
KEYS = {
    "joints": "id = NEW.id OR name = NEW.name",
    "joint_versions": "id = NEW.id OR uuid = NEW.uuid OR (joint_id = NEW.joint_id AND version = NEW.version)",
    "joint_states": "id = NEW.id",
    "audit_log": "id = NEW.id",
}
TRUNCATE_GUARDED = HISTORY + ("labels",)


GUARD_SCHEMA = "jointdb_guard"  # holds the event-trigger functions, outside the guarded schema


def _event_trigger_names(schema: str) -> tuple[str, str]:
    base = f"jointdb_guard_{schema}"[:50]
    return f"{base}_drop", f"{base}_end"


def _guard_function(schema: str) -> str:
    name = f"guard_{schema}"[:60].replace('"', "")
    return f'{GUARD_SCHEMA}."{name}"'


def upgrade() -> None:
    bind = op.get_bind()
    dialect = bind.dialect.name
    if dialect == "sqlite":
        for table in HISTORY:
            op.execute(
                f"CREATE TRIGGER {table}_no_replace BEFORE INSERT ON {table} "
                f"WHEN EXISTS (SELECT 1 FROM {table} WHERE {KEYS[table]}) "
                f"BEGIN SELECT RAISE(ABORT, 'jointdb: {table} rows are immutable "
                "(INSERT over an existing row refused)'); END"
            )
        return
    if dialect != "postgresql":  # pragma: no cover - only the two supported backends
        raise NotImplementedError(f"no history guards for {dialect}")
    op.execute(
        """
        CREATE FUNCTION jointdb_refuse_truncate() RETURNS trigger LANGUAGE plpgsql AS $$
        BEGIN
            RAISE EXCEPTION 'jointdb: TRUNCATE of % refused (history is never removed)', TG_TABLE_NAME
                USING ERRCODE = 'integrity_constraint_violation';
        END;
        $$
        """
    )
    for table in TRUNCATE_GUARDED:
        op.execute(f"CREATE TRIGGER {table}_no_truncate BEFORE TRUNCATE ON {table} "
                   "FOR EACH STATEMENT EXECUTE FUNCTION jointdb_refuse_truncate()")
        op.execute(f"ALTER TABLE {table} ENABLE ALWAYS TRIGGER {table}_no_truncate")
    for table in HISTORY:
        op.execute(f"ALTER TABLE {table} ENABLE ALWAYS TRIGGER {table}_immutable")
    superuser = bind.exec_driver_sql("SELECT current_setting('is_superuser')").scalar() == "on"
    if not superuser:
        return
    schema = bind.exec_driver_sql("SELECT current_schema()").scalar()
    guards = [f"{t}_immutable" for t in HISTORY] + [f"{t}_no_truncate" for t in TRUNCATE_GUARDED]
    names = ", ".join(f"'{g}'" for g in guards)
    tables = ", ".join(f"'{t}'" for t in TRUNCATE_GUARDED)
    lit = schema.replace("'", "''")
    fn = _guard_function(schema)
    # The function lives outside the guarded schema: `DROP SCHEMA ... CASCADE` must not take
    # the event triggers with it before they could refuse it.
    op.execute(f"CREATE SCHEMA IF NOT EXISTS {GUARD_SCHEMA}")
    op.execute(
        f"""
        CREATE FUNCTION {fn}() RETURNS event_trigger LANGUAGE plpgsql AS $$
        DECLARE
            obj record;
            intact int;
        BEGIN
            IF TG_EVENT = 'sql_drop' THEN
                FOR obj IN SELECT * FROM pg_event_trigger_dropped_objects() LOOP
                    IF obj.object_type = 'table' AND obj.schema_name = '{lit}'
                       AND obj.object_name IN ({tables}) THEN
                        RAISE EXCEPTION 'jointdb: dropping table %.% is refused (history is never removed)',
                            obj.schema_name, obj.object_name USING ERRCODE = 'integrity_constraint_violation';
                    END IF;
                END LOOP;
            END IF;
            IF NOT EXISTS (SELECT 1 FROM pg_class c JOIN pg_namespace n ON n.oid = c.relnamespace
                           WHERE n.nspname = '{lit}' AND c.relname = 'joint_versions') THEN
                RETURN;
            END IF;
            SELECT count(*) INTO intact FROM pg_trigger t JOIN pg_class c ON c.oid = t.tgrelid
                JOIN pg_namespace n ON n.oid = c.relnamespace
                WHERE n.nspname = '{lit}' AND t.tgname IN ({names}) AND t.tgenabled = 'A';
            IF intact < {len(guards)} THEN
                RAISE EXCEPTION 'jointdb: the immutability guards of schema % must stay in place and enabled '
                    '(% of {len(guards)} would remain)', '{lit}', intact
                    USING ERRCODE = 'integrity_constraint_violation';
            END IF;
        END;
        $$
        """
    )
    drop, end = _event_trigger_names(schema)
    op.execute(f'CREATE EVENT TRIGGER "{drop}" ON sql_drop EXECUTE FUNCTION {fn}()')
    op.execute(f'CREATE EVENT TRIGGER "{end}" ON ddl_command_end EXECUTE FUNCTION {fn}()')


def downgrade() -> None:
    bind = op.get_bind()
    dialect = bind.dialect.name
    if dialect == "sqlite":
        for table in HISTORY:
            op.execute(f"DROP TRIGGER IF EXISTS {table}_no_replace")
        return
    schema = bind.exec_driver_sql("SELECT current_schema()").scalar()
    for name in _event_trigger_names(schema):  # first: they would refuse what follows
        op.execute(f'DROP EVENT TRIGGER IF EXISTS "{name}"')
    op.execute(f"DROP FUNCTION IF EXISTS {_guard_function(schema)}()")
    for table in HISTORY:
        op.execute(f"ALTER TABLE {table} ENABLE TRIGGER {table}_immutable")
    for table in TRUNCATE_GUARDED:
        op.execute(f"DROP TRIGGER IF EXISTS {table}_no_truncate ON {table}")
    op.execute("DROP FUNCTION IF EXISTS jointdb_refuse_truncate()")
