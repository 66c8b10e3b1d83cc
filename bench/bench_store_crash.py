"""Crash figures of the joint database: SIGKILL a cataloguing process mid-write, many times.

For each backend (SQLite always; PostgreSQL when ``JOINTDB_TEST_PG_URL`` is set,
in a fresh schema that is dropped afterwards) a forked child catalogues versions
(joint FRF + raw measurement, 2,000 lines) in a loop and is killed with SIGKILL
after a random 0-0.6 s; then the database is checked: every row's record hash,
gapless numbering, every committed version's blobs read and hashed, the
immutability guards present, and nothing committed ever lost. Prints, per
backend: kills, versions committed, kills that left an unfinished write behind
(blob or temporary file without a row), and the number of failed checks (must be 0).

Run: ``.venv/bin/python bench/bench_store_crash.py [--kills N]`` (default 110 per backend).
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import os
import random
import signal
import sys
import tempfile
import time
import uuid
from pathlib import Path


def _child(url: str, blobs: str, seed: int, ready) -> None:
    import numpy as np

    from jointdb.frf import FRF
    from jointdb.store import Conditions, Repository

    repo = Repository(url, blobs=blobs)
    f = np.linspace(1.0, 4000.0, 2000)
    ready.set()
    i = 0
    while True:
        k = 1e6 * (1 + seed) + i
        h = np.zeros((f.size, 2, 2), complex)
        h[:, 0, 0] = 1 / (k + 2j * np.pi * f * 100.0)
        h[:, 1, 1] = 1 / (8e4 + 2j * np.pi * f * (80.0 + i))
        repo.catalogue(f"crash-{i % 3}", "tool-holder", FRF(f, h, ["3x", "3ry"], ["3x", "3ry"]),
                       Conditions(("steel",), torque_nm=10.0 + i, extra={"seed": seed, "i": i}),
                       "spring-damper-planar", raw_frfs={"tip": FRF(f, 2 * h, ["1x", "1ry"], ["1x", "1ry"])},
                       label="latest" if i % 2 else None, force=True)
        i += 1


def run(url: str, blobs: Path, kills: int, seed: int = 20261202) -> dict[str, int]:
    from jointdb.errors import NotFoundError
    from jointdb.store import Repository

    rng = random.Random(seed)
    ctx = mp.get_context("fork")
    committed = failures = interrupted = 0
    verified: set[str] = set()
    debris: set[str] = set()
    for it in range(kills):
        ready = ctx.Event()
        proc = ctx.Process(target=_child, args=(url, str(blobs), it, ready))
        proc.start()
        if not ready.wait(timeout=60):
            raise RuntimeError("child did not start")
        time.sleep(rng.uniform(0.0, 0.6))
        os.kill(proc.pid, signal.SIGKILL)
        proc.join(timeout=30)
        if proc.exitcode != -signal.SIGKILL:
            raise RuntimeError(f"child ended with {proc.exitcode}, not by the kill")
        repo = Repository(url, blobs=blobs)
        report = repo.check(verify_blobs=False)  # rows, record hashes, numbering, guards, blobs present
        failures += not report.ok
        if report.versions_checked < committed:
            failures += 1  # a committed version disappeared
        committed = report.versions_checked
        for j in range(3):
            try:
                hist = repo.history(f"crash-{j}")  # every read verifies the record hash
            except NotFoundError:
                continue
            failures += [v.version for v in hist] != list(range(1, len(hist) + 1))
            for v in hist:
                if v.uuid not in verified:
                    failures += any(repo.blobs.verify(d) is not None for d in (v.blob_sha256, *v.raw_blobs.values()))
                    verified.add(v.uuid)
        now = set(report.temporaries) | set(report.orphan_blobs)
        interrupted += bool(now - debris)
        debris |= now
        repo.close()
    final = Repository(url, blobs=blobs).check(verify_blobs=True)
    failures += not final.ok
    return {"kills": kills, "versions_committed": committed, "kills_mid_write": interrupted,
            "blobs_read_and_hashed": final.blobs_checked, "failed_checks": failures}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--kills", type=int, default=110)
    args = parser.parse_args()
    from jointdb.store import upgrade

    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        url = f"sqlite:///{root / 'crash.sqlite'}"
        upgrade(url)
        t0 = time.perf_counter()
        results["sqlite"] = run(url, root / "crash.sqlite.blobs", args.kills) | {"seconds": round(time.perf_counter() - t0)}
        pg = os.environ.get("JOINTDB_TEST_PG_URL")
        if pg:
            import sqlalchemy as sa

            from jointdb.store._guards import event_trigger_names, guard_function

            schema = "jt_crash_" + uuid.uuid4().hex[:8]
            admin = sa.create_engine(pg)
            with admin.begin() as conn:
                conn.exec_driver_sql(f"CREATE SCHEMA {schema}")
            pg_url = f"{pg}{'&' if '?' in pg else '?'}options=-csearch_path%3D{schema}"
            try:
                upgrade(pg_url)
                t0 = time.perf_counter()
                results["postgresql"] = run(pg_url, root / "pgblobs", args.kills) | {
                    "seconds": round(time.perf_counter() - t0)}
            finally:
                with admin.begin() as conn:
                    for name in event_trigger_names(schema):
                        conn.exec_driver_sql(f'DROP EVENT TRIGGER IF EXISTS "{name}"')
                    conn.exec_driver_sql(f"DROP FUNCTION IF EXISTS {guard_function(schema)}()")
                    conn.exec_driver_sql(f"DROP SCHEMA {schema} CASCADE")
                admin.dispose()
        else:
            print("postgresql: skipped (set JOINTDB_TEST_PG_URL to a server URL)")
    for backend, r in results.items():
        print(f"{backend}: {r['kills']} SIGKILLs, {r['versions_committed']} versions committed, "
              f"{r['kills_mid_write']} kills left an unfinished write, {r['blobs_read_and_hashed']} blobs read and "
              f"hashed at the end, {r['failed_checks']} failed checks ({r['seconds']} s)")
    return 1 if any(r["failed_checks"] for r in results.values()) else 0


if __name__ == "__main__":
    sys.exit(main())
