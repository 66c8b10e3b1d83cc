#!/usr/bin/env python
"""CPU per request of the service's hot routes, in process (issue 26, item 4).

The ASGI app is called directly (a hand-built HTTP scope, no socket, no HTTP client), so
what is timed is the server's own work per request: middleware, routing, dependencies, the
route, the store and the JSON. A PostgreSQL (or SQLite) catalogue is bulk-filled
(``bench/_bulk.py``) plus a few versions with blobs; then for each kind (show, FRF
download, nearest, list, healthz) ``--n`` requests are sent one after the other and the
process CPU time per request is printed. ``--profile KIND`` prints yappi's top functions
for that kind instead (yappi must be importable).

    PYTHONPATH=. OPENBLAS_NUM_THREADS=1 python bench/profile_service.py --versions 20000 [--db sqlite]
"""

from __future__ import annotations

import argparse
import asyncio
import json
import random
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "server"))
sys.path.insert(0, str(Path(__file__).resolve().parent))
from _asgi import call  # noqa: E402
from bench_server import fresh_db  # noqa: E402
from bench_service_load import seed  # noqa: E402
from server_helpers import drop_pg_schema, make_tokens  # noqa: E402

DEV_PG = "postgresql+psycopg://postgres@127.0.0.1:54330/postgres"


def requests_of(kind: str, rng: random.Random, n_joints: int, downloads) -> tuple[str, str, str, bytes]:
    if kind == "show":
        return "GET", f"/api/v1/joints/bulk-{rng.randrange(n_joints):07d}/versions/{rng.randint(1, 10)}", "", b""
    if kind == "download":
        name, version = rng.choice(downloads)
        return "GET", f"/api/v1/joints/{name}/versions/{version}/frf", "format=hdf5", b""
    if kind == "nearest":
        body = {"joint_type": "tool-holder", "conditions": {"materials": ["tungsten-carbide", "steel"],
                                                            "torque_nm": rng.uniform(10, 200)}, "k": 3}
        return "POST", "/api/v1/query/nearest", "", json.dumps(body).encode()
    if kind == "list":
        return "GET", "/api/v1/joints", "limit=50", b""
    return "GET", "/healthz", "", b""


async def drive(app, kinds, n: int, token: str, n_joints: int, downloads, profile: str | None) -> None:
    for kind in kinds:
        rng = random.Random(5)
        for _ in range(5):  # warm
            status, _ = await call(app, *requests_of(kind, rng, n_joints, downloads), token=token)
            assert status == 200, (kind, status)
        if profile == kind:
            import yappi

            yappi.set_clock_type("cpu")
            yappi.start()
        c0, w0 = time.process_time(), time.perf_counter()
        for _ in range(n):
            status, _ = await call(app, *requests_of(kind, rng, n_joints, downloads), token=token)
            if status != 200:
                raise RuntimeError(f"{kind}: {status}")
        cpu, wall = (time.process_time() - c0) / n * 1e3, (time.perf_counter() - w0) / n * 1e3
        if profile == kind:
            yappi.stop()
            stats = yappi.get_func_stats()
            for label, key in (("own time", "tsub"), ("total time", "ttot")):
                print(f"--- {kind}: top by {label} (ms per request)")
                for s in sorted(stats, key=lambda s: -getattr(s, key))[:35]:
                    print(f"{getattr(s, key) / n * 1e3:8.3f} {s.ncall / n:7.1f}x  {s.module.split('site-packages/')[-1][-45:]}:{s.lineno} {s.name}")
            yappi.clear_stats()
        print(f"{kind:9s} cpu {cpu:6.2f} ms/request, wall {wall:6.2f} ms", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--db", default=DEV_PG, help="PostgreSQL base URL or 'sqlite'")
    ap.add_argument("--versions", type=int, default=20_000)
    ap.add_argument("--n", type=int, default=300)
    ap.add_argument("--kinds", default="healthz,show,download,nearest,list")
    ap.add_argument("--profile", default=None)
    args = ap.parse_args()
    from jointdb.server import create_app
    from jointdb.server._settings import Settings
    from jointdb.store import Repository

    with tempfile.TemporaryDirectory() as tmp_:
        tmp = Path(tmp_)
        url, (engine, schema) = fresh_db(args.db, tmp)
        try:
            downloads = seed(url, "database", args.versions, 10)
            token = make_tokens(url, "database")["reader"]
            repo = Repository(url, blobs="database", auto_create=False)
            app = create_app(Settings(url=url, blobs="database", cache_dir=""), repo=repo)

            async def run():
                async with app.router.lifespan_context(app):
                    await drive(app, args.kinds.split(","), args.n, token, args.versions // 10, downloads,
                                args.profile)

            asyncio.run(run())
            repo.close()
        finally:
            if engine is not None:
                drop_pg_schema(engine, schema)


if __name__ == "__main__":
    main()
