"""History guards in the database itself: every statement that could rewrite history is refused.

SQLite: REPLACE / INSERT OR REPLACE / UPSERT over history rows (REPLACE deletes
without firing DELETE triggers), besides UPDATE and DELETE. PostgreSQL: TRUNCATE,
UPSERT, and (superuser-installed event triggers) DROP/ALTER of the guards,
DROP TABLE, DROP SCHEMA, and replica mode. Each statement is tried on its own
connection; afterwards the rows are exactly as before and ``check`` is clean.
"""

from __future__ import annotations

import uuid

import pytest
import sqlalchemy as sa
from store_helpers import count_rows, planar_conditions, spring_joint

HISTORY = ("joints", "joint_versions", "joint_states", "audit_log")


def _populate(repo):
    repo.catalogue("T1", "tool-holder", spring_joint(), planar_conditions(torque=40.0), "spring-damper-planar")
    repo.catalogue("T1", "tool-holder", spring_joint(k=(3e6, 8e4)), planar_conditions(torque=50.0),
                   "spring-damper-planar", force=True)
    repo.label("T1", 1, "released")
    repo.deprecate("T1", 1, reason="loose nut")


def _snapshot(url) -> dict[str, list]:
    engine = sa.create_engine(url)
    try:
        with engine.connect() as conn:
            return {t: [tuple(map(str, r)) for r in conn.execute(sa.text(f"SELECT * FROM {t} ORDER BY id"))]
                    for t in HISTORY + ("labels",)}
    finally:
        engine.dispose()


def _columns(conn, table):
    return [c["name"] for c in sa.inspect(conn).get_columns(table)]


def _replace_select(conn, table, column, value):
    cols = _columns(conn, table)
    sel = ", ".join(value if c == column else c for c in cols)
    return ", ".join(cols), sel


def _sqlite_statements(conn):
    out = []
    for table, column, value in (("joint_versions", "torque_nm", "999"), ("audit_log", "actor", "'mallory'"),
                                 ("joint_states", "state", "'active'"), ("joints", "created_by", "'mallory'")):
        cols, sel = _replace_select(conn, table, column, value)
        out += [
            f"INSERT OR REPLACE INTO {table} ({cols}) SELECT {sel} FROM {table}",
            f"REPLACE INTO {table} ({cols}) SELECT {sel} FROM {table}",
            f"INSERT INTO {table} ({cols}) SELECT {sel} FROM {table} WHERE true "
            f"ON CONFLICT(id) DO UPDATE SET {column} = excluded.{column}",
            f"UPDATE {table} SET {column} = {value}",
            f"DELETE FROM {table}",
        ]
    cols, sel = _replace_select(conn, "joint_versions", "id", "id + 1000")  # same (joint, version), new id
    out.append(f"INSERT OR REPLACE INTO joint_versions ({cols}) SELECT {sel} FROM joint_versions")
    return out


def _pg_statements(conn, schema):
    cols, sel = _replace_select(conn, "joint_versions", "torque_nm", "999")
    out = [f"TRUNCATE {t}" for t in ("joint_states", "audit_log", "labels")]  # the others: FK first
    out += [f"TRUNCATE {t} CASCADE" for t in ("joints", "joint_versions", "audit_log")]
    out += [
        f"INSERT INTO joint_versions ({cols}) SELECT {sel} FROM joint_versions "
        "ON CONFLICT (id) DO UPDATE SET torque_nm = 999",
        "UPDATE joint_versions SET torque_nm = 999",
        "DELETE FROM audit_log",
        "SET LOCAL session_replication_role = replica; DELETE FROM audit_log",
        "SET LOCAL session_replication_role = replica; TRUNCATE joint_states",
    ]
    return out


def _pg_ddl_statements(schema):
    return [
        "DROP TRIGGER joint_versions_immutable ON joint_versions",
        "DROP TRIGGER audit_log_no_truncate ON audit_log",
        "ALTER TABLE audit_log DISABLE TRIGGER audit_log_immutable",
        "ALTER TABLE joint_versions DISABLE TRIGGER ALL",
        "ALTER TABLE joint_states ENABLE TRIGGER joint_states_immutable",  # ALWAYS -> origin only
        "DROP FUNCTION jointdb_refuse_change() CASCADE",
        "DROP FUNCTION jointdb_refuse_truncate() CASCADE",
        "DROP TABLE audit_log",
        "DROP TABLE labels",
        f"DROP SCHEMA {schema} CASCADE",
    ]


def _superuser(conn) -> bool:
    return conn.exec_driver_sql("SELECT current_setting('is_superuser')").scalar() == "on"


def test_every_history_rewrite_is_refused_by_the_database(backend):
    repo = backend.repo()
    _populate(repo)
    before, rows_before = _snapshot(backend.url), count_rows(repo)
    engine = sa.create_engine(backend.url)
    with engine.connect() as conn:
        if backend.name == "sqlite":
            statements = _sqlite_statements(conn)
        else:
            schema = conn.exec_driver_sql("SELECT current_schema()").scalar()
            statements = _pg_statements(conn, schema)
            if _superuser(conn):
                statements += _pg_ddl_statements(schema)
    accepted = []
    for statement in statements:
        try:
            with engine.begin() as conn:
                for part in statement.split("; "):
                    conn.exec_driver_sql(part)
            accepted.append(statement)
        except sa.exc.DBAPIError as exc:
            assert "jointdb:" in str(exc.orig), (statement, str(exc.orig))
    engine.dispose()
    assert accepted == []
    assert _snapshot(backend.url) == before and count_rows(repo) == rows_before
    report = repo.check()
    assert report.ok, report.problems
    assert len(statements) >= (21 if backend.name == "sqlite" else 12)
    repo.close()


def test_db_check_reports_a_guard_that_was_dropped(backend, tmp_path):
    repo = backend.repo()
    _populate(repo)
    engine = sa.create_engine(backend.url)
    with engine.begin() as conn:
        if backend.name == "sqlite":  # nothing can stop whoever writes the file: check must see it
            conn.exec_driver_sql("DROP TRIGGER joint_versions_no_replace")
            conn.exec_driver_sql("DROP TRIGGER audit_log_no_delete")
            conn.exec_driver_sql("CREATE TRIGGER audit_log_no_delete BEFORE DELETE ON audit_log BEGIN SELECT 1; END")
        else:
            schema = conn.exec_driver_sql("SELECT current_schema()").scalar()
            from jointdb.store._guards import event_trigger_names

            for name in event_trigger_names(schema):  # what only a superuser can do
                conn.exec_driver_sql(f'DROP EVENT TRIGGER IF EXISTS "{name}"')
            conn.exec_driver_sql("ALTER TABLE audit_log DISABLE TRIGGER audit_log_immutable")
            conn.exec_driver_sql("DROP TRIGGER joint_versions_no_truncate ON joint_versions")
    engine.dispose()
    report = repo.check()
    assert not report.ok
    text = " | ".join(report.problems)
    if backend.name == "sqlite":
        assert "joint_versions_no_replace is missing" in text and "audit_log_no_delete no longer refuses" in text
    else:
        assert "audit_log_immutable is not enabled ALWAYS" in text and "joint_versions_no_truncate is missing" in text
        assert any("no DDL event triggers" in n for n in report.notes)
    repo.close()


def test_postgres_without_superuser_has_row_guards_and_check_tells_the_limit(empty_backend, tmp_path):
    """A non-superuser owner gets every row/TRUNCATE guard; it can drop them (PostgreSQL allows the
    owner to), so `db check` is what notices, and says why."""
    if empty_backend.name != "postgresql":
        pytest.skip("PostgreSQL roles")
    from conftest import pg_base_url

    from jointdb.store import Repository, upgrade

    base = pg_base_url()
    admin = sa.create_engine(base)
    with admin.connect() as conn:
        if not _superuser(conn):
            pytest.skip("creating a role needs a superuser")
    role, schema = "jt_role_" + uuid.uuid4().hex[:8], "jt_own_" + uuid.uuid4().hex[:8]
    with admin.begin() as conn:
        conn.exec_driver_sql(f"CREATE ROLE {role} LOGIN")
        conn.exec_driver_sql(f"CREATE SCHEMA {schema} AUTHORIZATION {role}")
    url = sa.engine.make_url(base).set(username=role, password=None)
    url = url.render_as_string(hide_password=False) + f"?options=-csearch_path%3D{schema}"
    try:
        upgrade(url)
        repo = Repository(url, blobs=tmp_path / "b")
        _populate(repo)
        report = repo.check()
        assert report.ok and any("no DDL event triggers" in n for n in report.notes)
        engine = sa.create_engine(url)
        with pytest.raises(sa.exc.DBAPIError, match="jointdb: TRUNCATE"):
            with engine.begin() as conn:
                conn.exec_driver_sql("TRUNCATE audit_log")
        with engine.begin() as conn:  # the owner may drop a trigger: the documented limit
            conn.exec_driver_sql("DROP TRIGGER audit_log_no_truncate ON audit_log")
        engine.dispose()
        report = repo.check()
        assert not report.ok and "audit_log_no_truncate is missing" in " ".join(report.problems)
        repo.close()
    finally:
        with admin.begin() as conn:
            conn.exec_driver_sql(f"DROP SCHEMA {schema} CASCADE")
            conn.exec_driver_sql(f"DROP ROLE {role}")
        admin.dispose()
