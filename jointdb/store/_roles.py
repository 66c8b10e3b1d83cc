"""Least privilege on PostgreSQL: an owner role migrates, an application role only appends.

The owner (the role that runs ``jointdb db upgrade``) owns every table, so it can disable
triggers and rewrite history; the service must not run as it. ``jointdb db upgrade
--app-role NAME`` (run as the owner) gives the application role exactly what the write
paths need (:data:`APP_PRIVILEGES`): SELECT and INSERT on the history tables, and the
updates and deletes of the mutable ones (labels move, the derived query index is rewritten,
tokens are revoked, unreferenced blobs are collected). Every other table gets SELECT only,
and default privileges give tables and sequences of later migrations SELECT/USAGE, so
re-running ``db upgrade --app-role NAME`` after an upgrade adds only what is listed here.

``UPDATE (id)`` on ``joints`` exists only because ``SELECT ... FOR UPDATE`` (the catalogue
locks a joint's row) needs some UPDATE privilege; the trigger ``joints_immutable``, enabled
ALWAYS and out of the application role's reach (only the owner may alter the table), refuses
every UPDATE.
"""

from __future__ import annotations

import re

from sqlalchemy import text

from jointdb.errors import InputError

HISTORY_TABLES = ("joints", "joint_versions", "joint_states", "audit_log", "history_chain", "parts",
                  "part_versions")
#: table -> privileges of the application role (every other table of the schema: SELECT)
APP_PRIVILEGES = {
    **{t: "SELECT, INSERT" for t in HISTORY_TABLES},
    "joints": "SELECT, INSERT, UPDATE (id)",
    "labels": "SELECT, INSERT, UPDATE (version, updated_at, updated_by)",
    "parts": "SELECT, INSERT, UPDATE (id)",  # SELECT ... FOR UPDATE locks a part's row (the trigger refuses UPDATE)
    "part_labels": "SELECT, INSERT, UPDATE (version, updated_at, updated_by)",
    "query_versions": "SELECT, INSERT, UPDATE, DELETE",
    "query_geometry": "SELECT, INSERT, UPDATE, DELETE",
    "query_stamp": "SELECT, INSERT, UPDATE",
    "query_counts": "SELECT, INSERT, UPDATE, DELETE",  # the listing's totals (migration 0010)
    "query_changes": "SELECT, INSERT, DELETE",  # the query index's change log (migration 0011), pruned
    "api_tokens": "SELECT, INSERT, UPDATE (revoked_at)",
    "frf_blobs": "SELECT, INSERT, UPDATE (touched_at), DELETE",
    "idempotency_keys": "SELECT, INSERT",  # the stored answers to retried catalogue requests
    "web_sessions": "SELECT, INSERT, UPDATE, DELETE",  # sign-ins: opened, seen, revoked, expired ones removed
    "alembic_version": "SELECT",
}
_NAME = re.compile(r"[a-z_][a-z0-9_]{0,62}")

SETUP_HINT = ("run migrations as an owner role and the service as an application role: "
              "`jointdb db upgrade --db OWNER_URL --app-role jointdb_app --create-role`, then "
              "`jointdb serve --db APP_URL` (docs/service.md, Deployment)")


def check_role_name(name: str) -> str:
    if not _NAME.fullmatch(name or ""):
        raise InputError(f"--app-role must be a lower-case PostgreSQL role name (letters, digits, _), got {name!r}")
    return name


def grant_app_role(conn, role: str, create: bool = False) -> list[str]:
    """Give ``role`` the application privileges on the current schema (run as the owner).

    Returns the tables granted. ``create``: make the role (LOGIN, no other attribute) when
    it does not exist; its password is set by the administrator (``ALTER ROLE ... PASSWORD``).

    Raises
    ------
    InputError
        SQLite, an unusable role name, a missing role without ``create``, or a role that is
        the owner itself or a superuser.
    """
    if conn.dialect.name != "postgresql":
        raise InputError("--app-role is for PostgreSQL; a SQLite file has no roles (see docs/service.md, "
                         "threat model)")
    role = check_role_name(role)
    me, schema = conn.execute(text("SELECT current_user, current_schema()")).first()
    if role == me:
        raise InputError(f"--app-role {role} is the role running the migration (the owner); name another role")
    found = conn.execute(text("SELECT rolsuper FROM pg_roles WHERE rolname = :r"), {"r": role}).first()
    if found is None:
        if not create:
            raise InputError(f"role {role} does not exist; add --create-role (or CREATE ROLE {role} LOGIN)")
        conn.exec_driver_sql(f'CREATE ROLE "{role}" LOGIN NOSUPERUSER NOCREATEDB NOCREATEROLE NOINHERIT')
    elif found[0]:
        raise InputError(f"role {role} is a superuser; the application role must be an ordinary role")
    tables = [r[0] for r in conn.execute(text(
        "SELECT c.relname FROM pg_class c JOIN pg_namespace n ON n.oid = c.relnamespace "
        "WHERE n.nspname = current_schema() AND c.relkind IN ('r', 'p') ORDER BY c.relname"))]
    q_schema = '"' + schema.replace('"', '""') + '"'
    conn.exec_driver_sql(f'GRANT USAGE ON SCHEMA {q_schema} TO "{role}"')
    conn.exec_driver_sql(f'REVOKE ALL ON ALL TABLES IN SCHEMA {q_schema} FROM "{role}"')
    for table in tables:
        conn.exec_driver_sql(f'GRANT {APP_PRIVILEGES.get(table, "SELECT")} ON {q_schema}."{table}" TO "{role}"')
    conn.exec_driver_sql(f'GRANT USAGE, SELECT ON ALL SEQUENCES IN SCHEMA {q_schema} TO "{role}"')
    conn.exec_driver_sql(f'ALTER DEFAULT PRIVILEGES IN SCHEMA {q_schema} GRANT SELECT ON TABLES TO "{role}"')
    conn.exec_driver_sql(f'ALTER DEFAULT PRIVILEGES IN SCHEMA {q_schema} GRANT USAGE, SELECT ON SEQUENCES TO "{role}"')
    return tables


def owner_problem(conn) -> str | None:
    """Why serving over this connection would let the service rewrite history: it is a superuser,
    or the owner (or a member of the owner role) of the history tables. None on SQLite."""
    if conn.dialect.name != "postgresql":
        return None
    row = conn.execute(text(
        "SELECT r.rolsuper, c.relowner IS NOT NULL AND pg_has_role(current_user, c.relowner, 'MEMBER') "
        "FROM pg_roles r LEFT JOIN pg_class c ON c.oid = to_regclass('joint_versions') "
        "WHERE r.rolname = current_user")).first()
    if row is None:
        return None
    if row[0]:
        return "the database role is a superuser"
    if row[1]:
        return "the database role owns the history tables (it could disable their triggers and rewrite them)"
    return None


def refuse_owner(url: str) -> None:
    """Refuse to serve over a PostgreSQL connection that could rewrite history (:func:`owner_problem`).

    Raises
    ------
    InputError
        Connected as a superuser or as the owner of the history tables (with how to set up the
        two roles, and ``--allow-owner``).
    """
    from jointdb.store import _db

    if _db.is_sqlite(url):
        return
    engine, _ = _db.make_engines(url)
    try:
        with _db.db_errors(url), engine.connect() as conn:
            problem = owner_problem(conn)
    finally:
        engine.dispose()
    if problem:
        raise InputError(f"refusing to serve: {problem}; {SETUP_HINT}; or pass --allow-owner to serve anyway")
