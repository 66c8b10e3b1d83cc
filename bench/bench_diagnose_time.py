"""Time bench of ``jointdb diagnose`` against the issue-25 goals (not a test: prints numbers).

Goal (one BLAS thread): median time per case ≤ 45 s for the micro-slip (multi-level) effects
``softening_joint`` and ``interface_softening``, ≤ 30 s for every other hidden effect.

Usage::

    .venv/bin/python bench/bench_diagnose_time.py [--cases 3] [--seed 1000] [--effects a,b]
    .venv/bin/python bench/bench_diagnose_time.py --from-jsonl cases.jsonl   # a bench_diagnose.py log

Each case is generated from the benchmark's independent truth models (seeds ≥ 1000 are the
reported ones) and diagnosed once on one BLAS thread. Printed per case and per effect: the wall
time and the CPU time of the diagnosis, and the machine's 1-minute load average. The machine this
runs on is shared, so the wall time grows with the load: the CPU time of the single-threaded
diagnosis is its time on an idle core (cache and memory-bandwidth contention still inflate it a
little), and the load average says how shared the machine was. The reference line is one direct
FRF synthesis of a nominal model on all recorded lines, timed in the same process before and
after, so that a ratio can be compared across machines.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from jointdb.diagnose_bench import EFFECTS, BenchResult, generate_case, run_case, single_blas_thread
from jointdb.diagnose_bench._run import effects_from, load_average
from jointdb.fe import model_from_dict


def _reference_seconds(seed: int) -> float:
    """Best of three direct FRF syntheses of a nominal model on all recorded lines [s] (warm)."""
    case = generate_case("none", seed)
    model = model_from_dict(case.model)
    freq = case.recordings[0].frf.freq
    model.frf(freq, points=["tip", "flute", "shank"], directions=["x"])     # warm-up
    best = np.inf
    for _ in range(3):
        t = time.perf_counter()
        model.frf(freq, points=["tip", "flute", "shank"], directions=["x"])
        best = min(best, time.perf_counter() - t)
    return float(best)


def _table(rows) -> str:
    cols = list(dict.fromkeys(k for r in rows for k in r))
    out = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    return "\n".join(out + ["| " + " | ".join(str(r.get(c, "")) for c in cols) + " |" for r in rows])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cases", type=int, default=3, help="cases per effect (seeds seed, seed+1, …)")
    ap.add_argument("--seed", type=int, default=1000)
    ap.add_argument("--effects", default=",".join(EFFECTS))
    ap.add_argument("--from-jsonl", default=None, help="summarise the cases logged by bench_diagnose.py --jsonl")
    args = ap.parse_args()
    try:
        effects = effects_from(args.effects)
    except ValueError as exc:
        ap.error(f"--effects: {exc}")
    print("load average at start: %.2f %.2f %.2f (1, 5, 15 min)" % load_average(), flush=True)
    if args.from_jsonl:
        bench, refs = BenchResult.from_file(args.from_jsonl), []
    else:
        results = []
        with single_blas_thread():
            refs = [_reference_seconds(args.seed)]
            for e in effects:
                for k in range(args.cases):
                    r = run_case(generate_case(e, args.seed + k))
                    results.append(r)
                    print(f"{r.case:28s} wall {r.seconds:6.1f} s  cpu {r.cpu_seconds:6.1f} s  load {r.load:.1f}",
                          flush=True)
            refs.append(_reference_seconds(args.seed))
        bench = BenchResult(results, sum(r.seconds for r in results))
    print(_table(bench.timing()))
    if refs:
        print(f"reference direct FRF synthesis: {refs[0]:.3f} s before, {refs[1]:.3f} s after "
              "(≈ 0.2 s on an idle core)")
    print("load average at end: %.2f %.2f %.2f (1, 5, 15 min)" % load_average())


if __name__ == "__main__":
    main()
