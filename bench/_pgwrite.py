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
on the code of git revision ``rev`` and on this tree, in two processes set up side by side
that run it in turns, blocks of 10 versions each (who goes first alternates), so that a loaded
machine affects both alike; a round's ratio is total time old / total time new.
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
    """SQL statements (every ``execute`` / ``executemany`` of a psycopg cursor: SQLAlchemy's and those
    sent in a pipeline; BEGIN and COMMIT are not counted) and round trips, while ``on``."""

    def __init__(self):
        import psycopg
        import psycopg._cursor_base as cursor_base
        import psycopg._pipeline_base as pipeline_base
        import psycopg.generators as generators

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

        def statement(name):
            real = getattr(psycopg.Cursor, name)

            def wrapper(*args, **kwargs):
                if self.on:
                    self.statements += 1
                return real(*args, **kwargs)

            setattr(psycopg.Cursor, name, wrapper)

        statement("execute")
        statement("executemany")


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


def _steppers(n: int, base: str, stack) -> dict:
    """``{what: step(i)}``: one catalogue call each, SQLite (blobs in files) and, with ``base``,
    PostgreSQL (blobs in the database, a fresh schema; ``ref``: the bare INSERT + COMMIT reference
    on a psycopg connection of its own), each catalogue warmed with 10 versions first."""
    from bench_store import joint_frf

    from jointdb.store import Conditions, Repository, upgrade

    frfs = [joint_frf(1e6 * (1 + i)) for i in range(n + 10)]  # every version a new FRF (a new blob)
    tmp = stack.enter_context(tempfile.TemporaryDirectory(prefix="jointdb-bench-"))
    repos = {"sqlite": Repository(Path(tmp) / "cat.sqlite")}
    if base:
        url, schema = stack.enter_context(fresh_schema(base))
        upgrade(url)
        repos["pg"] = Repository(url, blobs="database")
    steps = {}
    for what, repo in repos.items():
        stack.callback(repo.close)

        def step(i: int, repo=repo) -> None:
            repo.catalogue(f"J{i % 10}", "tool-holder", frfs[i], Conditions(("steel",), torque_nm=10.0 + i),
                           "spring-damper-planar", quality={"residual": 1e-3}, force=True)

        steps[what] = step
    if base:
        steps["ref"] = _bare_insert(stack, base, schema, frfs[:n])
    for what, step in steps.items():
        for i in range(n, n + 10):  # warm: joints exist, statements prepared, pool filled
            step(i)
    return steps


def _bare_insert(stack, base: str, schema: str, frfs: list):
    """The reference step: INSERT the blob bytes of an FRF into a plain table and COMMIT."""
    import psycopg

    from jointdb.store._blobformat import blob_bytes

    payloads = [blob_bytes(f) for f in frfs]
    dsn = base.replace("postgresql+psycopg://", "postgresql://", 1)
    conn = stack.enter_context(psycopg.connect(dsn, options=f"-csearch_path={schema}"))
    conn.execute("CREATE TABLE bench_ref (sha256 varchar(80) PRIMARY KEY, data bytea NOT NULL)")
    conn.commit()

    def bare(i: int) -> None:
        digest, data = payloads[i % len(payloads)]  # (the table's key is new every time)
        conn.execute("INSERT INTO bench_ref (sha256, data) VALUES (%s, %s)", (f"{i}-{digest}", data))
        conn.commit()

    return bare


def _serve(n: int, base: str) -> None:
    """A comparison's child: set up (:func:`_steppers`, ``n`` versions at most), say where jointdb came
    from, then answer each line ``<what> <start> <count>`` from stdin with one JSON line of :func:`_timed`."""
    from contextlib import ExitStack

    import jointdb

    counts = Counts()
    with ExitStack() as stack:
        steps = _steppers(n, base, stack)
        print(json.dumps({"jointdb": jointdb.__file__}), flush=True)
        for line in sys.stdin:
            what, start, count = line.split()
            start, count = int(start), int(count)
            print(json.dumps(_timed(counts, count, lambda i: steps[what](start + i))), flush=True)


def compare(rev: str, base: str | None, rounds: int, n_sqlite: int, n_pg: int, block: int = 10) -> None:
    """Compare git revision ``rev`` with this tree (module docstring): two child processes, one per
    code tree, set up side by side; each measurement is split into blocks of ``block`` versions
    run by the two in turn (who goes first alternates), so that both see the same load."""
    tree = BENCH.parent
    with tempfile.TemporaryDirectory(prefix="jointdb-before-") as before:
        archive = subprocess.run(["git", "-C", str(tree), "archive", rev, "jointdb", "migrations"], check=True,
                                 capture_output=True).stdout
        subprocess.run(["tar", "-x", "-C", before], input=archive, check=True)
        commit = subprocess.run(["git", "-C", str(tree), "rev-parse", "--short", rev], check=True,
                                capture_output=True, text=True).stdout.strip()
        print(f"load average before: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
        trees = {"before": before, "after": str(tree)}
        kids = {}
        try:
            for label, code in trees.items():
                env = {**os.environ, "PYTHONPATH": code, "OPENBLAS_NUM_THREADS": "1"}
                cmd = [sys.executable, str(BENCH / "_pgwrite.py"), str(rounds * max(n_sqlite, n_pg)), base or ""]
                kids[label] = subprocess.Popen(cmd, env=env, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
            for label, code in trees.items():
                hello = kids[label].stdout.readline()
                if not hello:
                    raise RuntimeError(f"the {label} child failed to start (its error is above)")
                where = json.loads(hello)["jointdb"]
                if not Path(where).resolve().is_relative_to(Path(code).resolve()):
                    raise RuntimeError(f"the {label} run imported jointdb from {where}, not {code}")
            _alternate(kids, commit, base, rounds, n_sqlite, n_pg, block)
        finally:
            for kid in kids.values():
                kid.stdin.close()
                kid.wait(timeout=300)
        print(f"load average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")


def _ask(kid, what: str, start: int, count: int) -> dict:
    kid.stdin.write(f"{what} {start} {count}\n")
    kid.stdin.flush()
    line = kid.stdout.readline()
    if not line:
        raise RuntimeError("a child of the comparison died (its error is above)")
    return json.loads(line)


def _alternate(kids: dict, commit: str, base, rounds: int, n_sqlite: int, n_pg: int, block: int) -> None:
    """Run the blocks of :func:`compare`; print each round and the summary."""
    whats = [("sqlite", n_sqlite)] + ([("pg", n_pg), ("ref", n_pg)] if base else [])
    totals: dict = {}
    blocks: dict = {}  # what -> [old/new time ratio of each block pair]
    for r in range(rounds):
        per: dict = {}
        for what, n in whats:
            for b, start in enumerate(range(r * n, (r + 1) * n, block)):
                count = min(block, (r + 1) * n - start)
                pair = {}
                for label in (("before", "after") if (b + r) % 2 == 0 else ("after", "before")):
                    out = pair[label] = _ask(kids[label], what, start, count)
                    acc = per.setdefault((what, label), dict.fromkeys(("n", "ms", "cpu_ms", "statements", "trips"), 0))
                    acc["n"] += count
                    for key in ("ms", "cpu_ms", "statements", "trips"):
                        acc[key] += out[key] * count
                blocks.setdefault(what, []).append(pair["before"]["ms"] / pair["after"]["ms"])
        for key, acc in per.items():
            totals.setdefault(key, []).append(acc)
        print(f"round {r + 1}: " + " | ".join(_round_line(per, what, commit) for what, _ in whats), flush=True)
    for what, _ in whats:
        if what != "ref":
            pairs = list(zip(totals[(what, "before")], totals[(what, "after")]))
            ratios = sorted(b["ms"] / a["ms"] for b, a in pairs)
            rate = {label: [x["n"] / x["ms"] * 1e3 for x in totals[(what, label)]] for label in ("before", "after")}
            print(f"{_NAMES[what]}: {commit} {min(rate['before']):.1f}-{max(rate['before']):.1f}, this tree "
                  f"{min(rate['after']):.1f}-{max(rate['after']):.1f} versions/s; new/old {ratios[0]:.2f}-"
                  f"{ratios[-1]:.2f}x (median {ratios[len(ratios) // 2]:.2f}x); median of the "
                  f"{len(blocks[what])} block pairs {sorted(blocks[what])[len(blocks[what]) // 2]:.2f}x")


_NAMES = {"sqlite": "SQLite", "pg": "PostgreSQL"}


def _round_line(per: dict, what: str, commit: str) -> str:
    if what == "ref":
        ref = per[("ref", "after")]
        return f"bare INSERT+COMMIT {ref['ms'] / ref['n']:.2f} ms"
    parts = []
    for label, name in (("before", commit), ("after", "this tree")):
        x = per[(what, label)]
        sql = f", {x['statements'] / x['n']:.1f} statements, {x['trips'] / x['n']:.1f} round trips" if what == "pg" else ""
        parts.append(f"{name} {x['n'] / x['ms'] * 1e3:.1f}/s (CPU {x['cpu_ms'] / x['n']:.2f} ms{sql})")
    ratio = per[(what, "before")]["ms"] / per[(what, "after")]["ms"]
    return f"{_NAMES[what]} " + ", ".join(parts) + f" = {ratio:.2f}x"


if __name__ == "__main__":
    _serve(int(sys.argv[1]), sys.argv[2])
