"""Benchmark of the joint database (SQLite): catalogue throughput, nearest-query latency.

Prints numbers and ratios against references measured in the same process:

1. Catalogue throughput: versions per second for a typical joint FRF
   (1,000 lines, 2×2), compared with the cost of one bare durable file write
   (write + fsync + rename + directory fsync) of the same FRF's bytes: the
   floor any durable store pays.
2. Nearest-query latency (median and 99th percentile over random requests) at
   1,000 and 100,000 catalogued versions. Rows are bulk-inserted directly
   (no blob files exist at all, so a ranking that touched blobs would fail), in
   two layouts: every version its own joint (half of them, 50,000, are of the
   queried type) and 10 versions per joint (only current versions rank).
   "Cold" = a fresh Repository (a one-shot CLI call); "warm" = a long-lived
   one whose candidate arrays are cached while the append-only tables' row
   counts are unchanged. Reference: the same distance computed by numpy over
   arrays already in memory.

Run: ``.venv/bin/python bench/bench_store.py [--quick]``.
"""

from __future__ import annotations

import math
import os
import sys
import tempfile
import time
import uuid
import warnings
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from jointdb.frf import FRF
from jointdb.store import Conditions, OutsideCatalogueWarning, Repository

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


def bench_catalogue(root: Path, n: int) -> None:
    repo = Repository(root / "cat.sqlite")
    frfs = [joint_frf(1e6 * (1 + i)) for i in range(n)]
    t0 = time.perf_counter()
    for i, frf in enumerate(frfs):
        repo.catalogue(f"J{i % 10}", "tool-holder", frf, Conditions(("steel",), torque_nm=10.0 + i),
                       "spring-damper-planar", quality={"residual": 1e-3})
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
    print(f"catalogue: {n} versions of a 1000-line 2x2 joint FRF")
    print(f"  {1 / t_cat:8.1f} versions/s  ({t_cat * 1e3:.1f} ms each: blob write+fsync+verify, row commit)")
    print(f"  reference bare durable write of the raw bytes: {t_ref * 1e3:.1f} ms -> ratio {t_cat / t_ref:.1f}x")
    print(f"  verified read (load_frf) median {np.median(frf_read) * 1e3:.1f} ms")
    repo.close()


def bulk_fill(repo: Repository, n_versions: int, per_joint: int, rng: np.random.Generator) -> dict:
    """Insert rows directly (no blobs). Returns the arrays of the current versions for the reference."""
    from jointdb.store._models import JointRow, VersionRow

    n_joints = n_versions // per_joint
    now = datetime.now(timezone.utc)
    joints, versions = [], []
    for j in range(n_joints):
        joints.append({"id": j + 1, "name": f"bulk-{j:06d}", "joint_type": TYPES[j % 2], "created_at": now,
                       "created_by": "bench"})
        for v in range(1, per_joint + 1):
            versions.append({
                "joint_id": j + 1, "version": v, "uuid": str(uuid.uuid4()), "created_at": now, "author": "bench",
                "materials": MATERIAL_SETS[int(rng.integers(3))], "preload_n": float(rng.uniform(1e3, 5e4)),
                "torque_nm": float(np.exp(rng.uniform(math.log(5), math.log(300)))),
                "geometry": {"diameter_m": float(rng.uniform(0.006, 0.04))}, "extra": {},
                "model_kind": "spring-damper-planar", "dofs": ["3x", "3ry"], "quantity": "receptance",
                "n_freq": 1000, "freq_min_hz": 10.0, "freq_max_hz": 5000.0, "blob_sha256": "0" * 64,
                "raw_blobs": {}, "input_files": {}, "method": "bulk", "method_params": {},
                "software_version": "bench", "parent_version": v - 1 if v > 1 else None, "quality": {},
                "record_sha256": "0" * 64,
            })
    with repo.write_engine.begin() as conn:
        conn.execute(JointRow.__table__.insert(), joints)
        for i in range(0, len(versions), 20_000):
            conn.execute(VersionRow.__table__.insert(), versions[i:i + 20_000])
    cur = [v for v in versions if v["version"] == per_joint and joints[v["joint_id"] - 1]["joint_type"] == TYPES[0]]
    return {
        "torque": np.array([v["torque_nm"] for v in cur]),
        "preload": np.array([v["preload_n"] for v in cur]),
        "diameter": np.array([v["geometry"]["diameter_m"] for v in cur]),
        "materials": [tuple(sorted(v["materials"])) for v in cur],
    }


def reference_rank(arrays: dict, torque: float, preload: float, diameter: float, mats: tuple, k: int) -> np.ndarray:
    lt = np.log(arrays["torque"])
    lp = np.log(arrays["preload"])
    d_t = np.abs(lt - math.log(torque)) / max(lt.max() - lt.min(), math.log(2))
    d_p = np.abs(lp - math.log(preload)) / max(lp.max() - lp.min(), math.log(2))
    dia = arrays["diameter"]
    d_g = np.abs(dia - diameter) / np.maximum(dia, diameter)
    want = tuple(sorted(mats))
    d_m = np.array([0.0 if m == want else 0.5 for m in arrays["materials"]])
    return np.argsort(np.sqrt(d_t**2 + d_p**2 + d_g**2 + d_m**2))[:k]


def bench_query(root: Path, n_versions: int, per_joint: int, n_queries: int) -> None:
    rng = np.random.default_rng(7)
    repo = Repository(root / f"q{n_versions}-{per_joint}.sqlite")
    t0 = time.perf_counter()
    arrays = bulk_fill(repo, n_versions, per_joint, rng)
    t_fill = time.perf_counter() - t0
    def request():
        torque = float(np.exp(rng.uniform(math.log(5), math.log(300))))
        preload = float(rng.uniform(1e3, 5e4))
        dia = float(rng.uniform(0.006, 0.04))
        mats = ("tungsten-carbide", "steel")
        return Conditions(mats, preload_n=preload, torque_nm=torque, geometry={"diameter_m": dia})

    def timed(r: Repository, req: Conditions) -> float:
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", OutsideCatalogueWarning)
            matches = r.nearest("tool-holder", req, k=5)
        assert len(matches) == 5
        return time.perf_counter() - t0

    cold = []  # a fresh Repository per query: what a one-shot CLI call pays
    for _ in range(max(3, n_queries // 4)):
        fresh = Repository(repo.url)
        cold.append(timed(fresh, request()))
        fresh.close()
    warm, ref = [], []  # one long-lived Repository (API server, predict over several interfaces)
    for _ in range(n_queries):
        req = request()
        warm.append(timed(repo, req))
        t0 = time.perf_counter()
        reference_rank(arrays, req.torque_nm, req.preload_n, req.geometry["diameter_m"], req.materials, 5)
        ref.append(time.perf_counter() - t0)
    ref_ms = np.median(ref) * 1e3
    n_cand = n_versions // per_joint // 2
    print(f"nearest, {n_versions:>7,} versions ({per_joint} per joint; {n_cand:,} current tool-holder candidates; "
          f"bulk insert {t_fill:.1f} s)")
    for label, lat in (("cold (new Repository)", cold), ("warm (cached arrays)", warm)):
        ms = np.array(lat) * 1e3
        print(f"  {label:22s} median {np.median(ms):8.2f} ms   p99 {np.percentile(ms, 99):8.2f} ms   "
              f"n={ms.size}   ratio to numpy reference {np.median(ms) / ref_ms:7.1f}x")
    print(f"  numpy reference on in-memory arrays: median {ref_ms:.2f} ms (no blob is read by the query)")
    repo.close()


def main() -> None:
    quick = "--quick" in sys.argv
    with tempfile.TemporaryDirectory(prefix="jointdb-bench-") as tmp:
        root = Path(tmp)
        bench_catalogue(root, 30 if quick else 100)
        bench_query(root, 1_000, 1, 50)
        bench_query(root, 1_000, 10, 50)
        bench_query(root, 100_000, 1, 10 if quick else 40)
        bench_query(root, 100_000, 10, 10 if quick else 40)


if __name__ == "__main__":
    main()
