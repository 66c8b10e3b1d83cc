"""The service's log: every line on stderr is one JSON object (uvicorn's included), a failure is
logged once with status 500 and its traceback as one field, and no secret reaches the log."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

from server_helpers import free_port, joint_upload, make_tokens, start_server, stop_server


def _lines(text: str) -> list[dict]:
    out = []
    for line in text.splitlines():
        if not line.strip():
            continue
        obj = json.loads(line)  # every line, or the test fails here
        assert isinstance(obj, dict), line
        out.append(obj)
    return out


def _no_secrets(text: str, tokens) -> None:
    for token in tokens:
        assert token not in text and token[16:] not in text


def test_every_line_is_json_from_start_to_shutdown(tmp_path):
    from jointdb.store import upgrade

    db = f"sqlite:///{tmp_path / 'l.sqlite'}"
    upgrade(db)
    tokens = make_tokens(db, tmp_path / "blobs")
    srv = start_server(db, tmp_path / "blobs", tmp_path / "server.log")
    srv.tokens = tokens
    try:
        with srv.client("writer") as c:
            assert c.post("/api/v1/catalogue", json=joint_upload(tmp_path, "LOG-1")).status_code == 201
            c.get("/api/v1/joints/LOG-1", headers={"Cookie": f"jointdb_token={tokens['admin']}"})
            c.get("/api/v1/joints/nope")
            c.get("/api/v1/joints", params={"label": "\x00"})
        with srv.client(token=tokens["writer"] + "x") as c:
            c.get("/api/v1/joints")
    finally:
        stop_server(srv)
    text = srv.log_text()
    lines = _lines(text)
    loggers = {x.get("logger") for x in lines}
    assert "uvicorn.error" in loggers, loggers  # uvicorn's own lines are JSON too
    messages = " ".join(str(x.get("message", "")) for x in lines)
    assert "Started server process" in messages and "Finished server process" in messages
    requests = [x for x in lines if x.get("event") == "request"]
    assert {x["status"] for x in requests} >= {201, 200, 404, 422, 401}
    assert all(set(x) >= {"time", "level", "logger", "request_id", "path"} for x in requests)
    _no_secrets(text, tokens.values())


def test_lines_of_a_running_server_are_json(server):
    with server.client("reader") as c:
        c.get("/api/v1/joints")
        c.get("/api/v1/joints/x%00y")
        c.get("/readyz")
    lines = _lines(server.log_text())
    assert any(x.get("event") == "startup" and x.get("logger") == "jointdb.server" for x in lines)
    assert any(x.get("event") == "request" and x["status"] == 422 and x["path"] == "/api/v1/joints/x\x00y"
               for x in lines)
    _no_secrets(server.log_text(), server.tokens.values())


_CRASH = textwrap.dedent('''
    import sys, threading, time
    import httpx, uvicorn
    from jointdb.server import Settings, create_app
    from jointdb.io._jsonlog import log_config

    db, blobs, port, token = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
    app = create_app(Settings(url=db, blobs=blobs))

    @app.get("/api/v1/boom")
    def boom():
        raise RuntimeError("kaboom\\nsecond line postgresql://jointdb:hunter2@db/jointdb " + token)

    server = uvicorn.Server(uvicorn.Config(app, host="127.0.0.1", port=port, log_config=log_config("info"),
                                           access_log=False))
    thread = threading.Thread(target=server.run)
    thread.start()
    while not server.started:
        time.sleep(0.05)
    r = httpx.get(f"http://127.0.0.1:{port}/api/v1/boom",
                  headers={"Authorization": "Bearer " + token, "Cookie": "jointdb_token=" + token})
    print(r.status_code, r.text)
    server.should_exit = True
    thread.join(30)
''')


def test_unhandled_exception_is_logged_once_with_status_500_and_a_one_line_traceback(tmp_path):
    from jointdb.store import upgrade

    db = f"sqlite:///{tmp_path / 'c.sqlite'}"
    upgrade(db)
    token = make_tokens(db, tmp_path / "blobs")["writer"]
    proc = subprocess.run([sys.executable, "-c", _CRASH, db, str(tmp_path / "blobs"), str(free_port()), token],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr[-3000:]
    status, body = proc.stdout.split(" ", 1)
    assert status == "500"
    body = json.loads(body)
    assert "kaboom" not in body["error"] and body["request_id"] in body["error"]
    lines = _lines(proc.stderr)
    failed = [x for x in lines if "kaboom" in json.dumps(x)]
    assert len(failed) == 1, failed  # logged once
    line = failed[0]
    assert line["status"] == 500 and line["request_id"] == body["request_id"] and line["level"] == "ERROR"
    assert line["traceback"].startswith("Traceback") and "RuntimeError: kaboom" in line["traceback"]
    assert sum("Traceback" in json.dumps(x) for x in lines) == 1
    assert "hunter2" not in proc.stderr  # the password of a URL in the message is redacted
    _no_secrets(proc.stderr, [token])
