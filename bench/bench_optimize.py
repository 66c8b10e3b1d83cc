"""Bench: `optimize`'s candidate evaluation — 10 000 stacks × 300 speeds, zero-order lobes.

Builds the bundled catalogue (as `jointdb demo` does), then a grid of candidates: 50 overhangs
(50–74.5 mm) × 20 clamping torques (40–120 N·m) × 10 drawbar forces (12–24 kN), joints interpolated
between the catalogued conditions. Measures, in this process:

1. the fast path in-process (cached substructures, coupling over a candidate axis, batched ZOA);
2. the straightforward loop (``predict_stack`` + ``stability_lobes`` per candidate) on a seeded
   sample, extrapolated to all candidates (the whole loop would take hours) — and checks that the
   fast results on the sample equal the loop's to the last digit;
3. the fast path on a Dask local cluster of 1 and of 2 worker processes (cluster start-up and the
   workers' own set-up included), and that its results equal the in-process ones.

    python bench/bench_optimize.py [--candidates N] [--sample K]
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np


def build(tmp: Path, n: int):
    from jointdb.usecases._demo import run_main_job
    from jointdb.stack import stack_to_dict
    from jointdb.store import Repository
    from jointdb.usecases import load_stack
    from jointdb.usecases._optimize import Candidate, load_problem

    run_main_job(tmp / "demo", f"sqlite:///{tmp / 'joints.sqlite'}", say=lambda _: None, n_speeds=40)
    data = Path(__file__).resolve().parents[1] / "jointdb" / "data" / "catalogue"
    doc = stack_to_dict(load_stack(data / "demo-stack.json"))
    for name in ("tool-holder", "holder-spindle"):
        doc["interfaces"][name]["query"]["interpolate"] = True
    (tmp / "stack.json").write_text(json.dumps(doc))
    spec = json.loads((data.parents[2] / "fixtures" / "optimize" / "optimize-spec.json").read_text())
    spec["stack"] = "stack.json"
    (tmp / "spec.json").write_text(json.dumps(spec))
    problem = load_problem(tmp / "spec.json")
    n_over = max(1, n // 200)
    cands = [Candidate("template", round(0.05 + 0.0005 * i, 6), float(t), float(f))
             for i in range(n_over) for t in np.linspace(40, 120, 20) for f in np.linspace(12000, 24000, 10)][:n]
    return problem, Repository(f"sqlite:///{tmp / 'joints.sqlite'}"), cands


def same(a, b) -> bool:
    return all(x.candidate == y.candidate and x.best == y.best and
               np.array_equal(x.lobes.depth_m, y.lobes.depth_m, equal_nan=True) for x, y in zip(a, b))


def main() -> None:
    from jointdb.usecases._optimize import evaluate_brute_force
    from jointdb.usecases._optimize_eval import evaluate_candidates

    ap = argparse.ArgumentParser()
    ap.add_argument("--candidates", type=int, default=10_000)
    ap.add_argument("--sample", type=int, default=12)
    ap.add_argument("--no-dask", action="store_true")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as d:
        problem, repo, cands = build(Path(d), args.candidates)
        print(f"{len(cands)} candidates x {problem.spec.machine.n_speeds} speeds (ZOA)")
        t = time.perf_counter()
        fast = evaluate_candidates(problem, cands, repo)
        t_fast = time.perf_counter() - t
        print(f"fast, in-process:   {t_fast:8.1f} s  ({t_fast / len(cands) * 1e3:.2f} ms per candidate)")
        rng = np.random.default_rng(24)
        sample = sorted(rng.choice(len(cands), size=min(args.sample, len(cands)), replace=False))
        t = time.perf_counter()
        slow = evaluate_brute_force(problem, [cands[i] for i in sample], repo)
        per = (time.perf_counter() - t) / len(sample)
        print(f"loop predict+lobes: {per * 1e3:8.0f} ms per candidate on a sample of {len(sample)}, "
              f"extrapolated {per * len(cands):.0f} s for all -> fast path {per * len(cands) / t_fast:.0f}x")
        print(f"  sample equal to the last digit: {same([fast[i] for i in sample], slow)}")
        if not args.no_dask:
            times = {}
            steady = {}
            for w in (1, 2):
                stamps = []
                t = time.perf_counter()
                on = evaluate_candidates(problem, cands, repo, lambda done, total, msg: stamps.append(
                    (time.perf_counter(), done)), scheduler="local", n_workers=w)
                times[w] = time.perf_counter() - t
                # after the first chunk per worker (cluster start, imports, each worker's own cache warm-up)
                (t1, d1), (t2, d2) = stamps[w - 1], stamps[-1]
                steady[w] = (d2 - d1) / (t2 - t1)
                print(f"Dask local cluster, {w} worker(s): {times[w]:8.1f} s (start-up included; first chunk "
                      f"done after {stamps[0][0] - t:.1f} s), then {steady[w]:.0f} candidates/s; "
                      f"equal to in-process: {same(on, fast)}")
            print(f"  2 workers vs 1: {times[1] / times[2]:.2f}x overall, {steady[2] / steady[1]:.2f}x after start-up")
        repo.close()


if __name__ == "__main__":
    main()
