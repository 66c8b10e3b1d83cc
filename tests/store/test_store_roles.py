"""Least privilege (issue 20, item 2): the documented two-role PostgreSQL deployment. An owner role
migrates (`db upgrade --app-role NAME`); the application role can append history but cannot UPDATE,
DELETE, ALTER, DISABLE TRIGGER or TRUNCATE any history table; `serve` refuses to run as the owner
or a superuser. On today's code there is no --app-role and serve starts as anyone."""

from __future__ import annotations

import subprocess
import sys
import uuid

import pytest
import sqlalchemy as sa
from store_helpers import planar_conditions, refused_statements, run_cli, spring_joint

HISTORY = ("joints", "joint_versions", "joint_states", "audit_log", "history_chain")


def _url(base: str, role: str, schema: str) -> str:
    url = sa.engine.make_url(base).set(username=role, password=None)
    return url.render_as_string(hide_password=False) + f"?options=-csearch_path%3D{schema}"


@pytest.fixture
def two_roles(tmp_path):
    """A schema owned by a fresh owner role, migrated by it with a fresh application role."""
    from conftest import pg_base_url

    base = pg_base_url()
    admin = sa.create_engine(base)
    with admin.connect() as conn:
        if conn.exec_driver_sql("SELECT current_setting('is_superuser')").scalar() != "on":
            pytest.skip("creating roles needs a superuser")
    tag = uuid.uuid4().hex[:10]
    owner, app, schema = f"jt_owner_{tag}", f"jt_app_{tag}", f"jt_roles_{tag}"
    with admin.begin() as conn:
        conn.exec_driver_sql(f"CREATE ROLE {owner} LOGIN")
        conn.exec_driver_sql(f"CREATE ROLE {app} LOGIN")
        conn.exec_driver_sql(f"CREATE SCHEMA {schema} AUTHORIZATION {owner}")
    try:
        owner_url, app_url = _url(base, owner, schema), _url(base, app, schema)
        blobs = tmp_path / "blobs"
        rc, out, err = run_cli("db", "upgrade", "--db", owner_url, "--app-role", app)
        assert rc == 0, err
        yield type("Roles", (), {"owner_url": owner_url, "app_url": app_url, "app": app, "blobs": blobs,
                                 "super_url": _url(base, sa.engine.make_url(base).username, schema)})
    finally:
        with admin.begin() as conn:
            conn.exec_driver_sql(f"DROP OWNED BY {app}, {owner} CASCADE")
            conn.exec_driver_sql(f"DROP SCHEMA IF EXISTS {schema} CASCADE")
            conn.exec_driver_sql(f"DROP ROLE {app}")
            conn.exec_driver_sql(f"DROP ROLE {owner}")
        admin.dispose()


def test_the_app_role_writes_but_cannot_rewrite_history(two_roles):
    from jointdb.store import Repository
    from jointdb.store._tokens import create_token, revoke_token

    repo = Repository(two_roles.app_url, blobs=two_roles.blobs, auto_create=False)
    try:  # every write path works with the minimal privileges
        repo.catalogue("T1", "tool-holder", spring_joint(), planar_conditions(torque=40.0), "spring-damper-planar")
        repo.catalogue("T1", "tool-holder", spring_joint(k=(3e6, 8e4)), planar_conditions(torque=40.0),
                       "spring-damper-planar", label="released")
        repo.label("T1", 1, "released")
        repo.deprecate("T1", 1, reason="loose nut")
        _, info = create_token(repo, "alice", "writer")
        revoke_token(repo, info.token_id)
        assert repo.check(verify_blobs=False).ok
    finally:
        repo.close()
    attacks = []
    for table in HISTORY:
        column = "kind" if table == "history_chain" else "id" if table != "joint_versions" else "torque_nm"
        value = "'x'" if table == "history_chain" else "id" if table != "joint_versions" else "1"
        attacks += [f"UPDATE {table} SET {column} = {value}", f"DELETE FROM {table}", f"TRUNCATE {table}",
                    f"ALTER TABLE {table} DISABLE TRIGGER ALL", f"ALTER TABLE {table} RENAME TO {table}_old",
                    f"ALTER TABLE {table} ADD COLUMN x int", f"DROP TABLE {table}"]
    attacks += ["UPDATE labels SET joint_id = joint_id", "TRUNCATE labels", "DELETE FROM labels"]
    assert refused_statements(two_roles.app_url, attacks) == []


def test_serve_refuses_the_owner_and_a_superuser_but_not_the_app_role(two_roles, tmp_path):
    from jointdb.store._roles import refuse_owner

    for url in (two_roles.owner_url, two_roles.super_url):
        try:
            out = subprocess.run([sys.executable, "-m", "jointdb", "serve", "--db", url, "--blobs",
                                  str(two_roles.blobs), "--port", "1"], capture_output=True, text=True, timeout=60)
        except subprocess.TimeoutExpired:
            pytest.fail("serve did not refuse")
        assert out.returncode == 2 and "refusing to serve" in out.stderr and "--app-role" in out.stderr, out.stderr
        assert "--allow-owner" in out.stderr and "postgresql" not in out.stderr.lower()
    refuse_owner(two_roles.app_url)  # no error: the documented deployment starts


def test_upgrade_with_app_role_on_sqlite_is_one_line(tmp_path):
    rc, _, err = run_cli("db", "upgrade", "--db", tmp_path / "j.sqlite", "--app-role", "jointdb_app")
    assert rc == 2 and "a SQLite file has no roles" in err and len(err.strip().splitlines()) == 1, err
