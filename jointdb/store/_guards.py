"""Which immutability guards a database at the current schema revision must have, and a check.

The guards are created by migrations ``0002`` (UPDATE/DELETE) and ``0003``
(REPLACE/UPSERT, TRUNCATE, DDL); see those scripts for what each refuses. On
SQLite anyone who can write the file can drop a trigger, and on PostgreSQL the
table owner can unless a superuser installed the DDL event triggers, so
``jointdb db check`` looks for every guard with :func:`missing_guards`.
"""

from __future__ import annotations

from sqlalchemy import Connection, text

HISTORY = ("joints", "joint_versions", "joint_states", "audit_log", "history_chain",  # history_chain: 0006
           "parts", "part_versions")  # 0009
TRUNCATE_GUARDED = HISTORY + ("labels", "part_labels")


def expected_sqlite_triggers() -> list[str]:
    return [f"{t}_no_{e}" for t in HISTORY for e in ("update", "delete", "replace")]


def expected_pg_triggers() -> list[str]:
    return [f"{t}_immutable" for t in HISTORY] + [f"{t}_no_truncate" for t in TRUNCATE_GUARDED]


def event_trigger_names(schema: str) -> tuple[str, str]:
    base = f"jointdb_guard_{schema}"[:50]
    return f"{base}_drop", f"{base}_end"


def guard_function(schema: str) -> str:
    """The event-trigger function of a schema's DDL guard (in the ``jointdb_guard`` schema)."""
    name = f"guard_{schema}"[:60].replace('"', "")
    return f'jointdb_guard."{name}"'


def missing_guards(conn: Connection) -> tuple[list[str], list[str]]:
    """``(problems, notes)``: guards that are missing or disabled, and what the backend cannot enforce."""
    problems: list[str] = []
    notes: list[str] = []
    if conn.dialect.name == "sqlite":
        have = {name: sql or "" for name, sql in conn.execute(
            text("SELECT name, sql FROM sqlite_master WHERE type = 'trigger'"))}
        for name in expected_sqlite_triggers():
            if name not in have:
                problems.append(f"immutability guard {name} is missing (the trigger was dropped)")
            elif "RAISE(ABORT" not in have[name].upper().replace(" ", ""):
                problems.append(f"immutability guard {name} no longer refuses anything (trigger replaced)")
        return problems, notes
    rows = conn.execute(text(
        "SELECT t.tgname, t.tgenabled FROM pg_trigger t JOIN pg_class c ON c.oid = t.tgrelid "
        "JOIN pg_namespace n ON n.oid = c.relnamespace WHERE n.nspname = current_schema() AND NOT t.tgisinternal"
    ))
    have = {name: str(enabled) for name, enabled in rows}
    for name in expected_pg_triggers():
        if name not in have:
            problems.append(f"immutability guard {name} is missing (the trigger was dropped)")
        elif have[name] != "A":
            problems.append(f"immutability guard {name} is not enabled ALWAYS (state {have[name]!r})")
    schema = conn.execute(text("SELECT current_schema()")).scalar()
    names = event_trigger_names(schema)
    found = {r[0]: r[1] for r in conn.execute(
        text("SELECT evtname, evtenabled FROM pg_event_trigger WHERE evtname IN (:a, :b)"), {"a": names[0], "b": names[1]})}
    if not found:
        notes.append("no DDL event triggers (the schema was not migrated by a superuser): the table owner can "
                     "drop or disable the guards; db check reports it when that happens")
    elif len(found) < 2 or any(str(v) == "D" for v in found.values()):
        problems.append(f"DDL guard event triggers {', '.join(names)} are incomplete or disabled")
    return problems, notes
