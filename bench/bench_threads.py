#!/usr/bin/env python
"""Benchmark: the CLI's own BLAS thread policy (issue 26), as ratios in the same run.

``jointdb predict`` on the demo stack (the bundled catalogue, built first by
``jointdb demo``) is timed, wall clock, in three settings:

- *policy*: no thread variable set — jointdb's default (one thread) applies;
- *reference*: ``OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1`` set by hand (what only the
  Makefile did before);
- *library default*: ``--blas-threads 0`` — OpenBLAS at its own thread count, which is
  what every command ran with before the policy.

Each setting runs quiet and again with two busy processes beside it (pure-Python spin
loops, one per core of the 2-core reference machine). Goal: policy / reference <= 1.2 in
both cases. Printed: median of ``--runs`` runs each, and the ratios.

Run: ``PYTHONPATH=. .venv/bin/python bench/bench_threads.py [--runs 2]``
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

THREAD_VARS = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS",
               "JOINTDB_BLAS_THREADS")
JOINTDB = [sys.executable, "-m", "jointdb"]


def _env(**extra: str) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in THREAD_VARS}
    env.update(extra)
    return env


def _predict(work: Path, env: dict[str, str], extra: list[str]) -> float:
    t0 = time.perf_counter()
    subprocess.run([*JOINTDB, *extra, "predict", str(work / "ex/stacks/demo-stack.json"),
                    "--db", str(work / "demo/joints.sqlite"), "--json"], env=env, cwd=work, check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - t0


def _busy(n: int) -> list[subprocess.Popen]:
    spin = "import time\nt = time.time() + 900\nwhile time.time() < t:\n    pass\n"
    return [subprocess.Popen([sys.executable, "-c", spin]) for _ in range(n)]


def _settings(work: Path, runs: int) -> dict[str, float]:
    settings = {
        "policy (no variables)": (_env(), []),
        "reference (OPENBLAS_NUM_THREADS=1 by hand)": (_env(OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1"), []),
        "library default (--blas-threads 0)": (_env(), ["--blas-threads", "0"]),
    }
    times: dict[str, list[float]] = {name: [] for name in settings}
    for _ in range(runs):  # interleaved, so a change of machine load hits every setting alike
        for name, (env, extra) in settings.items():
            times[name].append(_predict(work, env, extra))
    return {name: statistics.median(t) for name, t in times.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=2)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="jointdb-bench-threads-") as tmp:
        work = Path(tmp)
        subprocess.run([*JOINTDB, "examples", "ex"], cwd=work, check=True, stdout=subprocess.DEVNULL)
        subprocess.run([*JOINTDB, "demo", "--out", "demo"], cwd=work, env=_env(OPENBLAS_NUM_THREADS="1"),
                       check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        print(f"load before: {os.getloadavg()[0]:.2f}, cores: {os.cpu_count()}")
        for label, n_busy in (("quiet", 0), ("two busy processes beside it", 2)):
            busy = _busy(n_busy)
            try:
                med = _settings(work, args.runs)
            finally:
                for p in busy:
                    p.kill()
                    p.wait()
            ref = med["reference (OPENBLAS_NUM_THREADS=1 by hand)"]
            print(f"== jointdb predict, demo stack, {label} (median of {args.runs})")
            for name, t in med.items():
                print(f"  {name:44s} {t:7.2f} s   {t / ref:5.2f}x the reference")
            ok = med["policy (no variables)"] / ref <= 1.2
            print(f"  goal policy/reference <= 1.2: {'met' if ok else 'NOT met'}")


if __name__ == "__main__":
    main()
