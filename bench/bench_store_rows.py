#!/usr/bin/env python
"""Benchmark: the store rows of issue 11, each as a ratio against a reference in the same run.

1. Nearest query, SQLite, 100,000 versions (filled in bulk through the real tables,
   :mod:`_bulk`), two layouts: one version per joint (50,000 candidates of the queried
   type) and 10 per joint (5,000 joints of that type; only their current versions rank).
   - warm: one process, repeated random requests (p50/p99), against the same distance
     computed by numpy over the candidate arrays already in memory;
   - cold: the first query of a fresh process (``Repository(...)`` opened first, not
     timed; and the ``jointdb query`` path, opening included), goal <= 150 ms: with the
     shared on-disk cache current (any process since the last write has queried), and
     without it (``JOINTDB_QUERY_CACHE=off``: the first process after a write);
   - options: ``--all-versions`` (100k/2 candidates) and ``--label released`` warm.
   Goal: warm p99 <= 20 ms.
2. Catalogue one version (SQLite, WAL, synchronous=FULL, blob fsync'd and renamed
   atomically) against a bare durable write of the same blob bytes (write, fsync,
   rename, directory fsync), interleaved. Goal >= 40 versions/s.
3. ``jointdb query`` CPU time (getrusage of the children) on a 6-version database,
   against ``python -c pass``. Goal <= 0.35 s.

4. ``--pg URL``: PostgreSQL at ``--versions`` (default 1,000,000; 100,000 for a shorter run), one
   version per joint (half of them tool-holders: ~490k candidates), filled by COPY
   (:func:`_bulk.bulk_fill_copy`) into the schema ``jointdb_bench_rows_N`` of that server, which is
   kept for the next run (``--refill`` rebuilds it). Rows: ``jointdb query`` wall time of a fresh
   process with the shared query cache current, and the first one after a write (one version
   catalogued before each; the cache is updated from the previous generation), against
   ``python -c pass``, a bare psycopg connect + ``SELECT 1``, and a bare psycopg fetch of the same
   candidate rows; warm p50/p99 in one process; the candidate query's EXPLAIN (ANALYZE, BUFFERS)
   checked for temp (spilled) blocks with the query's work_mem and with the server default.
   Goals (issue 26): query <= 0.4 s with a current cache, <= 0.8 s after a write, warm p99 <= 40 ms.

``--check-old REV``: also run the query code of git revision REV (e.g. cd2eba3, before
the query index) on the same 100k databases and require identical answers.

Run: ``PYTHONPATH=. .venv/bin/python bench/bench_store_rows.py [--quick] [--check-old cd2eba3]``
PostgreSQL: ``PYTHONPATH=. OPENBLAS_NUM_THREADS=1 .venv/bin/python bench/bench_store_rows.py --pg
postgresql+psycopg://postgres@127.0.0.1:54330/postgres [--versions 100000]``
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
import uuid
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _bulk import bulk_fill  # noqa: E402
from _bench_pg_rows import bench_pg, candidate_arrays  # noqa: E402

from jointdb.store import Conditions, OutsideCatalogueWarning, Repository  # noqa: E402

HERE = Path(__file__).resolve().parent


def requests(n: int, seed: int = 3) -> list[Conditions]:
    rng = np.random.default_rng(seed)
    return [Conditions(("tungsten-carbide", "steel"), preload_n=float(rng.uniform(1e3, 5e4)),
                       torque_nm=float(np.exp(rng.uniform(math.log(5), math.log(300)))),
                       geometry={"diameter_m": float(rng.uniform(0.006, 0.04))}) for _ in range(n)]


def numpy_reference(cand, req: Conditions, k: int) -> np.ndarray:
    """The distance by plain numpy over arrays in memory, and the k best (the issue's reference)."""
    def log_term(x, r):
        lx = np.log(x)
        return np.abs(lx - math.log(r)) / max(lx.max() - lx.min(), math.log(2))
    d_t = log_term(cand.torque, req.torque_nm)
    d_p = log_term(cand.preload, req.preload_n)
    dia = cand.geometry["diameter_m"]
    d_g = np.abs(dia - req.geometry["diameter_m"]) / np.maximum(dia, req.geometry["diameter_m"])
    want = json.dumps(sorted(req.materials))
    d_m = np.array([0.0 if m == want else 0.5 for m in cand.materials])[cand.materials_index]
    return np.argsort(np.sqrt(d_t**2 + d_p**2 + d_m**2 + d_g**2), kind="stable")[:k]


def timed_nearest(repo, req, **kw):
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", OutsideCatalogueWarning)
        out = repo.nearest("tool-holder", req, k=5, **kw)
    return time.perf_counter() - t0, out


COLD = r"""
import sys, time, warnings, json
t_start = time.perf_counter()
from jointdb.store import Conditions, Repository
from jointdb.store._light import nearest_in_file
from pathlib import Path
t_import = time.perf_counter()
req = Conditions(("tungsten-carbide", "steel"), preload_n=2e4, torque_nm=40.0, geometry={"diameter_m": 0.02})
warnings.simplefilter("ignore")
if sys.argv[2] == "repo":
    repo = Repository(sys.argv[1])
    t0 = time.perf_counter()
    m = repo.nearest("tool-holder", req, k=5)
else:
    t0 = time.perf_counter()
    m = nearest_in_file(Path(sys.argv[1]), "tool-holder", req, k=5)
t1 = time.perf_counter()
print(json.dumps({"first_query_s": t1 - t0, "import_s": t_import - t_start, "n": len(m)}))
"""


def cold_runs(db: Path, mode: str, n: int, cache: str) -> list[float]:
    """First-query times of ``n`` fresh processes; ``cache``: the on-disk cache directory or ``off``."""
    out = []
    for _ in range(n):
        r = subprocess.run([sys.executable, "-c", COLD, str(db), mode], capture_output=True, text=True, check=True,
                           env=dict(os.environ, OPENBLAS_NUM_THREADS="1", JOINTDB_QUERY_CACHE=cache))
        out.append(json.loads(r.stdout)["first_query_s"])
    return out


def check_old(repo, rev: str, reqs) -> str:
    """Run the nearest query of git revision ``rev`` on ``repo``; answers must be identical."""
    import types

    src = subprocess.run(["git", "show", f"{rev}:jointdb/store/_query.py"], cwd=HERE.parent, capture_output=True,
                         text=True, check=True).stdout
    old = types.ModuleType("old_query")
    exec(compile(src, f"{rev}:_query.py", "exec"), old.__dict__)
    same = 0
    for req in reqs:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", OutsideCatalogueWarning)
            a = old.nearest(repo, "tool-holder", req, k=5)
            b = repo.nearest("tool-holder", req, k=5)
        key = lambda ms: [(m.version.name, m.version.version, m.distance, m.per_condition) for m in ms]  # noqa: E731
        if key(a) != key(b):
            raise SystemExit(f"old and new query differ for {req}: {key(a)} != {key(b)}")
        same += 1
    return f"identical to {rev} on {same} requests (names, versions, distances and terms compared exactly)"


def bench_query(root: Path, per_joint: int, n_warm: int, n_cold: int, old_rev: str | None) -> None:
    db = root / f"q-{per_joint}.sqlite"
    repo = Repository(db)
    t0 = time.perf_counter()
    bulk_fill(repo, 100_000, per_joint)
    t_fill = time.perf_counter() - t0
    reqs = requests(n_warm)
    timed_nearest(repo, reqs[0])  # fills this process's cache
    cand = candidate_arrays(repo)
    warm, ref = [], []
    for req in reqs:  # interleaved: both see the same machine load
        warm.append(timed_nearest(repo, req)[0])
        t1 = time.perf_counter()
        numpy_reference(cand, req, 5)
        ref.append(time.perf_counter() - t1)
    extra = {}
    for label, kw in (("--all-versions", {"all_versions": True}), ("--label released", {"label": "released"})):
        timed_nearest(repo, reqs[0], **kw)
        extra[label] = [timed_nearest(repo, r, **kw)[0] for r in reqs[: max(20, n_warm // 4)]]
    cache = str(root / f"qcache-{per_joint}")
    cold_runs(db, "file", 1, cache)  # the first process after the last write fills the shared cache
    cold = {"cold, shared on-disk cache current: Repository open, first query": cold_runs(db, "repo", n_cold, cache),
            "cold, shared on-disk cache current: jointdb query path": cold_runs(db, "file", n_cold, cache),
            "cold, no cache (first process after a write): Repository": cold_runs(db, "repo", n_cold, "off"),
            "cold, no cache (first process after a write): query path": cold_runs(db, "file", n_cold, "off")}
    ms = lambda xs, q=50: float(np.percentile(np.array(xs) * 1e3, q))  # noqa: E731
    ref_ms = ms(ref)
    print(f"\nnearest, SQLite, 100,000 versions, {per_joint} per joint: {cand.version_id.size:,} current tool-holder "
          f"candidates (bulk fill {t_fill:.1f} s)")
    print(f"  reference: numpy over the candidate arrays in memory   p50 {ref_ms:7.2f} ms  p99 {ms(ref, 99):7.2f} ms")
    print(f"  warm (one process, n={len(warm)})                     p50 {ms(warm):7.2f} ms  p99 {ms(warm, 99):7.2f} ms"
          f"   p50 = {ms(warm) / ref_ms:4.2f}x reference   goal p99 <= 20 ms: {'met' if ms(warm, 99) <= 20 else 'NOT met'}")
    for label, xs in extra.items():
        print(f"  warm {label:18s} (n={len(xs)})              p50 {ms(xs):7.2f} ms  p99 {ms(xs, 99):7.2f} ms")
    for label, xs in cold.items():
        print(f"  {label:66s} median {ms(xs):7.1f} ms  max {max(xs) * 1e3:7.1f} ms  (n={len(xs)})"
              f"   {ms(xs) / ref_ms:5.1f}x reference   goal <= 150 ms: {'met' if max(xs) <= 0.150 else 'NOT met'}")
    if old_rev:
        print("  " + check_old(repo, old_rev, reqs[:5]))
    repo.close()


def bench_catalogue(root: Path, n: int) -> None:
    sys.path.insert(0, str(HERE))
    from bench_store import joint_frf

    from jointdb.store._blobs import write_frf_file

    repo = Repository(root / "cat.sqlite")
    frfs = [joint_frf(1e6 * (1 + i)) for i in range(n + 5)]
    for i in range(5):  # warm-up: first joint rows, engine, h5py
        repo.catalogue(f"J{i}", "tool-holder", frfs[i], Conditions(("steel",), torque_nm=10.0 + i), "spring-damper-planar")
    sample = root / "sample.h5"
    write_frf_file(sample, frfs[0])
    payload = sample.read_bytes()  # the blob file's bytes
    ref_dir = root / "ref"
    ref_dir.mkdir()
    cat, bare, cpu = [], [], []
    for i in range(5, n + 5):
        t0, c0 = time.perf_counter(), time.process_time()
        repo.catalogue(f"J{i % 10}", "tool-holder", frfs[i], Conditions(("steel",), torque_nm=10.0 + i),
                       "spring-damper-planar", quality={"residual": 1e-3}, force=True)
        cat.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
        t0 = time.perf_counter()
        tmp = ref_dir / f".tmp-{uuid.uuid4().hex}"
        with open(tmp, "wb") as fh:
            fh.write(payload)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, ref_dir / uuid.uuid4().hex)
        fd = os.open(ref_dir, os.O_RDONLY)
        os.fsync(fd)
        os.close(fd)
        bare.append(time.perf_counter() - t0)
    c, b = statistics.median(cat), statistics.median(bare)
    print(f"\ncatalogue one version (1000-line 2x2 FRF, {len(payload):,} blob bytes), SQLite WAL synchronous=FULL, n={n}")
    print(f"  reference: bare durable write of the same bytes (write, fsync, rename, dir fsync)  median {b * 1e3:6.2f} ms")
    print(f"  catalogue (blob fsync'd + renamed, row committed)   median {c * 1e3:6.2f} ms = {1 / c:5.1f} versions/s"
          f"   {c / b:4.1f}x reference   goal >= 40/s: {'met' if 1 / c >= 40 else 'NOT met'}")
    print(f"  (mean {statistics.mean(cat) * 1e3:.2f} ms = {1 / statistics.mean(cat):.1f} versions/s; CPU of this process "
          f"per version, all threads: median {statistics.median(cpu) * 1e3:.2f} ms)")
    repo.close()


def bench_cli(root: Path, repeat: int) -> None:
    sys.path.insert(0, str(HERE))
    from bench_cli_start import CLI, cpu_seconds
    from bench_store import joint_frf

    db = root / "six.sqlite"
    repo = Repository(db)
    for i, t in enumerate((20.0, 40.0, 80.0, 20.0, 40.0, 80.0)):
        repo.catalogue(f"th-{i // 3}-{t:.0f}", "tool-holder", joint_frf(1e6 * t), Conditions(("steel",), torque_nm=t),
                       "spring-damper-planar")
    repo.close()
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    py = sys.executable
    rows = {"python -c pass": [py, "-c", "pass"],
            "jointdb query": [py, "-c", CLI, "query", "--type", "tool-holder", "--torque", "35", "--db", str(db)]}
    times = {k: [] for k in rows}
    for _ in range(repeat):
        for k, cmd in rows.items():
            times[k].append(cpu_seconds(cmd, env))
    ref, q = statistics.median(times["python -c pass"]), statistics.median(times["jointdb query"])
    print(f"\n`jointdb query` on a 6-version database, CPU (user+system) median of {repeat} fresh processes")
    print(f"  reference: python -c pass {ref:.3f} s")
    print(f"  jointdb query             {q:.3f} s = {q / ref:4.1f}x reference   goal <= 0.35 s: "
          f"{'met' if q <= 0.35 else 'NOT met'}")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--check-old", metavar="REV", help="compare with the query code of this git revision")
    ap.add_argument("--only", choices=("query", "catalogue", "cli"))
    ap.add_argument("--pg", metavar="URL", help="run only the PostgreSQL rows, on this server")
    ap.add_argument("--versions", type=int, default=1_000_000, help="versions in the PostgreSQL database")
    ap.add_argument("--refill", action="store_true", help="rebuild the kept PostgreSQL bench schema")
    ap.add_argument("--check-index", action="store_true", help="after filling, compare the index with history")
    args = ap.parse_args(argv)
    print(f"bench_store_rows  {time.strftime('%Y-%m-%dT%H:%MZ', time.gmtime())}  python {sys.version.split()[0]}  "
          f"numpy {np.__version__}  cpus {os.cpu_count()}  load {os.getloadavg()[0]:.1f}")
    with tempfile.TemporaryDirectory(prefix="jointdb-bench-", dir=os.environ.get("BENCH_TMP")) as tmp:
        root = Path(tmp)
        if args.pg:
            bench_pg(args.pg, args.versions, root, quick=args.quick, refill=args.refill,
                     check_index=args.check_index, requests=requests, reference=numpy_reference)
            return
        if args.only in (None, "catalogue"):
            bench_catalogue(root, 30 if args.quick else 100)
        if args.only in (None, "cli"):
            bench_cli(root, 5 if args.quick else 9)
        if args.only in (None, "query"):
            for per_joint in (1, 10):
                bench_query(root, per_joint, 50 if args.quick else 200, 3 if args.quick else 7, args.check_old)


if __name__ == "__main__":
    main()
