"""The service's hot read path (issue 26, item 4): a pinned version is read in one statement, the
routes encode what they built without a second validation pass, a pooled PostgreSQL connection is
pinged only after sitting idle. Every answer must be the one the general path gives: the same
bytes, a deprecation or a new label visible at once, the same errors."""

from __future__ import annotations

import dataclasses

import httpx
import pytest
from server_helpers import _load, _STORE, migrated_database, spring_joint

from jointdb.server import create_app
from jointdb.server._settings import Settings
from jointdb.store import Repository

alter_version_row = _load("jointdb_store_helpers", _STORE / "store_helpers.py").alter_version_row

NAMES = ("H-1", "H-2")


@pytest.fixture(scope="module", params=["sqlite", "postgresql"])
def repo(request, tmp_path_factory):
    """Two joints of three versions each; one label, one deprecated version."""
    tmp = tmp_path_factory.mktemp(f"hot-{request.param}")
    with migrated_database(request.param, tmp) as db:
        r = Repository(db, blobs=tmp / "blobs", auto_create=False)
        for name in NAMES:
            for i in range(3):
                r.catalogue(name, "tool-holder", spring_joint(k=(2e6 + 1e5 * i, 8e4)),
                            {"materials": ["steel", "steel"], "torque_nm": 20.0 + i}, "spring-damper-planar",
                            author="hot", force=True)
        r.label("H-1", 2, "released")
        r.deprecate("H-2", 3, reason="bad fixture")
        yield r
        r.close()


def general_path(repo, monkeypatch) -> None:
    """Make :meth:`Repository.get` skip the one-statement read (the path every other read takes)."""
    monkeypatch.setattr(type(repo), "_pinned", lambda self, name, version: None)


def app_get(repo, *paths: str) -> list[httpx.Response]:
    app = create_app(Settings(open_reads=True, cache_dir=""), repo=repo)
    transport = httpx.ASGITransport(app=app)

    async def run():
        async with httpx.AsyncClient(transport=transport, base_url="http://t") as c:
            return [await c.get(p) for p in paths]

    import asyncio

    return asyncio.run(run())


PATHS = [f"/api/v1/joints/{n}/versions/{v}" for n in NAMES for v in (1, 2, 3)] + [
    "/api/v1/joints/H-1/versions/4", "/api/v1/joints/nobody/versions/1", "/api/v1/joints/H-1",
    "/api/v1/joints/H-2/versions/3/frf?format=json", "/api/v1/joints/H-1/versions/2/frf?format=csv"]


def test_pinned_read_equals_the_general_path(repo, monkeypatch):
    fast = [repo.get(n, v) for n in NAMES for v in (1, 2, 3)]
    assert [v.state for v in fast] == ["active"] * 5 + ["deprecated"] and fast[1].labels == ("released",)
    general_path(repo, monkeypatch)
    assert fast == [repo.get(n, v) for n in NAMES for v in (1, 2, 3)]


def test_http_answers_are_byte_equal_to_the_general_path(repo, monkeypatch):
    fast = app_get(repo, *PATHS)
    assert [r.status_code for r in fast] == [200] * 6 + [404, 404, 200, 200, 200]
    general_path(repo, monkeypatch)
    slow = app_get(repo, *PATHS)
    for path, a, b in zip(PATHS, fast, slow):
        assert (a.status_code, a.content) == (b.status_code, b.content.replace(b.headers["x-request-id"].encode(),
                                                                                a.headers["x-request-id"].encode())), path


def test_a_deprecation_and_a_label_are_visible_at_once(repo):
    path = "/api/v1/joints/H-1/versions/1"
    (before,) = app_get(repo, path)
    assert before.json()["state"] == "active" and before.json()["labels"] == []
    repo.label("H-1", 1, "tested")
    repo.deprecate("H-1", 1, reason="superseded")
    (after,) = app_get(repo, path)
    assert after.json()["state"] == "deprecated" and after.json()["labels"] == ["tested"]
    repo.deprecate("H-1", 1, undo=True)
    repo.deprecate("H-1", None, reason="whole joint")  # a state row for the whole joint counts too
    assert [r.json()["state"] for r in app_get(repo, path, "/api/v1/joints/H-1/versions/3")] == ["deprecated"] * 2
    repo.deprecate("H-1", None, undo=True)
    assert repo.get("H-1", 1).state == "active"
    assert dataclasses.replace(repo.get("H-1", 1), labels=()) == dataclasses.replace(
        repo.get("H-1", 1, at="2999-01-01T00:00:00Z"), labels=())  # the general path with a time


def test_a_damaged_row_is_refused_as_by_the_general_path(repo, monkeypatch, caplog):
    alter_version_row(repo.url, "UPDATE joint_versions SET torque_nm = 99.0 WHERE version = 1 AND joint_id = "
                                "(SELECT id FROM joints WHERE name = 'H-2')")
    fast = app_get(repo, "/api/v1/joints/H-2/versions/1")[0]
    general_path(repo, monkeypatch)
    slow = app_get(repo, "/api/v1/joints/H-2/versions/1")[0]
    assert fast.status_code == slow.status_code == 500  # damaged data: the text goes to the log only
    assert fast.json()["error"].replace(fast.json()["request_id"], "") == slow.json()["error"].replace(
        slow.json()["request_id"], "")
    assert "record hash" in caplog.text and "H-2 v1" in caplog.text


def test_a_dropped_connection_is_replaced_after_idle(tmp_path, monkeypatch):
    """The pool pings a connection that sat idle (here: any idle time) and replaces a dead one."""
    from jointdb.store import _db

    with migrated_database("postgresql", tmp_path) as db:
        monkeypatch.setattr(_db, "PING_AFTER_S", 0.0)
        r = Repository(db, blobs=tmp_path / "blobs", auto_create=False, pool_size=1)
        try:
            r.catalogue("P-1", "tool-holder", spring_joint(), {"torque_nm": 5.0}, "spring-damper-planar", author="t")
            with r.read_engine.connect() as conn:
                pid = conn.exec_driver_sql("SELECT pg_backend_pid()").scalar()
            import sqlalchemy as sa

            other = sa.create_engine(db)
            with other.begin() as conn:
                assert conn.exec_driver_sql(f"SELECT pg_terminate_backend({int(pid)})").scalar()
            other.dispose()
            assert r.get("P-1", 1).version == 1  # no error: the dead connection was pinged and replaced
            with r.read_engine.connect() as conn:
                assert conn.exec_driver_sql("SELECT pg_backend_pid()").scalar() != pid
        finally:
            r.close()


def test_the_control_character_check_is_unicode_category_cc():
    """The guard's one regex against Unicode's own definition, over every code point."""
    import sys
    import unicodedata

    from jointdb.server._safety import _has_control

    assert [c for c in range(sys.maxunicode + 1) if _has_control(chr(c))] == [
        c for c in range(sys.maxunicode + 1) if unicodedata.category(chr(c)) == "Cc"]
    assert _has_control("name\x00") and not _has_control("Ärger-ß/versions/3")


def test_http_0_9_is_refused_before_the_app():
    """httptools (uvicorn's C parser) parses HTTP/0.9, which h11 refused: the middleware answers 400."""
    import asyncio

    from jointdb.server._middleware import ServiceMiddleware

    reached, sent = [], []

    async def app(scope, receive, send):
        reached.append(scope["http_version"])

    async def receive():
        return {"type": "http.request", "body": b"", "more_body": False}

    async def send(message):
        sent.append(message)

    mw = ServiceMiddleware(app, max_upload_bytes=100, request_timeout_s=5)
    for version in ("0.9", "1.0", "1.1"):
        asyncio.run(mw({"type": "http", "http_version": version, "method": "GET", "path": "/", "headers": []},
                       receive, send))
    assert reached == ["1.0", "1.1"] and sent[0]["status"] == 400
