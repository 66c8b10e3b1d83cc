"""The same commands against a server (``jointdb --server URL`` / ``JOINTDB_SERVER`` with
``JOINTDB_TOKEN``) and against the database directly give the same answers (the commands run in-process; the
server is a real process)."""

from __future__ import annotations

import json
from types import SimpleNamespace

import pytest

from server_helpers import spring_joint


@pytest.fixture
def _jointdb(run_cli, monkeypatch):
    """``_jointdb(*args, env=..., ok=True)``: the console entry point in this process with ``env`` set for the
    call (the CLI reads ``JOINTDB_SERVER``/``JOINTDB_TOKEN`` when it runs); the result as ``subprocess.run``'s."""

    def call(*args, env=None, ok=True):
        with monkeypatch.context() as m:
            for key, value in {"OPENBLAS_NUM_THREADS": "1", **(env or {})}.items():
                m.setenv(key, value)
            code, out, err = run_cli(*args)
        if ok:
            assert code == 0, err
        return SimpleNamespace(returncode=code, stdout=out, stderr=err)

    return call


def test_cli_over_http_matches_the_database(server, tmp_path, _jointdb):
    from jointdb import io

    path = tmp_path / "joint.h5"
    io.write_frf_hdf5(path, spring_joint(), {"kind": "joint", "joint_model": "planar", "joint_type": "tool-holder",
                                             "conditions": {"materials": ["tungsten-carbide", "steel"]}})
    remote = {"JOINTDB_SERVER": server.url, "JOINTDB_TOKEN": server.tokens["writer"]}
    for torque in (25, 45):
        out = json.loads(_jointdb("catalogue", path, "--name", "CLI-1", "--torque", torque, "--label", "latest", "--force",
                                  "--json", env=remote).stdout)
    assert out["version"] == 2 and out["author"] == "writer-owner"
    out = json.loads(_jointdb("--server", server.url, "catalogue", path, "--name", "CLI-2", "--torque", 60, "--json",
                              env={"JOINTDB_TOKEN": server.tokens["writer"]}).stdout)
    assert out["version"] == 1
    local = ["--db", server.db, "--blobs", server.blobs]
    for cmd in (["joints", "list", "--json"], ["joints", "show", "CLI-1", "--version", "1", "--json"],
                ["joints", "history", "CLI-1", "--json"],
                ["query", "--type", "tool-holder", "--material", "carbide+steel", "--torque", "40", "--json"]):
        via_server = json.loads(_jointdb(*cmd, env=remote).stdout)
        direct = json.loads(_jointdb(*cmd, *local).stdout)
        assert via_server == direct, cmd
    frf_out = tmp_path / "remote.h5"
    _jointdb("joints", "show", "CLI-1", "--frf-out", frf_out, env=remote)
    assert io.read_frf_hdf5(frf_out).allclose(spring_joint(), rtol=0)
    # errors keep their meaning: unknown joint is exit 3, a reader cannot write, no token is refused
    assert _jointdb("joints", "show", "NOPE", env=remote, ok=False).returncode == 3
    r = _jointdb("catalogue", path, "--name", "CLI-3", env={**remote, "JOINTDB_TOKEN": server.tokens["reader"]},
                 ok=False)
    assert r.returncode == 2 and "writer" in r.stderr and server.tokens["reader"] not in r.stderr
    r = _jointdb("joints", "list", env={"JOINTDB_SERVER": server.url, "JOINTDB_TOKEN": ""}, ok=False)
    assert r.returncode == 2 and "token" in r.stderr and len(r.stderr.strip().splitlines()) == 1


def test_tokens_commands(tmp_path, _jointdb):
    db = tmp_path / "t.sqlite"
    _jointdb("db", "upgrade", "--db", db)
    created = json.loads(_jointdb("tokens", "create", "--name", "alice", "--role", "writer", "--expires", "30d",
                                  "--json", "--db", db).stdout)
    token, tid = created["token"], created["token_id"]
    assert token.startswith(f"jdb_{tid}_") and created["status"] == "active" and created["expires_at"]
    listed = _jointdb("tokens", "list", "--json", "--db", db).stdout
    stored = b"".join(p.read_bytes() for p in tmp_path.glob("t.sqlite*"))  # with the WAL
    assert tid in listed and token not in listed and token[16:].encode() not in stored
    assert json.loads(_jointdb("tokens", "revoke", tid, "--json", "--db", db).stdout)["status"] == "revoked"
    assert json.loads(_jointdb("tokens", "list", "--json", "--db", db).stdout)[0]["status"] == "revoked"
    for args, code, text in ((["create", "--name", "bob", "--role", "root"], 2, "role"),
                             (["create", "--name", "bob", "--role", "reader", "--expires", "2000-01-01"], 2, "past"),
                             (["create", "--name", "b/ob", "--role", "reader"], 2, "owner"),
                             (["revoke", "0123456789ab"], 3, "no token"),
                             (["revoke", "zz"], 2, "12 hex")):
        r = _jointdb("tokens", *args, "--db", db, ok=False)
        assert r.returncode == code and text in r.stderr and len(r.stderr.strip().splitlines()) == 1, r.stderr
