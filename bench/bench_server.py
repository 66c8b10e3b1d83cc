"""HTTP service under load and its latencies (run by hand; needs the server extra).

1. Load: C concurrent clients x W catalogue writes (each followed by a read of what it
   wrote) through HTTP against a `jointdb serve --workers N` on one database; then counts:
   every write acknowledged exactly once as a distinct (name, version), no version lost or
   duplicated in the database, and `db check` passes.
2. Latency: p50/p99 of show, download (JSON, cold cache: a new version each time) and
   nearest at the catalogue size reached (--versions; 10k in the issue, seeded directly
   through the Repository to save time).

    python bench/bench_server.py --db postgresql+psycopg://postgres@127.0.0.1:54332/postgres \
        --clients 16 --writes 50 --workers 2 --versions 10000
"""

from __future__ import annotations

import argparse
import random
import sys
import tempfile
import time
import uuid
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "server"))
from server_helpers import make_tokens, run_load, spring_joint, start_server, stop_server  # noqa: E402


def fresh_db(base: str, tmp: Path) -> tuple[str, object]:
    from jointdb.store import upgrade

    if base.startswith("postgresql"):
        import sqlalchemy as sa

        schema = "bench_" + uuid.uuid4().hex[:10]
        engine = sa.create_engine(base)
        with engine.begin() as conn:
            conn.exec_driver_sql(f"CREATE SCHEMA {schema}")
        url = f"{base}{'&' if '?' in base else '?'}options=-csearch_path%3D{schema}"
    else:
        url, schema, engine = f"sqlite:///{tmp / 'bench.sqlite'}", None, None
    upgrade(url)
    return url, (engine, schema)


def seed(server, n: int, threads: int = 4) -> None:
    """Catalogue versions directly through the Repository until the database holds ``n``
    (500 joints; ``threads`` writers, each on its own joints)."""
    import concurrent.futures as cf

    repo = server.repo()
    have = sum(len(repo.history(j.name)) for j in repo.list_joints())
    frf = spring_joint()

    def writer(t: int) -> None:
        rng = random.Random(t)
        for i in range(have + t, n, threads):
            repo.catalogue(f"S{i % 500:03d}", "tool-holder", frf,
                           {"materials": ["tungsten-carbide", "steel"], "torque_nm": rng.uniform(10, 100)},
                           "spring-damper-planar", author="bench", force=True)

    with cf.ThreadPoolExecutor(threads) as pool:
        list(pool.map(writer, range(threads)))


def latencies(server, samples: int) -> dict:
    repo = server.repo()
    names = [j.name for j in repo.list_joints() if j.name.startswith("S")]
    rng = random.Random(2)
    out = {}
    with server.client("reader") as c:
        def timed(fn):
            t = []
            for _ in range(samples):
                t0 = time.perf_counter()
                r = fn()
                t.append(time.perf_counter() - t0)
                assert r.status_code == 200, r.text[:200]
            return {"p50_ms": round(1e3 * float(np.percentile(t, 50)), 1),
                    "p99_ms": round(1e3 * float(np.percentile(t, 99)), 1)}

        out["show"] = timed(lambda: c.get(f"/api/v1/joints/{rng.choice(names)}/versions/{rng.randint(1, 10)}"))
        out["download_json"] = timed(lambda: c.get(
            f"/api/v1/joints/{rng.choice(names)}/versions/{rng.randint(1, 10)}/frf", params={"format": "json"}))
        out["nearest"] = timed(lambda: c.post("/api/v1/query/nearest", json={
            "joint_type": "tool-holder", "conditions": {"materials": ["carbide", "steel"],
                                                        "torque_nm": rng.uniform(10, 100)}, "k": 3}))
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--db", required=True, help="PostgreSQL base URL (a fresh schema is made) or 'sqlite'.")
    ap.add_argument("--clients", type=int, default=16)
    ap.add_argument("--writes", type=int, default=50)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--versions", type=int, default=10000)
    ap.add_argument("--samples", type=int, default=200)
    ap.add_argument("--blobs", default="database", help="'database' (blobs in the database) or 'files'.")
    ap.add_argument("--schema", default=None, help="Reuse this PostgreSQL schema (already seeded): latency only.")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp_:
        tmp = Path(tmp_)
        if args.schema:
            import sqlalchemy as sa

            url = f"{args.db}{'&' if '?' in args.db else '?'}options=-csearch_path%3D{args.schema}"
            engine, schema, args.clients = sa.create_engine(args.db), args.schema, 0
        else:
            url, (engine, schema) = fresh_db(args.db, tmp)
        blobs = "database" if args.blobs == "database" else tmp / "blobs"
        tokens = make_tokens(url, blobs)
        server = start_server(url, blobs, tmp / "server.log", workers=args.workers)
        server.tokens = tokens
        try:
            if args.clients:
                print("load:", run_load(server, args.clients, args.writes, tmp), flush=True)
            if args.versions:
                t0 = time.perf_counter()
                seed(server, args.versions)
                print(f"seeded to {args.versions} versions in {time.perf_counter() - t0:.0f} s", flush=True)
                print("latency at", args.versions, "versions:", latencies(server, args.samples), flush=True)
        finally:
            stop_server(server)
            if engine is not None:
                from server_helpers import drop_pg_schema

                drop_pg_schema(engine, schema)


if __name__ == "__main__":
    main()
