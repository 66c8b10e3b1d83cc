"""Helpers of the server tests (imported by name; pytest puts this directory on sys.path): start and
stop ``jointdb serve`` on a free local port, tokens per role, joint-file uploads."""

from __future__ import annotations

import base64
import os
import signal
import socket
import subprocess
import sys
import time
import uuid
from dataclasses import dataclass, field
from pathlib import Path

import pytest


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
                             "--port", str(port), "--workers", str(workers), *extra],
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
