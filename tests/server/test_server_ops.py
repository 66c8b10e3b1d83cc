"""Operation: request time limit (503, one line), structured request logs, graceful shutdown
(a request in flight finishes before the process exits)."""

from __future__ import annotations

import asyncio
import base64
import io
import json
import signal
import threading
import time
import zipfile
from pathlib import Path

import httpx

from server_helpers import make_tokens, start_server

from jointdb.server._middleware import ServiceMiddleware


async def _slow_app(scope, receive, send):
    await asyncio.sleep(5)
    await send({"type": "http.response.start", "status": 200, "headers": []})
    await send({"type": "http.response.body", "body": b"late"})


def test_request_time_limit_gives_503_one_line():
    app = ServiceMiddleware(_slow_app, max_upload_bytes=1000, request_timeout_s=0.2)

    async def go():
        async with httpx.AsyncClient(transport=httpx.ASGITransport(app=app), base_url="http://t") as c:
            t0 = time.perf_counter()
            r = await c.get("/anything")
            return r, time.perf_counter() - t0

    r, elapsed = asyncio.run(go())
    assert r.status_code == 503 and elapsed < 2
    body = r.json()
    assert "longer than 0.2 s" in body["error"] and "\n" not in body["error"] and body["request_id"]
    assert r.headers["x-request-id"] == body["request_id"]


def _campaign_zip() -> str:
    root = Path(__file__).resolve().parents[2] / "fixtures" / "campaigns" / "th-steel-30nm"
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zf:
        for p in sorted(root.iterdir()):
            zf.write(p, p.name)
    return base64.b64encode(buf.getvalue()).decode()


def test_graceful_shutdown_finishes_the_request_in_flight(tmp_path):
    from jointdb.store import upgrade

    db = f"sqlite:///{tmp_path / 'g.sqlite'}"
    upgrade(db)
    tokens = make_tokens(db, tmp_path / "blobs")
    server = start_server(db, tmp_path / "blobs", tmp_path / "server.log")
    server.tokens = tokens
    result = {}

    def upload():  # identification on the server takes a while
        with server.client("writer") as c:
            result["r"] = c.post("/api/v1/catalogue", json={"name": "GRACE", "filename": "c.zip",
                                                             "file_b64": _campaign_zip()})

    t = threading.Thread(target=upload)
    t.start()
    time.sleep(0.5)
    server.proc.send_signal(signal.SIGTERM)
    t.join(60)
    # uvicorn shuts down gracefully, then re-raises the signal it caught (exit by SIGTERM)
    assert server.proc.wait(60) in (0, -signal.SIGTERM)
    assert result["r"].status_code == 201, result["r"].text
    text = server.log_text()
    assert text.index("Shutting down") < text.index('"path": "/api/v1/catalogue"') < text.index("Finished server")
    with server.repo() as repo:
        assert repo.get("GRACE").version == 1 and repo.check().ok
    lines = [json.loads(x) for x in server.log_text().splitlines() if x.startswith('{"event": "request"')]
    post = [x for x in lines if x["method"] == "POST"][0]
    assert post["status"] == 201 and post["actor"] == "writer-owner" and post["duration_ms"] > 0
    assert set(post) >= {"request_id", "path", "bytes_in", "client"}
