"""Catalogue requests under client retries and a killed server (issue 20): C clients x R catalogue
requests through a live `jointdb serve` on loopback, each made by :class:`jointdb.client.RemoteRepository`
(an ``Idempotency-Key`` per request, retried with the same key after a connection error or a 503),
with a SIGKILL of the server mid-run and a restart on the same port. Then, in the database:

- lost: requests that got a success answer but have no version;
- duplicated: requests that made more than one version.

Each request asks for a new version even when its content equals the latest one
(``allow_identical``), so only the idempotency key keeps a retry from making a second version.

    python bench/bench_reliability.py                      # SQLite, 16 x 80
    python bench/bench_reliability.py --pg postgresql+psycopg://postgres@127.0.0.1:54330/postgres
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import httpx

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "server"))
from server_helpers import _pg_schema, drop_pg_schema, free_port, make_tokens, spring_joint  # noqa: E402

def _serve(db: str, blobs: Path, log: Path, port: int) -> subprocess.Popen:
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "JOINTDB_AUTHOR": "server-process"}
    with open(log, "ab") as fh:
        proc = subprocess.Popen([sys.executable, "-m", "jointdb", "serve", "--db", db, "--blobs", str(blobs),
                                 "--port", str(port), "--workers", "1",
                                 # the bench connects as the server's superuser (JOINTDB_TEST_PG_URL)
                                 *(["--allow-owner"] if db.startswith("postgresql") else [])],
                                stdout=fh, stderr=subprocess.STDOUT, env=env)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            raise RuntimeError(f"jointdb serve exited with {proc.returncode}")
        try:
            if httpx.get(f"http://127.0.0.1:{port}/readyz", timeout=2).status_code == 200:
                return proc
        except httpx.HTTPError:
            pass
        time.sleep(0.1)
    proc.kill()
    raise RuntimeError("jointdb serve did not become ready")


def run_killed_server(db: str, blobs: Path, log: Path, token: str, clients: int, requests: int,
                      kill_after: int) -> dict:
    """``clients`` x ``requests`` catalogue calls through :class:`jointdb.client.RemoteRepository`
    (Idempotency-Key, retries), SIGKILL of the server after ``kill_after`` successes, restart on the
    same port; then count lost and duplicated requests in the database (``retries``: requests
    resent after a transport error)."""
    from jointdb.client import RemoteRepository
    from jointdb.store import Conditions, Repository

    port = free_port()
    state = {"proc": _serve(db, blobs, log, port), "ok": 0, "killed": False, "retries": 0}
    url = f"http://127.0.0.1:{port}"

    def client(c: int) -> list[tuple[int, int, str]]:
        done = []
        with RemoteRepository(url, token, timeout=30) as remote:
            post = remote._http.post

            def counted(*a, **kw):  # each transport error is followed by a retry with the same key
                try:
                    return post(*a, **kw)
                except httpx.TransportError:
                    state["retries"] += 1
                    raise

            remote._http.post = counted
            for i in range(requests):
                try:
                    jv, created = remote.catalogue_outcome(
                        f"rel-{c}", "tool-holder", spring_joint(k=(1e6 * (1 + i), 8e4)),
                        Conditions(("steel",), torque_nm=40.0), "spring-damper-planar",
                        {"method": "bench", "parameters": {"client": c, "seq": i}}, allow_identical=True)
                    done.append((c, i, "ok"))
                    state["ok"] += 1
                except Exception as exc:  # counted: a request that never got an answer
                    done.append((c, i, type(exc).__name__))
        return done

    def killer():
        deadline = time.monotonic() + 120
        while state["ok"] < kill_after and not state.get("clients_done") and time.monotonic() < deadline:
            time.sleep(0.01)
        state["proc"].send_signal(signal.SIGKILL)
        state["proc"].wait()
        state["killed"] = True
        time.sleep(0.5)
        state["proc"] = _serve(db, blobs, log, port)

    started = time.monotonic()
    with cf.ThreadPoolExecutor(clients + 1) as pool:
        kill = pool.submit(killer)
        outcomes = [x for part in pool.map(client, range(clients)) for x in part]
        state["clients_done"] = True
        kill.result(timeout=180)
    seconds = time.monotonic() - started
    state["proc"].send_signal(signal.SIGTERM)
    state["proc"].wait(timeout=30)
    counts: dict[tuple[int, int], int] = {}
    with Repository(db, blobs=blobs, auto_create=False) as repo:
        for c in range(clients):
            try:
                history = repo.history(f"rel-{c}")
            except Exception:  # no version of this client at all
                history = []
            for v in history:
                key = (v.provenance.parameters["client"], v.provenance.parameters["seq"])
                counts[key] = counts.get(key, 0) + 1
        check_ok = repo.check().ok
    succeeded = [(c, i) for c, i, how in outcomes if how == "ok"]
    return {"requests": len(outcomes), "succeeded": len(succeeded), "failed": len(outcomes) - len(succeeded),
            "lost": sum(1 for k in succeeded if counts.get(k, 0) == 0),
            "duplicated": sum(1 for n in counts.values() if n > 1), "versions": sum(counts.values()),
            "killed": state["killed"], "retries": state["retries"], "db_check_ok": check_ok,
            "seconds": round(seconds, 1)}



def run(backend: str, pg: str | None, clients: int, requests: int, kill_after: int) -> dict:
    """One run on a fresh SQLite file or PostgreSQL schema (dropped afterwards)."""
    from jointdb.store import upgrade

    with tempfile.TemporaryDirectory(prefix="jointdb-reliability-") as tmp:
        tmp = Path(tmp)
        cleanup = None
        if backend == "sqlite":
            db = f"sqlite:///{tmp / 'j.sqlite'}"
        else:
            engine, schema, db = _pg_schema(pg)
            cleanup = (engine, schema)
        try:
            upgrade(db)
            token = make_tokens(db, tmp / "blobs")["writer"]
            return run_killed_server(db, tmp / "blobs", tmp / "server.log", token, clients, requests, kill_after)
        finally:
            if cleanup:
                drop_pg_schema(*cleanup)
                cleanup[0].dispose()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--clients", type=int, default=16)
    ap.add_argument("--requests", type=int, default=80)
    ap.add_argument("--kill-after", type=int, default=None, help="successes before the SIGKILL (default: half)")
    ap.add_argument("--pg", default=os.environ.get("JOINTDB_TEST_PG_URL"), help="PostgreSQL URL (also run there)")
    args = ap.parse_args()
    kill_after = args.kill_after or args.clients * args.requests // 2
    for backend in ("sqlite", "postgresql") if args.pg else ("sqlite",):
        out = run(backend, args.pg, args.clients, args.requests, kill_after)
        print(f"{backend}: {args.clients} clients x {args.requests} requests, SIGKILL after {kill_after} successes: "
              + ", ".join(f"{k} {v}" for k, v in out.items()), flush=True)


if __name__ == "__main__":
    main()
