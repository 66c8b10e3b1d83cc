"""Keep-alive latency with one and with two uvicorn workers (issue 26, item 4).

Starts ``jointdb serve --workers 1`` and ``--workers 2`` on the same SQLite file and
times ``GET /healthz`` on one kept-alive connection each; prints p50 and the ratio
2-workers / 1-worker (goal <= 2; without TCP_NODELAY per connection it was ~60x:
44 ms against 0.7 ms). ``--plain-uvicorn`` also runs uvicorn's own protocol with two
workers, the reference that shows the penalty in the same run.

    python bench/bench_keepalive.py [--requests 300]
"""

from __future__ import annotations

import argparse
import http.client
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "server"))
from server_helpers import free_port, start_server, stop_server  # noqa: E402


def p50_ms(url: str, n: int) -> float:
    host, port = url.removeprefix("http://").split(":")
    conn = http.client.HTTPConnection(host, int(port))
    times = []
    for _ in range(n):
        t0 = time.perf_counter()
        conn.request("GET", "/healthz")
        conn.getresponse().read()
        times.append(time.perf_counter() - t0)
    conn.close()
    return statistics.median(times) * 1e3


def plain_uvicorn(db: str, n: int) -> float:
    """p50 of uvicorn's own protocol with two workers (the app as jointdb serve builds it)."""
    port = free_port()
    env = {**os.environ, "JOINTDB_URL": db, "JOINTDB_OPEN_READS": "1", "OPENBLAS_NUM_THREADS": "1"}
    proc = subprocess.Popen([sys.executable, "-m", "uvicorn", "--factory", "jointdb.server:app_from_env",
                             "--port", str(port), "--workers", "2", "--log-level", "warning"], env=env)
    try:
        url = f"http://127.0.0.1:{port}"
        for _ in range(100):
            try:
                p50_ms(url, 1)
                break
            except OSError:
                time.sleep(0.2)
        return p50_ms(url, n)
    finally:
        proc.terminate()
        proc.wait(30)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--requests", type=int, default=300)
    parser.add_argument("--plain-uvicorn", action="store_true")
    args = parser.parse_args()
    from jointdb.store import upgrade

    with tempfile.TemporaryDirectory() as tmp:
        db = f"sqlite:///{Path(tmp) / 'k.sqlite'}"
        upgrade(db)
        result = {}
        for workers in (1, 2):
            server = start_server(db, Path(tmp) / "blobs", Path(tmp) / f"log{workers}", "--open-reads",
                                  workers=workers)
            try:
                p50_ms(server.url, 20)  # warm up
                result[workers] = p50_ms(server.url, args.requests)
            finally:
                stop_server(server)
        print(f"keep-alive /healthz p50: 1 worker {result[1]:.2f} ms, 2 workers {result[2]:.2f} ms, "
              f"ratio {result[2] / result[1]:.2f} (goal <= 2)")
        if args.plain_uvicorn:
            plain = plain_uvicorn(db, args.requests)
            print(f"reference, uvicorn's own protocol, 2 workers: p50 {plain:.2f} ms "
                  f"({plain / result[1]:.0f}x the 1-worker jointdb serve)")


if __name__ == "__main__":
    main()
