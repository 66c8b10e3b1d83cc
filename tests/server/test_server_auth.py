"""Tokens and roles against a running server: no write without a writer token, admin
routes need admin, revoked/expired tokens refused, the audit log names the owner, and no
token ever appears in the server log or in an error message."""

from __future__ import annotations

import json

import pytest

from server_helpers import joint_upload


def _writes(tmp_path, name="AUTH-1"):
    """Every write route with a valid body: (method, path, json)."""
    return [
        ("POST", "/api/v1/catalogue", joint_upload(tmp_path, name)),
        ("POST", f"/api/v1/joints/{name}/labels", {"version": 1, "label": "released"}),
        ("POST", f"/api/v1/joints/{name}/deprecate", {"reason": "test"}),
    ]


ADMIN = [
    ("GET", "/api/v1/admin/tokens", None),
    ("POST", "/api/v1/admin/tokens", {"name": "mallory", "role": "admin"}),
    ("DELETE", "/api/v1/admin/tokens/0123456789ab", None),
    ("POST", "/api/v1/admin/gc", {"dry_run": True}),
    ("GET", "/api/v1/admin/check", None),
    ("GET", "/api/v1/admin/migrations", None),
    ("POST", "/api/v1/admin/migrations/upgrade", None),
]


def _call(client, method, path, body):
    return client.request(method, path, json=body) if body is not None else client.request(method, path)


def test_no_write_without_a_writer_token(server, tmp_path):
    before = server.repo().audit(limit=1000)
    for who in (None, "reader", "revoked", "expired"):
        with server.client(who) as c:
            for method, path, body in _writes(tmp_path):
                r = _call(c, method, path, body)
                expected = 403 if who == "reader" else 401
                assert r.status_code == expected, (who, path, r.status_code, r.text)
                assert "error" in r.json() and "\n" not in r.json()["error"]
    with server.client(token="jdb_0123456789ab_" + "A" * 43) as c:  # well-formed, unknown
        assert _call(c, *_writes(tmp_path)[0]).status_code == 401
    with server.client(token="not a token at all") as c:
        assert _call(c, *_writes(tmp_path)[0]).status_code == 401
    assert server.repo().audit(limit=1000) == before  # nothing was written
    with pytest.raises(Exception):
        server.repo().get("AUTH-1")


def test_admin_routes_need_admin(server):
    for who, expected in ((None, 401), ("reader", 403), ("writer", 403), ("revoked", 401), ("expired", 401)):
        with server.client(who) as c:
            for method, path, body in ADMIN:
                r = _call(c, method, path, body)
                assert r.status_code == expected, (who, path, r.status_code, r.text)
    with server.client("admin") as c:
        assert c.get("/api/v1/admin/migrations").json()["revision"] == c.get("/api/v1/admin/migrations").json()["head"]
        assert c.get("/api/v1/admin/check").json()["ok"] is True


def test_reads_are_token_only_by_default(server):
    with server.client() as c:
        for path in ("/api/v1/joints", "/api/v1/audit", "/api/v1/joints/X/history"):
            assert c.get(path).status_code == 401
        assert c.post("/api/v1/query/nearest", json={"joint_type": "tool-holder"}).status_code == 401
        assert c.get("/healthz").status_code == 200  # health needs no token
    with server.client("reader") as c:
        assert c.get("/api/v1/joints").status_code == 200


def test_writes_are_audited_under_the_token_owner(server, tmp_path):
    with server.client("writer") as c:
        r = c.post("/api/v1/catalogue", json=joint_upload(tmp_path, "OWNED-1", author="someone-else"))
        assert r.status_code == 422  # 'author' is not a field: the owner cannot be chosen by the body
        r = c.post("/api/v1/catalogue", json=joint_upload(tmp_path, "OWNED-1"))
        assert r.status_code == 201, r.text
        assert r.json()["provenance"]["author"] == "writer-owner"
        assert c.post("/api/v1/joints/OWNED-1/labels", json={"version": 1, "label": "released"}).status_code == 200
        assert c.post("/api/v1/joints/OWNED-1/deprecate", json={"reason": "worn"}).status_code == 200
    entries = server.repo().audit("OWNED-1")
    assert [e["action"] for e in entries] == ["deprecate", "label", "catalogue"]
    assert {e["actor"] for e in entries} == {"writer-owner"}
    with server.client("reader") as c:
        items = c.get("/api/v1/audit", params={"joint": "OWNED-1"}).json()["items"]
    assert [e["actor"] for e in items] == ["writer-owner"] * 3


def test_token_management_over_http(server):
    with server.client("admin") as c:
        r = c.post("/api/v1/admin/tokens", json={"name": "carol", "role": "reader", "expires": "1d"})
        assert r.status_code == 201
        token, tid = r.json()["token"], r.json()["token_id"]
        listed = c.get("/api/v1/admin/tokens").json()["items"]
        assert tid in {t["token_id"] for t in listed} and token not in json.dumps(listed)
        with server.client(token=token) as carol:
            assert carol.get("/api/v1/joints").status_code == 200
            assert c.delete(f"/api/v1/admin/tokens/{tid}").json()["status"] == "revoked"
            assert carol.get("/api/v1/joints").status_code == 401  # refused at once
    audit = server.repo().audit(limit=50)
    assert any(e["action"] == "token-revoke" and e["actor"] == "admin-owner" for e in audit)


def test_tokens_never_in_logs_or_errors(server, tmp_path):
    seen = []
    for who in ("reader", "writer", "admin", "revoked", "expired"):
        with server.client(who) as c:
            for method, path, body in _writes(tmp_path, "LOG-1") + ADMIN + [("GET", "/api/v1/joints/nope", None)]:
                seen.append(_call(c, method, path, body).text)
    with server.client(token=server.tokens["writer"] + "x") as c:
        seen.append(c.get("/api/v1/joints").text)
    text = server.log_text()
    assert '"path": "/api/v1/joints/nope"' in text  # the log is written
    for token in server.tokens.values():
        assert token not in text
        assert token[16:] not in text  # not even the secret part
        for body in seen:
            assert token not in body and token[16:] not in body
    with server.repo() as repo:
        stored = json.dumps(repo.audit(limit=1000))
    assert all(t[16:] not in stored for t in server.tokens.values())
