"""The service under 32 clients (issue 26, item 4): show, FRF download and nearest on a
PostgreSQL catalogue of 100k versions, ``jointdb serve --workers 2``.

The catalogue is bulk-filled (``bench/_bulk.py``: real rows and record hashes, no blobs)
plus ``--with-blobs`` versions catalogued through the Repository (their FRFs are what
the downloads fetch, HDF5 exchange files, each version several times so the encoded-file
cache is exercised as in real use). Each of ``--clients`` threads sends a mix of the three
requests on its own kept-alive connection; the bench prints p50/p99 per kind and the count
of every status (the goal: no 500 and no 503; 429 is the service's back-pressure and is
counted separately).

The load generator runs on the same cores as the server, so it is kept cheap
(``bench/_rawhttp.py``: one raw socket per client, requests built before the clock starts,
0.05 ms of client CPU per /healthz request against 0.40 ms with an httpx.Client, measured
side by side); it still reads every response whole
and counts its status. Printed as well: the CPU time per request of the server's processes
(the workers, from /proc) and of the load generator, which the machine's load moves far less
than the latencies, and the load average before, at the start and after.

Reference in the same run: the same mix from one client (the service's unloaded latency).

    PYTHONPATH=. OPENBLAS_NUM_THREADS=1 python bench/bench_service_load.py --versions 100000
    (defaults: the dev PostgreSQL at 127.0.0.1:54330, --workers 2 --clients 32 --per-client 30)
"""

from __future__ import annotations

import argparse
import collections
import os
import concurrent.futures as cf
import random
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "server"))
sys.path.insert(0, str(Path(__file__).resolve().parent))
from _bulk import bulk_fill  # noqa: E402
from _rawhttp import RawClient, build  # noqa: E402

DEV_PG = "postgresql+psycopg://postgres@127.0.0.1:54330/postgres"
from bench_server import fresh_db  # noqa: E402
from server_helpers import drop_pg_schema, make_tokens, spring_joint, start_server, stop_server  # noqa: E402


def seed(url: str, blobs, versions: int, with_blobs: int) -> list[tuple[str, int]]:
    """Bulk rows, then ``with_blobs`` real versions (10 joints); their (name, version) pairs."""
    from jointdb.store import Repository

    with Repository(url, blobs=blobs, auto_create=False) as repo:
        bulk_fill(repo, versions, per_joint=10)
        if not repo.is_sqlite:  # bulk_fill gives explicit ids: move the sequence past them
            with repo.write_engine.begin() as conn:
                conn.exec_driver_sql("SELECT setval(pg_get_serial_sequence('joints', 'id'), "
                                     "(SELECT max(id) FROM joints))")
        frf = spring_joint()
        real = [repo.catalogue(f"D{i % 10:02d}", "tool-holder", frf, {"torque_nm": 20.0 + i},
                               "spring-damper-planar", author="bench", force=True) for i in range(with_blobs)]
    return [(v.name, v.version) for v in real]


def prebuilt(rng: random.Random, n: int, host: str, token: str, downloads, n_joints: int) -> list[tuple[str, bytes]]:
    """``n`` requests of a seeded mix of show, HDF5 download and nearest, as bytes (built before timing)."""
    out = []
    for _ in range(n):
        kind = rng.choice(KINDS)
        if kind == "show":
            req = build("GET", f"/api/v1/joints/bulk-{rng.randrange(n_joints):07d}/versions/{rng.randint(1, 10)}",
                        host, token)
        elif kind == "download":
            name, version = rng.choice(downloads)
            req = build("GET", f"/api/v1/joints/{name}/versions/{version}/frf?format=hdf5", host, token)
        else:
            req = build("POST", "/api/v1/query/nearest", host, token, {"joint_type": "tool-holder", "conditions": {
                "materials": ["tungsten-carbide", "steel"], "torque_nm": rng.uniform(10, 200)}, "k": 3})
        out.append((kind, req))
    return out


KINDS = ("show", "download", "nearest")


def run(server, clients: int, per_client: int, downloads, seed_: int, n_joints: int) -> tuple[dict, collections.Counter]:
    """``clients`` threads, each on its own kept-alive raw connection (:mod:`_rawhttp`: the load
    generator shares the cores, so it is kept cheap), each sending ``per_client`` requests; every
    response is read whole and its status counted. p50/p99 [ms] of the 200s per kind."""
    host, port = server.url.removeprefix("http://").split(":")
    token = server.tokens["reader"]
    plans = [prebuilt(random.Random(seed_ * 1000 + i), per_client, f"{host}:{port}", token, downloads, n_joints)
             for i in range(clients)]
    start = threading.Barrier(clients)

    def client(i: int):
        c = RawClient(host, int(port))
        done = []
        try:
            start.wait()
            for kind, req in plans[i]:
                t0 = time.perf_counter()
                status, body = c.send(req)
                done.append((kind, status, time.perf_counter() - t0, len(body)))
        finally:
            c.close()
        return done

    with cf.ThreadPoolExecutor(clients) as pool:
        results = [x for part in pool.map(client, range(clients)) for x in part]
    statuses = collections.Counter(status for _, status, _, _ in results)
    if any(n == 0 for k, s, _, n in results if s == 200):
        raise RuntimeError("an empty 200 response")
    if any(s != 200 for s in statuses):  # every request names something that exists: any other status is a fault
        raise RuntimeError(f"not every request answered 200: {dict(statuses)}")
    table = {}
    for kind in KINDS:
        t = np.array([dt for k, s, dt, _ in results if k == kind and s == 200]) * 1e3
        table[kind] = {"n": len(t), "p50_ms": round(float(np.percentile(t, 50)), 1),
                       "p99_ms": round(float(np.percentile(t, 99)), 1)} if len(t) else {"n": 0}
    return table, statuses


def tree_cpu_s(pid: int) -> float:
    """CPU time [s] (user + system) of process ``pid`` and its children (the server's workers), from /proc."""
    tick = os.sysconf("SC_CLK_TCK")
    stats = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            stats[int(entry.name)] = (int(fields[1]), (int(fields[11]) + int(fields[12])) / tick)
    family, total, grew = {pid}, 0.0, True
    while grew:
        more = {p for p, (parent, _) in stats.items() if parent in family} - family
        grew, family = bool(more), family | more
    return sum(stats[p][1] for p in family if p in stats)


def measured(server, clients: int, per_client: int, downloads, seed_: int, n_joints: int):
    """:func:`run` plus the CPU per request [ms] of the server's processes and of this load generator."""
    s0, c0 = tree_cpu_s(server.proc.pid), time.process_time()
    table, statuses = run(server, clients, per_client, downloads, seed_, n_joints)
    n = clients * per_client
    cpu = {"server_ms": round((tree_cpu_s(server.proc.pid) - s0) / n * 1e3, 2),
           "client_ms": round((time.process_time() - c0) / n * 1e3, 2)}
    return table, statuses, cpu


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--db", default=DEV_PG, help="PostgreSQL base URL (a fresh schema is made) or 'sqlite'.")
    ap.add_argument("--versions", type=int, default=100_000)
    ap.add_argument("--with-blobs", type=int, default=40)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--clients", type=int, default=32)
    ap.add_argument("--per-client", type=int, default=30)
    ap.add_argument("--blobs", default="database", help="'database' or 'files'")
    args = ap.parse_args()
    print(f"load average before: {os.getloadavg()}", flush=True)
    with tempfile.TemporaryDirectory() as tmp_:
        tmp = Path(tmp_)
        url, (engine, schema) = fresh_db(args.db, tmp)
        blobs = "database" if args.blobs == "database" else tmp / "blobs"
        try:
            t0 = time.perf_counter()
            downloads = seed(url, blobs, args.versions, args.with_blobs)
            print(f"seeded {args.versions} + {args.with_blobs} versions in {time.perf_counter() - t0:.0f} s", flush=True)
            tokens = make_tokens(url, blobs)
            server = start_server(url, blobs, tmp / "server.log", workers=args.workers)
            server.tokens = tokens
            try:
                n_joints = args.versions // 10
                run(server, 4, 10, downloads, 0, n_joints)  # warm: connections, caches, imports
                print(f"load average at start: {os.getloadavg()}", flush=True)
                ref, _, ref_cpu = measured(server, 1, 3 * args.per_client, downloads, 1, n_joints)
                print("reference, 1 client:", ref, "CPU per request:", ref_cpu, flush=True)
                table, statuses, cpu = measured(server, args.clients, args.per_client, downloads, 2, n_joints)
                print(f"{args.clients} clients, {args.workers} workers:", table, "CPU per request:", cpu, flush=True)
                print("statuses:", dict(statuses), flush=True)
                print("p99 ratio to 1 client:", {k: round(table[k]["p99_ms"] / ref[k]["p99_ms"], 1)
                                                 for k in table if table[k].get("n") and ref[k].get("n")})
                print(f"load average after: {os.getloadavg()}", flush=True)
            finally:
                stop_server(server)
        finally:
            if engine is not None:
                drop_pg_schema(engine, schema)


if __name__ == "__main__":
    main()
