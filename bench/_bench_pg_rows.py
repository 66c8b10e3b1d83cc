"""The PostgreSQL rows of ``bench_store_rows.py --pg URL`` (issue 26 item 3; see that script's docstring).

Every time is the wall time of a fresh process (``python -m jointdb query`` from the repository,
as a user runs it) unless said otherwise; references run interleaved with them in the same run.
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import time
import uuid
import warnings
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
REQUEST = ["--type", "tool-holder", "--material", "tungsten-carbide+steel", "--torque", "40", "--preload", "20000",
           "--geometry", "diameter_m=0.02", "-k", "5"]
#: the rows of the default selection as a plain client would fetch them (the issue's "before": fetchall)
BARE_SQL = ("SELECT q.version_id, q.joint_id, q.version, q.torque_nm, q.preload_n, q.materials, g.value "
            "FROM query_versions q LEFT JOIN query_geometry g ON g.key = 'diameter_m' AND g.version_id = q.version_id "
            "WHERE q.joint_type = 'tool-holder' AND q.newest_active")
BARE = r"""
import json, sys, psycopg
with psycopg.connect("", **json.loads(sys.argv[1])) as c:
    rows = c.execute(sys.argv[2]).fetchall()
print(len(rows))
"""


def _schema_url(base: str, schema: str) -> str:
    return f"{base}{'&' if '?' in base else '?'}options=-csearch_path%3D{schema}"


def _drop(conn, schema: str) -> None:
    from jointdb.store._guards import event_trigger_names, guard_function

    for name in event_trigger_names(schema):
        conn.execute(f'DROP EVENT TRIGGER IF EXISTS "{name}"')
    conn.execute(f"DROP FUNCTION IF EXISTS {guard_function(schema)}()")
    conn.execute(f"DROP SCHEMA {schema} CASCADE")


def prepare(base: str, n: int, refill: bool, check_index: bool) -> tuple[str, str]:
    """The URL of the kept bench schema with ``n`` versions (filled now if missing, stale or asked)."""
    import psycopg
    from _bulk import bulk_fill_copy

    from jointdb.store import upgrade
    from jointdb.store._light import _libpq
    from jointdb.store._sqlitefile import HEAD_REVISION

    schema = f"jointdb_bench_rows_{n}"
    url = _schema_url(base, schema)
    info, kw = _libpq(base)
    with psycopg.connect(info, autocommit=True, **kw) as conn:
        exists = conn.execute("SELECT 1 FROM pg_namespace WHERE nspname = %s", [schema]).fetchone() is not None
        if exists and not refill:
            try:
                rev = conn.execute(f"SELECT version_num FROM {schema}.alembic_version").fetchone()
                count = conn.execute(f"SELECT count(*) FROM {schema}.joint_versions").fetchone()[0]
                if rev == (HEAD_REVISION,) and count >= n:
                    return url, f"kept schema {schema} ({count:,} versions)"
            except psycopg.Error:
                pass
        if exists:
            _drop(conn, schema)
        conn.execute(f"CREATE SCHEMA {schema}")
    t0 = time.perf_counter()
    upgrade(url)
    bulk_fill_copy(url, n, 1)
    note = f"filled schema {schema} by COPY in {time.perf_counter() - t0:.0f} s"
    if check_index:
        import sqlalchemy as sa

        from jointdb.store._index import index_problems

        engine = sa.create_engine(url)
        with engine.connect() as conn:
            problems = index_problems(conn)
        engine.dispose()
        if problems:
            raise SystemExit("bulk index differs from history: " + "; ".join(problems[:3]))
        note += "; index == recomputed from history (db check)"
    return url, note


def _run(cmd: list[str], env: dict) -> float:
    t0 = time.perf_counter()
    r = subprocess.run(cmd, cwd=REPO, env=env, capture_output=True, text=True)
    dt = time.perf_counter() - t0
    if r.returncode:
        raise SystemExit(f"{' '.join(cmd[:4])} failed: {r.stderr.strip()[-500:]}")
    return dt


def explain(url: str, work_mem: str | None) -> tuple[bool, str]:
    """``(spilled, plan)`` of the default selection's candidate query (with the diameter key) as the
    query path runs it, with ``work_mem`` None: the server's default instead of the query's own."""
    from jointdb.store import _nearest
    from jointdb.store._light import open_postgres_reader
    from jointdb.store._nearest import Selection

    reader = open_postgres_reader(url)
    plans: list[str] = []
    real_rows = reader.rows

    def rows(sql, params=()):
        if sql.startswith("SELECT count(*)"):
            plans.extend(r[0] for r in real_rows("EXPLAIN (ANALYZE, BUFFERS) " + sql, params))
        if sql.startswith("SET LOCAL work_mem") and work_mem is None:
            return []
        return real_rows(sql, params)
    reader.rows = rows
    try:
        with reader.snapshot():
            _nearest._fetch(reader, Selection("tool-holder"), ["diameter_m"])
    finally:
        reader.conn.close()
    plan = "\n".join(plans)
    return "temp written" in plan or "temp read" in plan, plan


def _ms(xs, q=50) -> float:
    return float(np.percentile(np.array(xs) * 1e3, q))


def _line(label: str, xs: list[float], ref: float, goal: float | None = None) -> str:
    text = f"  {label:58s} median {_ms(xs):7.0f} ms  max {max(xs) * 1e3:7.0f} ms  (n={len(xs)})  {_ms(xs) / ref:5.2f}x ref"
    if goal is not None:
        text += f"   goal <= {goal * 1e3:.0f} ms: {'met' if statistics.median(xs) <= goal else 'NOT met'}"
    return text


def candidate_arrays(repo):
    """The current tool-holder candidates (with ``diameter_m``) as the nearest query holds them: the
    arrays the numpy reference ranks."""
    from jointdb.store._nearest import Reader, Selection, current_candidates

    raw = repo.read_engine.raw_connection()
    try:
        reader = Reader(raw, repo.read_engine.dialect.name)
        with reader.snapshot():
            return current_candidates(reader, repo.url, Selection("tool-holder"), ["diameter_m"])
    finally:
        raw.close()


def bench_pg(base: str, n: int, root: Path, *, quick: bool, refill: bool, check_index: bool,
             requests, reference) -> None:
    """All PostgreSQL rows (module docstring of bench_store_rows.py)."""
    sys.path.insert(0, str(HERE))
    from bench_store import joint_frf

    from jointdb.store import Conditions, OutsideCatalogueWarning, Repository
    url, note = prepare(base, n, refill, check_index)
    runs = 3 if quick else 7
    # as installed: byte code compiled once (a PYTHONDONTWRITEBYTECODE=1 shell would recompile jointdb every run)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env.update(OPENBLAS_NUM_THREADS="1", PYTHONPATH=str(REPO), JOINTDB_QUERY_CACHE=str(root / "qcache"))
    query = [sys.executable, "-m", "jointdb", "query", *REQUEST, "--db", url]
    from jointdb.store._light import _libpq

    bare = [sys.executable, "-c", BARE, json.dumps(_libpq(url)[1])]
    first = _run(query, env)  # the first query after the fill: no cache file yet
    spilled, _ = explain(url, None)
    no_spill, plan = explain(url, _nearest_work_mem())
    refs = {"python -c pass": [], "psycopg connect + SELECT 1": [], "bare psycopg fetchall of the candidates": []}
    cached, after, writes = [], [], []
    repo = Repository(url, blobs=root / "blobs")
    for i in range(runs):  # interleaved, so that every row sees the same load
        refs["python -c pass"].append(_run([sys.executable, "-c", "pass"], env))
        refs["psycopg connect + SELECT 1"].append(_run([*bare, "SELECT 1"], env))
        if i < max(2, runs // 2):
            refs["bare psycopg fetchall of the candidates"].append(
                _run([*bare, BARE_SQL], env))
        cached.append(_run(query, env))
        t0 = time.perf_counter()
        repo.catalogue(f"bench-w-{uuid.uuid4().hex[:12]}", "tool-holder", joint_frf(1e6 * (1 + i)),
                       Conditions(("steel",), torque_nm=10.0 + i, geometry={"diameter_m": 0.02}),
                       "spring-damper-planar")
        writes.append(time.perf_counter() - t0)
        after.append(_run(query, env))
    off = [_run(query, dict(env, JOINTDB_QUERY_CACHE="off")) for _ in range(1 if quick else 2)]
    reqs = requests(50 if quick else 200)
    warm, ref = [], []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", OutsideCatalogueWarning)
        repo.nearest("tool-holder", reqs[0], k=5)
        cand = candidate_arrays(repo)
        for req in reqs:
            t0 = time.perf_counter()
            repo.nearest("tool-holder", req, k=5)
            warm.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            reference(cand, req, 5)
            ref.append(time.perf_counter() - t0)
    repo.close()
    base_ref = _ms(refs["python -c pass"])
    print(f"\n`jointdb query` on PostgreSQL, {n:,} versions (1 per joint), {cand.version_id.size:,} current tool-holder "
          f"candidates; {note}; load {os.getloadavg()[0]:.1f}")
    print("  wall time of fresh processes; ref = `python -c pass` median")
    for label, xs in refs.items():
        print(_line(f"reference: {label}", xs, base_ref))
    print(_line("jointdb query, shared query cache current", cached, base_ref, 0.4))
    print(_line("jointdb query, first after a write (cache of the previous gen.)", after, base_ref, 0.8))
    print(_line("jointdb query, no cache (JOINTDB_QUERY_CACHE=off)", off, base_ref))
    print(f"  (first query after the fill, no cache file: {first * 1e3:.0f} ms; the writes between: catalogue one "
          f"version median {statistics.median(writes) * 1e3:.0f} ms)")
    print(f"  warm, one process (n={len(warm)}): p50 {_ms(warm):6.1f} ms  p99 {_ms(warm, 99):6.1f} ms   reference numpy "
          f"over the arrays p50 {_ms(ref):6.1f} ms  ({_ms(warm) / _ms(ref):4.2f}x)   goal p99 <= 40 ms: "
          f"{'met' if _ms(warm, 99) <= 40 else 'NOT met'}")
    print(f"  candidate query EXPLAIN (ANALYZE, BUFFERS): with the query's work_mem {_nearest_work_mem()}: "
          f"{'SPILLS' if no_spill else 'no temp blocks'}; with the server default: "
          f"{'temp blocks written (spills)' if spilled else 'no temp blocks'}")
    for line in plan.splitlines():
        if any(w in line for w in ("Hash", "Join", "Aggregate", "Execution Time", "temp", "Sort")):
            print("    " + line.strip())


def _nearest_work_mem() -> str:
    from jointdb.store._nearest import WORK_MEM

    return WORK_MEM
