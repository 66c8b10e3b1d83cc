"""Catalogue throughput on PostgreSQL with the blobs in the database (``bench_store.py --pg``).

Measured in one process: ``n`` versions catalogued (``Repository.catalogue``, blobs in the
table ``frf_blobs``: blob and rows in one transaction, one durable commit), then the
reference: a bare ``INSERT`` of the same blob bytes into a plain table and its ``COMMIT``,
``n`` times, on one psycopg connection (the durable floor of writing those bytes to this
server). For both: wall time, the client process's CPU time (the server's is not in it),
SQL statements and round trips per version. A round trip is one exchange the client waits
for: psycopg's ``execute`` generator (a statement, or BEGIN / COMMIT) or one pipeline sync
(statements sent together, psycopg's ``executemany`` included), counted by wrapping them
while the loop runs.

``compare(rev, ...)``: the same measurement (and the SQLite catalogue of ``bench_store.py``)
run alternately on the code of git revision ``rev`` and on this tree, each run in a process
of its own, so that a loaded machine affects both alike.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
import uuid
from contextlib import contextmanager
from pathlib import Path

BENCH = Path(__file__).resolve().parent


class Counts:
    """SQL statements (SQLAlchemy's, plus the driver's own) and round trips, while ``on``."""

    def __init__(self):
        import psycopg._cursor_base as cursor_base
        import psycopg._pipeline_base as pipeline_base
        import psycopg.generators as generators
        from sqlalchemy import engine, event

        self.on, self.statements, self.trips = False, 0, 0

        def counted(module, name):
            real = getattr(module, name)

            def wrapper(*args, **kwargs):
                if self.on:
                    self.trips += 1
                return real(*args, **kwargs)

            setattr(module, name, wrapper)

        counted(cursor_base, "execute")  # a statement (pool pre-ping included)
        counted(generators, "execute")  # BEGIN, COMMIT, ROLLBACK (the connection's own commands)
        counted(pipeline_base.BasePipeline, "_sync_gen")  # a pipeline's sync (its statements: one trip)
        counted(pipeline_base.BasePipeline, "_exit_gen")  # the sync on leaving a pipeline

        @event.listens_for(engine.Engine, "before_cursor_execute")
        def statement(*_):
            if self.on:
                self.statements += 1


@contextmanager
def fresh_schema(base: str):
    """A new schema on the server ``base``; yields the URL that uses it; dropped afterwards."""
    import sqlalchemy as sa

    from jointdb.store._guards import event_trigger_names, guard_function

    schema = "bench_" + uuid.uuid4().hex[:10]
    engine = sa.create_engine(base)
    with engine.begin() as conn:
        conn.exec_driver_sql(f"CREATE SCHEMA {schema}")
    try:
        yield f"{base}{'&' if '?' in base else '?'}options=-csearch_path%3D{schema}", schema
    finally:
        with engine.begin() as conn:  # the DDL guard a superuser migration installed refuses the drop
            for name in event_trigger_names(schema):
                conn.exec_driver_sql(f'DROP EVENT TRIGGER IF EXISTS "{name}"')
            conn.exec_driver_sql(f"DROP FUNCTION IF EXISTS {guard_function(schema)}()")
            conn.exec_driver_sql(f"DROP SCHEMA {schema} CASCADE")
        engine.dispose()


def _timed(counts: Counts, n: int, step) -> dict:
    counts.statements = counts.trips = 0
    counts.on = True
    t0, c0 = time.perf_counter(), time.process_time()
    for i in range(n):
        step(i)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    counts.on = False
    return {"per_s": n / wall, "ms": wall / n * 1e3, "cpu_ms": cpu / n * 1e3,
            "statements": counts.statements / n, "trips": counts.trips / n}


def measure_pg(base: str, n: int, counts: Counts) -> dict:
    """The catalogue and the bare INSERT + COMMIT reference (module docstring), in a fresh schema."""
    import psycopg
    from bench_store import joint_frf

    from jointdb.store import Conditions, Repository, upgrade
    from jointdb.store._blobformat import blob_bytes

    frfs = [joint_frf(1e6 * (1 + i)) for i in range(n + 10)]
    with fresh_schema(base) as (url, schema):
        upgrade(url)
        repo = Repository(url, blobs="database")

        def catalogue(i: int) -> None:
            repo.catalogue(f"J{i % 10}", "tool-holder", frfs[i], Conditions(("steel",), torque_nm=10.0 + i),
                           "spring-damper-planar", quality={"residual": 1e-3}, force=True)

        for i in range(n, n + 10):  # warm: joints exist, statements prepared, pool filled
            catalogue(i)
        out = {"catalogue": _timed(counts, n, catalogue)}
        repo.close()
        payloads = [blob_bytes(f) for f in frfs[:n]]
        dsn = base.replace("postgresql+psycopg://", "postgresql://", 1)
        with psycopg.connect(dsn, options=f"-csearch_path={schema}") as conn:
            conn.execute("CREATE TABLE bench_ref (sha256 varchar(64) PRIMARY KEY, data bytea NOT NULL)")
            conn.commit()
            out["synchronous_commit"] = conn.execute("SHOW synchronous_commit").fetchone()[0]

            def bare(i: int) -> None:
                conn.execute("INSERT INTO bench_ref (sha256, data) VALUES (%s, %s)", payloads[i])
                conn.commit()

            out["reference"] = _timed(counts, n, bare)
    return out


def measure_sqlite(n: int) -> dict:
    """The SQLite catalogue of ``bench_store.py`` (blobs in files), its CPU time too."""
    from bench_store import joint_frf

    from jointdb.store import Conditions, Repository

    frfs = [joint_frf(1e6 * (1 + i)) for i in range(n)]
    with tempfile.TemporaryDirectory(prefix="jointdb-bench-") as tmp:
        repo = Repository(Path(tmp) / "cat.sqlite")
        t0, c0 = time.perf_counter(), time.process_time()
        for i, frf in enumerate(frfs):
            repo.catalogue(f"J{i % 10}", "tool-holder", frf, Conditions(("steel",), torque_nm=10.0 + i),
                           "spring-damper-planar", quality={"residual": 1e-3}, force=True)
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        repo.close()
    return {"per_s": n / wall, "ms": wall / n * 1e3, "cpu_ms": cpu / n * 1e3}


def print_pg(out: dict, n: int) -> None:
    cat, ref = out["catalogue"], out["reference"]
    print(f"catalogue (PostgreSQL, blobs in the database): {n} versions of a 1000-line 2x2 joint FRF")
    print(f"  {cat['per_s']:8.1f} versions/s  ({cat['ms']:.1f} ms each; client CPU {cat['cpu_ms']:.2f} ms; "
          f"{cat['statements']:.1f} statements, {cat['trips']:.1f} round trips per version)")
    print(f"  reference bare INSERT + COMMIT of the same bytes (synchronous_commit={out['synchronous_commit']}): "
          f"{ref['ms']:.2f} ms ({ref['trips']:.1f} round trips; client CPU {ref['cpu_ms']:.2f} ms) "
          f"-> ratio {cat['ms'] / ref['ms']:.1f}x")


def bench_catalogue_pg(root: Path, base: str, n: int) -> None:
    """Print the PostgreSQL catalogue measurement (``root`` is unused: everything is in the database)."""
    print_pg(measure_pg(base, n, Counts()), n)


def compare(rev: str, base: str | None, rounds: int, n_sqlite: int, n_pg: int) -> None:
    """Alternate the measurements between git revision ``rev`` and this tree (module docstring)."""
    tree = BENCH.parent
    with tempfile.TemporaryDirectory(prefix="jointdb-before-") as before:
        archive = subprocess.run(["git", "-C", str(tree), "archive", rev, "jointdb", "migrations"], check=True,
                                 capture_output=True).stdout
        subprocess.run(["tar", "-x", "-C", before], input=archive, check=True)
        commit = subprocess.run(["git", "-C", str(tree), "rev-parse", "--short", rev], check=True,
                                capture_output=True, text=True).stdout.strip()
        print(f"load average before: {os.getloadavg()[0]:.2f} {os.getloadavg()[1]:.2f} {os.getloadavg()[2]:.2f}")
        results: dict[str, list] = {"before": [], "after": []}
        for r in range(rounds):
            for label, code in (("before", before), ("after", str(tree))):
                env = {**os.environ, "PYTHONPATH": code, "OPENBLAS_NUM_THREADS": "1"}
                cmd = [sys.executable, str(BENCH / "_pgwrite.py"), str(n_sqlite), str(n_pg), base or ""]
                run = subprocess.run(cmd, env=env, capture_output=True, text=True)
                if run.returncode:
                    raise RuntimeError(f"the {label} run failed:\n{run.stderr[-3000:]}")
                out = json.loads(run.stdout.splitlines()[-1])
                if not Path(out["jointdb"]).resolve().is_relative_to(Path(code).resolve()):
                    raise RuntimeError(f"the {label} run imported jointdb from {out['jointdb']}, not {code}")
                results[label].append(out)
                line = f"round {r + 1} {label:6s} ({commit if label == 'before' else 'this tree'}): SQLite " \
                       f"{out['sqlite']['per_s']:6.1f} versions/s (CPU {out['sqlite']['cpu_ms']:.2f} ms)"
                if base:
                    cat, ref = out["pg"]["catalogue"], out["pg"]["reference"]
                    line += (f" | PostgreSQL {cat['per_s']:6.1f} versions/s, CPU {cat['cpu_ms']:.2f} ms, "
                             f"{cat['statements']:.1f} statements, {cat['trips']:.1f} round trips; bare "
                             f"INSERT+COMMIT {ref['ms']:.2f} ms -> {cat['ms'] / ref['ms']:.1f}x")
                print(line, flush=True)
        print(f"load average after: {os.getloadavg()[0]:.2f} {os.getloadavg()[1]:.2f} {os.getloadavg()[2]:.2f}")
        for what in (["sqlite"] + (["pg"] if base else [])):
            pick = (lambda o: o["sqlite"]) if what == "sqlite" else (lambda o: o["pg"]["catalogue"])
            b = [pick(o)["per_s"] for o in results["before"]]
            a = [pick(o)["per_s"] for o in results["after"]]
            print(f"{'SQLite' if what == 'sqlite' else 'PostgreSQL'}: before {min(b):.1f}-{max(b):.1f}, "
                  f"after {min(a):.1f}-{max(a):.1f} versions/s (median ratio "
                  f"{sorted(a)[len(a) // 2] / sorted(b)[len(b) // 2]:.2f}x)")


def _child(n_sqlite: int, n_pg: int, base: str) -> None:
    """One run of a comparison: JSON on the last line of stdout."""
    import jointdb

    out = {"jointdb": jointdb.__file__, "sqlite": measure_sqlite(n_sqlite)}
    if base:
        out["pg"] = measure_pg(base, n_pg, Counts())
    print(json.dumps(out))


if __name__ == "__main__":
    _child(int(sys.argv[1]), int(sys.argv[2]), sys.argv[3])
