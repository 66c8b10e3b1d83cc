"""A running ``jointdb serve`` (uvicorn in a subprocess on a free local port) on SQLite and,
when ``JOINTDB_TEST_PG_URL`` is set, PostgreSQL (a fresh schema), with one token per role."""

from __future__ import annotations

import pytest

pytest.importorskip("fastapi", reason="the server extra (fastapi, uvicorn, httpx) is not installed")
pytest.importorskip("httpx", reason="the server extra (httpx) is not installed")

from server_helpers import make_tokens, migrated_database, start_server, stop_server  # noqa: E402


@pytest.fixture(scope="module", params=["sqlite", "postgresql"])
def server(request, tmp_path_factory):
    """A migrated database with tokens and a running server (one per test module and backend)."""
    tmp = tmp_path_factory.mktemp(f"server-{request.param}")
    with migrated_database(request.param, tmp) as db:
        tokens = make_tokens(db, tmp / "blobs")
        srv = start_server(db, tmp / "blobs", tmp / "server.log")
        srv.tokens = tokens
        yield srv
        stop_server(srv)
