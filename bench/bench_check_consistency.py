"""False alarms of ``jointdb db check`` while others write (issue 20, item 4).

On PostgreSQL (``JOINTDB_TEST_PG_URL``; a fresh schema, dropped afterwards) 16 writer
threads, each with its own repository, catalogue versions, move labels and deprecate in a
loop while the main thread runs ``check`` (guards, history chain, query index against
history, every version row) ``--checks`` times. Every problem a check reports is a false
alarm: nothing is damaged. ``--before`` also runs today's way of reading (index and history
in separate READ COMMITTED statements) for comparison. Prints one JSON line per mode.

Run: ``.venv/bin/python bench/bench_check_consistency.py [--checks 100] [--writers 16] [--before]``
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np


def _frf(seed: int):
    from jointdb.frf import FRF

    f = np.linspace(10.0, 2000.0, 32)
    k = 2e6 * (1 + 0.01 * seed)
    h = np.zeros((f.size, 2, 2), complex)
    h[:, 0, 0] = 1 / (k + 2j * np.pi * f * 100.0)
    h[:, 1, 1] = 1 / (8e4 + 2j * np.pi * f * 80.0)
    return FRF(f, h, ["3x", "3ry"], ["3x", "3ry"])


def _writer(url: str, blobs: Path, i: int, stop: threading.Event, counts: dict) -> None:
    from jointdb.errors import JointdbError
    from jointdb.store import Conditions, Repository

    repo = Repository(url, blobs=blobs)
    n = 0
    try:
        while not stop.is_set():
            name = f"W{i}-{n % 3}"
            try:
                v = repo.catalogue(name, "tool-holder", _frf(n), Conditions(materials=("steel",), torque_nm=40.0 + i),
                                   "spring-damper-planar")
                if n % 3 == 1:
                    repo.label(name, v.version, "released")
                if n % 5 == 4:
                    repo.deprecate(name, v.version, reason="bench")
            except JointdbError:
                counts["write_errors"] += 1
            n += 1
            counts["writes"] += 1
    finally:
        repo.close()


def _old_check(repo) -> list[str]:
    """Today's reading: guards and index in one connection (READ COMMITTED: each statement its own snapshot)."""
    from jointdb.store._index import index_problems

    with repo.read_engine.connect() as conn:
        return index_problems(conn)


def run(url: str, blobs: Path, writers: int = 16, checks: int = 100, before: bool = False) -> dict:
    """``{"checks": N, "false_alarms": n, "writes": w, ...}`` for one database (migrated here)."""
    from jointdb.store import Repository, upgrade
    from jointdb.store._maintenance import check

    upgrade(url)
    stop = threading.Event()
    counts = {"writes": 0, "write_errors": 0}
    threads = [threading.Thread(target=_writer, args=(url, blobs, i, stop, counts)) for i in range(writers)]
    for t in threads:
        t.start()
    repo = Repository(url, blobs=blobs)
    alarms, old_alarms, examples = 0, 0, []
    t0 = time.perf_counter()
    try:
        time.sleep(1.0)  # let the writers get going
        for _ in range(checks):
            try:
                problems = list(check(repo, verify_blobs=False).problems)
            except Exception as exc:  # noqa: BLE001 - a crash of the check is a false alarm too (counted)
                problems = [f"check raised {type(exc).__name__}"]
            if problems:
                alarms += 1
                examples += problems[:1]
            if before:
                try:
                    old_alarms += bool(_old_check(repo))
                except Exception:  # noqa: BLE001 - counted, like the check's own crash
                    old_alarms += 1
    finally:
        stop.set()
        for t in threads:
            t.join()
        final = check(repo, verify_blobs=True)
        repo.close()
    out = {"checks": checks, "writers": writers, "false_alarms": alarms, "writes_during": counts["writes"],
           "write_errors": counts["write_errors"], "seconds": round(time.perf_counter() - t0, 1),
           "final_check_ok": final.ok, "examples": examples[:3]}
    if before:
        out["false_alarms_separate_snapshots"] = old_alarms
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--checks", type=int, default=100)
    ap.add_argument("--writers", type=int, default=16)
    ap.add_argument("--before", action="store_true", help="also count alarms of separate-snapshot reads")
    args = ap.parse_args()
    base = os.environ.get("JOINTDB_TEST_PG_URL")
    if not base:
        print("JOINTDB_TEST_PG_URL is not set; this bench needs PostgreSQL (skipped)", file=sys.stderr)
        return 0
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "server"))
    from server_helpers import _pg_schema, drop_pg_schema  # the tests' schema helpers (DDL guard dropped first)

    admin, schema, url = _pg_schema(base)
    try:
        with tempfile.TemporaryDirectory() as tmp:
            result = run(url, Path(tmp) / "blobs", args.writers, args.checks, args.before)
        print(json.dumps({"backend": "postgresql", **result}))
    finally:
        drop_pg_schema(admin, schema)
        admin.dispose()
    return 0 if result["false_alarms"] == 0 and result["final_check_ok"] else 1


if __name__ == "__main__":
    sys.exit(main())
