"""Benchmark of the joint database (SQLite): catalogue throughput, nearest-query latency.

Prints numbers and ratios against references measured in the same process:

1. Catalogue throughput: versions per second for a typical joint FRF
   (1,000 lines, 2×2), compared with the cost of one bare durable file write
   (write + fsync + rename + directory fsync) of the same FRF's bytes: the
   floor any durable store pays.
2. Nearest-query latency: see ``bench/bench_store_rows.py`` (100,000 versions filled
   in bulk through the real tables, the query index, warm and cold, against numpy).

3. With ``--pg URL`` also catalogue throughput on PostgreSQL with the blobs in the
   database (``blobs="database"``: blob and row in one transaction, one commit), in a
   fresh schema that is dropped afterwards, against a bare durable ``INSERT`` + ``COMMIT``
   of the same blob bytes into a plain table (``synchronous_commit`` as the server has it,
   printed), with the client's CPU time, the SQL statements and the round trips (psycopg
   waits for the server) per version (:mod:`bench._pgwrite`).
4. With ``--compare REV`` (a git revision, e.g. the main branch before a change) the
   catalogues of 1 and 3 run on that revision's code (``git archive`` into a temporary
   directory) and on this tree's, in two processes set up side by side that take turns in
   blocks of 10 versions (who goes first alternates; every version a new FRF), ``--rounds``
   rounds (default 3) of 100 (SQLite) and 200 (PostgreSQL) versions each; per round the
   ratio old/new of the total times, with the load average before and after.

Run: ``.venv/bin/python bench/bench_store.py [--quick] [--pg postgresql+psycopg://...]
[--compare REV [--rounds N]]``.
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
import uuid
from pathlib import Path

import numpy as np

from jointdb.frf import FRF
from jointdb.store import Conditions, Repository

TYPES = ("tool-holder", "holder-spindle")
MATERIAL_SETS = (["tungsten-carbide", "steel"], ["steel", "steel"], ["hardened-steel", "steel"])


def joint_frf(k: float, n: int = 1000) -> FRF:
    f = np.linspace(10.0, 5000.0, n)
    w = 2 * np.pi * f
    h = np.zeros((n, 2, 2), complex)
    h[:, 0, 0] = 1 / (k + 1j * w * 100.0)
    h[:, 1, 1] = 1 / (k / 25 + 1j * w * 80.0)
    return FRF(f, h, ["3x", "3ry"], ["3x", "3ry"])


def bare_durable_write(directory: Path, payload: bytes) -> None:
    tmp = directory / f".tmp-{uuid.uuid4().hex}"
    with open(tmp, "wb") as fh:
        fh.write(payload)
        fh.flush()
        os.fsync(fh.fileno())
    final = directory / uuid.uuid4().hex
    os.replace(tmp, final)
    fd = os.open(directory, os.O_RDONLY)
    os.fsync(fd)
    os.close(fd)


def bench_catalogue(root: Path, n: int, url: str | None = None, blobs=None, what: str = "SQLite") -> None:
    repo = Repository(url or root / "cat.sqlite", blobs=blobs)
    frfs = [joint_frf(1e6 * (1 + i)) for i in range(n)]
    t0 = time.perf_counter()
    for i, frf in enumerate(frfs):
        repo.catalogue(f"J{i % 10}", "tool-holder", frf, Conditions(("steel",), torque_nm=10.0 + i),
                       "spring-damper-planar", quality={"residual": 1e-3}, force=True)
    t_cat = (time.perf_counter() - t0) / n
    ref_dir = root / "ref"
    ref_dir.mkdir()
    payload = frfs[0].values.tobytes() + frfs[0].freq.tobytes()
    t0 = time.perf_counter()
    for _ in range(n):
        bare_durable_write(ref_dir, payload)
    t_ref = (time.perf_counter() - t0) / n
    frf_read = []
    jv = repo.get("J0")
    for _ in range(20):
        t0 = time.perf_counter()
        repo.load_frf(jv)
        frf_read.append(time.perf_counter() - t0)
    print(f"catalogue ({what}): {n} versions of a 1000-line 2x2 joint FRF")
    print(f"  {1 / t_cat:8.1f} versions/s  ({t_cat * 1e3:.1f} ms each: blob write+fsync+verify, row commit)")
    print(f"  reference bare durable write of the raw bytes: {t_ref * 1e3:.1f} ms -> ratio {t_cat / t_ref:.1f}x")
    print(f"  verified read (load_frf) median {np.median(frf_read) * 1e3:.1f} ms")
    repo.close()


def main() -> None:
    args = sys.argv[1:]
    quick = "--quick" in args
    pg = args[args.index("--pg") + 1] if "--pg" in args else None
    if "--compare" in args:
        from _pgwrite import compare

        rounds = int(args[args.index("--rounds") + 1]) if "--rounds" in args else 3
        compare(args[args.index("--compare") + 1], pg, rounds, 30 if quick else 100, 30 if quick else 200)
        return
    with tempfile.TemporaryDirectory(prefix="jointdb-bench-") as tmp:
        root = Path(tmp)
        bench_catalogue(root, 30 if quick else 100)
        if pg:
            from _pgwrite import bench_catalogue_pg

            bench_catalogue_pg(root / "pg", pg, 30 if quick else 200)


if __name__ == "__main__":
    main()
