"""The service signs checkpoints of the history chain (`serve --checkpoint-key`) and serves the latest
at GET /api/v1/checkpoint; a client saves it and verifies the history against it with
`jointdb db check --checkpoint FILE --trust KEY.pub` (issue 20, item 3). No such route on today's code."""

from __future__ import annotations

import subprocess
import sys

import pytest

pytest.importorskip("fastapi", reason="the server extra is not installed")

from server_helpers import make_tokens, spring_joint, start_server, stop_server  # noqa: E402


def _cli(*args):
    out = subprocess.run([sys.executable, "-m", "jointdb", *map(str, args)], capture_output=True, text=True,
                         timeout=120)
    return out.returncode, out.stdout, out.stderr


def test_served_checkpoint_verifies_and_catches_a_deleted_audit_row(tmp_path):
    import sqlalchemy as sa

    from jointdb.store import Conditions, Repository, upgrade

    db, blobs = f"sqlite:///{tmp_path / 'j.sqlite'}", tmp_path / "blobs"
    upgrade(db)
    tokens = make_tokens(db, blobs)
    with Repository(db, blobs=blobs) as repo:
        repo.catalogue("T1", "tool-holder", spring_joint(), Conditions(materials=("steel",), torque_nm=40.0),
                       "spring-damper-planar")
        repo.deprecate("T1", 1, reason="loose nut")
    assert _cli("keys", "create", tmp_path / "svc")[0] == 0
    srv = start_server(db, blobs, tmp_path / "server.log", "--checkpoint-key", str(tmp_path / "svc"))
    srv.tokens = tokens
    try:
        with srv.client("reader") as c:
            r = c.get("/api/v1/checkpoint")
            assert r.status_code == 200, r.text
            assert c.get("/api/v1/checkpoint").json() == r.json()  # the latest, not re-signed every request
        with srv.client() as c:
            assert c.get("/api/v1/checkpoint").status_code == 401
    finally:
        stop_server(srv)
    (tmp_path / "cp.json").write_text(r.text)
    assert r.json()["tree_size"] >= 6  # joint, version, state, and the audit rows (tokens, catalogue, deprecate)
    args = ("db", "check", "--db", db, "--blobs", blobs, "--checkpoint", tmp_path / "cp.json", "--trust",
            tmp_path / "svc.pub")
    rc, _, err = _cli(*args)
    assert rc == 0, err
    engine = sa.create_engine(db)
    with engine.begin() as conn:  # whoever can write the file: drop the guard, delete, put it back
        create = conn.exec_driver_sql("SELECT sql FROM sqlite_master WHERE name = 'audit_log_no_delete'").scalar()
        conn.exec_driver_sql("DROP TRIGGER audit_log_no_delete")
        conn.exec_driver_sql("DELETE FROM audit_log WHERE action = 'deprecate'")
        conn.exec_driver_sql(create)
    engine.dispose()
    rc, _, err = _cli(*args)
    assert rc == 5 and "the row is missing" in err, err


def test_without_a_key_the_checkpoint_route_says_how(tmp_path):
    from jointdb.store import upgrade

    db, blobs = f"sqlite:///{tmp_path / 'j.sqlite'}", tmp_path / "blobs"
    upgrade(db)
    tokens = make_tokens(db, blobs)
    srv = start_server(db, blobs, tmp_path / "server.log")
    srv.tokens = tokens
    try:
        with srv.client("reader") as c:
            r = c.get("/api/v1/checkpoint")
        assert r.status_code == 404 and "--checkpoint-key" in r.text
    finally:
        stop_server(srv)
