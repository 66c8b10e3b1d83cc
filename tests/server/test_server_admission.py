"""Back-pressure (issue 26, item 4): at most ``concurrency`` requests in the app, at
most ``max_queued`` waiting, 429 with Retry-After beyond; probes never queued; a pool
that stays empty answers 503 with Retry-After, never 500."""

from __future__ import annotations

import asyncio
import json

import pytest

from jointdb.server._middleware import Admission, Busy, ServiceMiddleware


def test_admission_counts_and_refuses_beyond_the_queue():
    async def scenario():
        gate = Admission(concurrency=2, max_queued=1)
        await gate.enter()
        await gate.enter()  # two running
        waiter = asyncio.create_task(gate.enter())  # the third waits
        await asyncio.sleep(0)
        assert (gate.running, gate.waiting) == (2, 1)
        with pytest.raises(Busy):
            await gate.enter()  # the queue is full
        gate.leave()
        await waiter
        assert (gate.running, gate.waiting) == (2, 0)
        gate.leave()
        gate.leave()
        assert gate.running == 0

    asyncio.run(scenario())


def test_a_cancelled_wait_gives_no_turn_away():
    async def scenario():
        gate = Admission(concurrency=1, max_queued=5)
        await gate.enter()
        waiter = asyncio.create_task(gate.enter())
        await asyncio.sleep(0)
        waiter.cancel()
        with pytest.raises(asyncio.CancelledError):
            await waiter
        assert gate.waiting == 0
        gate.leave()
        await asyncio.wait_for(gate.enter(), 1)  # the one turn is free again
        assert gate.running == 1

    asyncio.run(scenario())


def test_admission_rejects_nonsense():
    with pytest.raises(ValueError, match="concurrency"):
        Admission(0, 1)


async def _call(mw, path: str):
    sent = []

    async def receive():
        return {"type": "http.request", "body": b"", "more_body": False}

    async def send(message):
        sent.append(message)

    await mw({"type": "http", "method": "GET", "path": path, "headers": []}, receive, send)
    return sent


def test_middleware_answers_429_with_retry_after_when_full_and_probes_pass():
    async def scenario():
        release = asyncio.Event()

        async def slow_app(scope, receive, send):
            if scope["path"] == "/slow":
                await release.wait()
            await send({"type": "http.response.start", "status": 200, "headers": []})
            await send({"type": "http.response.body", "body": b"ok"})

        mw = ServiceMiddleware(slow_app, max_upload_bytes=1000, request_timeout_s=10, concurrency=1, max_queued=1)
        first = asyncio.create_task(_call(mw, "/slow"))
        second = asyncio.create_task(_call(mw, "/slow"))
        await asyncio.sleep(0.05)
        refused = await _call(mw, "/slow")
        probe = await _call(mw, "/healthz")
        release.set()
        done = await asyncio.gather(first, second)
        return refused, probe, done

    refused, probe, done = asyncio.run(scenario())
    start = refused[0]
    assert start["status"] == 429
    headers = dict(start["headers"])
    assert headers[b"retry-after"] == b"1"
    assert "busy" in json.loads(refused[1]["body"])["error"]
    assert probe[0]["status"] == 200
    assert [d[0]["status"] for d in done] == [200, 200]


def test_pool_timeout_is_a_503_with_retry_after(tmp_path):
    from fastapi.testclient import TestClient
    from sqlalchemy.exc import TimeoutError as PoolTimeout

    from jointdb.server import create_app
    from jointdb.server._settings import Settings
    from jointdb.store import Repository

    with Repository(tmp_path / "j.sqlite", blobs=tmp_path / "b") as repo:
        app = create_app(Settings(bind_host="127.0.0.1", open_reads=True), repo=repo)

        def empty_pool():
            raise PoolTimeout("QueuePool limit of size 16 overflow 8 reached")

        app.get("/api/v1/_test_pool")(empty_pool)
        with TestClient(app, raise_server_exceptions=False) as client:
            answer = client.get("/api/v1/_test_pool")
    assert answer.status_code == 503
    assert answer.headers["retry-after"] == "1"
    assert "QueuePool" not in answer.text


def test_pg_pool_is_sized_to_the_concurrency():
    from jointdb.store._db import make_engines

    engine, _ = make_engines("postgresql+psycopg://u@127.0.0.1:1/x", pool_size=24)
    assert engine.pool.size() == 24
    assert engine.pool._max_overflow == 12
    with pytest.raises(Exception, match="pool_size"):
        make_engines("postgresql+psycopg://u@127.0.0.1:1/x", pool_size=0)
