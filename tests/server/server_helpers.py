"""Helpers of the server tests (imported by name; pytest puts this directory on sys.path): start and
stop ``jointdb serve`` on a free local port, tokens per role, joint-file uploads."""

from __future__ import annotations

import base64
import contextlib
import os
import signal
import socket
import subprocess
import sys
import time
import uuid
from dataclasses import dataclass, field
from pathlib import Path

import httpx


def _load(name: str, path: Path):
    import importlib.util

    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


_STORE = Path(__file__).resolve().parents[1] / "store"
_store_conftest = _load("jointdb_store_conftest", _STORE / "conftest.py")  # the PostgreSQL schema helpers
_pg_schema, drop_pg_schema, pg_base_url = (_store_conftest._pg_schema, _store_conftest.drop_pg_schema,
                                           _store_conftest.pg_base_url)
spring_joint = _load("jointdb_store_helpers", _STORE / "store_helpers.py").spring_joint


def one_line_4xx(r, status=None) -> str:
    """The one-line error of a 4xx answer (``status``: exactly that one)."""
    assert 400 <= r.status_code < 500, (r.status_code, r.text)
    if status is not None:
        assert r.status_code == status, (r.status_code, r.text)
    msg = r.json()["error"]
    assert msg and "\n" not in msg and "Traceback" not in msg
    return msg


@contextlib.contextmanager
def migrated_database(backend: str, tmp: Path):
    """The URL of a migrated database: ``"sqlite"`` a file in ``tmp``; ``"postgresql"`` a fresh schema
    (skipped without ``JOINTDB_TEST_PG_URL``), dropped afterwards."""
    from jointdb.store import upgrade

    cleanup = None
    if backend == "sqlite":
        db = f"sqlite:///{tmp / 'j.sqlite'}"
    else:
        engine, schema, db = _pg_schema(pg_base_url())
        cleanup = (engine, schema)
    try:
        upgrade(db)
        yield db
    finally:
        if cleanup:
            drop_pg_schema(*cleanup)
            cleanup[0].dispose()


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@dataclass
class Server:
    url: str
    db: str
    blobs: Path
    log: Path
    proc: subprocess.Popen
    tokens: dict[str, str] = field(default_factory=dict)

    def client(self, role: str | None = None, token: str | None = None) -> "httpx.Client":
        tok = token if token is not None else (self.tokens[role] if role else None)
        headers = {"Authorization": f"Bearer {tok}"} if tok else {}
        return httpx.Client(base_url=self.url, headers=headers, timeout=60.0)

    def repo(self):
        from jointdb.store import Repository

        return Repository(self.db, blobs=self.blobs, auto_create=False)

    def log_text(self) -> str:
        return self.log.read_text(encoding="utf-8", errors="replace")


def start_server(db: str, blobs: Path, log: Path, *extra: str, workers: int = 1) -> Server:
    port = free_port()
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "JOINTDB_AUTHOR": "server-process"}
    fh = open(log, "ab")
    proc = subprocess.Popen([sys.executable, "-m", "jointdb", "serve", "--db", db, "--blobs", str(blobs),
                             "--port", str(port), "--workers", str(workers),
                             *(["--allow-owner"] if db.startswith("postgresql") else []), *extra],
                            stdout=fh, stderr=subprocess.STDOUT, env=env)
    fh.close()
    url = f"http://127.0.0.1:{port}"
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            raise RuntimeError(f"jointdb serve exited with {proc.returncode}: {log.read_text()[-2000:]}")
        try:
            if httpx.get(f"{url}/readyz", timeout=2).status_code == 200:
                return Server(url, db, blobs, log, proc)
        except httpx.HTTPError:
            pass
        time.sleep(0.2)
    proc.kill()
    raise RuntimeError(f"jointdb serve did not become ready: {log.read_text()[-2000:]}")


def stop_server(server: Server) -> int:
    server.proc.send_signal(signal.SIGTERM)
    try:
        return server.proc.wait(timeout=30)
    except subprocess.TimeoutExpired:
        server.proc.kill()
        return server.proc.wait()


def make_tokens(db: str, blobs: Path) -> dict[str, str]:
    from jointdb.store import Repository
    from jointdb.store._tokens import create_token, revoke_token

    with Repository(db, blobs=blobs, auto_create=False) as repo:
        tokens = {role: create_token(repo, f"{role}-owner", role)[0] for role in ("reader", "writer", "admin")}
        revoked, info = create_token(repo, "revoked-owner", "writer")
        revoke_token(repo, info.token_id)
        tokens["revoked"] = revoked
        expired, info = create_token(repo, "expired-owner", "writer", "1m")
        tokens["expired"] = expired
        from datetime import datetime, timedelta, timezone

        from sqlalchemy import update

        from jointdb.store._models import TokenRow

        with repo._write() as s, s.begin():  # as if a minute had passed
            s.execute(update(TokenRow).where(TokenRow.token_id == info.token_id)
                      .values(expires_at=datetime.now(timezone.utc) - timedelta(seconds=1)))
    return tokens


def joint_upload(tmp: Path, name: str, torque: float = 40.0, k: float = 2e6, **extra) -> dict:
    """The JSON body of POST /api/v1/catalogue for a planar spring-damper joint file."""
    from jointdb import io

    path = tmp / f"{uuid.uuid4().hex[:8]}.h5"
    io.write_frf_hdf5(path, spring_joint(k=(k, 8e4)), {
        "kind": "joint", "joint_model": "planar", "joint_type": "tool-holder",
        "conditions": {"materials": ["tungsten-carbide", "steel"], "torque_nm": torque}})
    body = {"name": name, "filename": "joint.h5", "file_b64": base64.b64encode(path.read_bytes()).decode()}
    body.update(extra)
    return body


class _Tolerant:
    """An httpx client whose transport errors become a 599 response (a killed worker)."""

    def __init__(self, client, failed: list):
        self.client, self.failed = client, failed

    def _call(self, method, *a, **kw):
        try:
            return getattr(self.client, method)(*a, **kw)
        except httpx.HTTPError:
            return httpx.Response(599, text="transport error")

    def post(self, *a, **kw):
        return self._call("post", *a, **kw)

    def get(self, *a, **kw):
        return self._call("get", *a, **kw)


def run_load(server, clients: int, writes: int, tmp: Path, tolerate_errors: bool = False) -> dict:
    """``clients`` threads x ``writes`` catalogue uploads (20 shared joint names, so versions
    of one joint race), each read back; then what the database holds against what was
    acknowledged. With ``tolerate_errors`` a failed request (e.g. a killed worker) is
    counted, not raised."""
    import concurrent.futures as cf

    body = joint_upload(tmp, "template")

    def client(i: int) -> list[tuple[str, int]]:
        done = []
        with server.client("writer") as c:
            c = _Tolerant(c, failed) if tolerate_errors else c
            for j in range(writes):
                name = f"L{i % 4}-{j % 5}"  # 20 joints shared by the clients: concurrent new versions
                r = c.post("/api/v1/catalogue", json={**body, "name": name,
                                                      "conditions": {"torque_nm": 10.0 + i + j / 100},
                                                      "force": True})
                if r.status_code != 201:
                    if tolerate_errors:
                        failed.append(r.status_code)
                        continue
                    raise RuntimeError(f"{r.status_code} {r.text[:200]}")
                v = r.json()["version"]
                got = c.get(f"/api/v1/joints/{name}/versions/{v}")
                for _ in range(20 if tolerate_errors else 0):  # a killed worker: the next one answers
                    if got.status_code != 599:
                        break
                    time.sleep(0.25)
                    got = c.get(f"/api/v1/joints/{name}/versions/{v}")
                if got.status_code != 200 or got.json()["conditions"]["torque_nm"] != 10.0 + i + j / 100:
                    raise RuntimeError(f"read-back of {name} v{v} failed: {got.status_code}")
                done.append((name, v))
        return done

    failed: list = []
    t0 = time.perf_counter()
    with cf.ThreadPoolExecutor(clients) as pool:
        acked = [x for part in pool.map(client, range(clients)) for x in part]
    elapsed = time.perf_counter() - t0
    repo = server.repo()
    stored = [(v.name, v.version) for j in repo.list_joints() for v in repo.history(j.name)]
    report = repo.check()
    return {"acknowledged": len(acked), "distinct_acknowledged": len(set(acked)), "stored": len(stored),
            "lost": len(set(acked) - set(stored)), "duplicated": len(acked) - len(set(acked)),
            "extra_in_db": len(set(stored) - set(acked)), "check_ok": report.ok, "check_problems": list(report.problems)[:3],
            "failed_requests": len(failed), "seconds": round(elapsed, 1),
            "writes_per_s": round(len(acked) / elapsed, 1)}
