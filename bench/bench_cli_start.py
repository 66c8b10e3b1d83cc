#!/usr/bin/env python
"""Benchmark: start-up CPU time of the command line and of ``import jointdb.fe``.

Each row is a fresh Python process run ``--repeat`` times; the CPU time (user +
system, from ``getrusage`` of the children) is the median. The reference,
measured in the same run, is ``python -c pass`` (the interpreter alone):

- ``import jointdb.fe``          (goal <= 0.2 s CPU)
- ``jointdb --help``             (goal <= 0.2 s CPU)
- ``jointdb query`` on the demo's database (6 versions; goal <= 0.35 s CPU)

The database comes from ``jointdb demo`` run once into a temporary directory
(not timed), unless ``--db`` names one. The processes import ``jointdb`` as
this interpreter finds it (the installed package, or ``PYTHONPATH``).

Usage: .venv/bin/python bench/bench_cli_start.py [--repeat 7] [--db joints.sqlite] [--importtime]
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

CLI = "import sys; from jointdb.cli import main; sys.argv[0] = 'jointdb'; main()"


def cpu_seconds(argv: list[str], env: dict) -> float:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(argv, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--db", type=Path, help="a jointdb SQLite database (default: build the demo's)")
    ap.add_argument("--importtime", action="store_true", help="also print the 12 slowest imports of each row")
    args = ap.parse_args(argv)
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    py = sys.executable
    with tempfile.TemporaryDirectory() as tmp:
        db = args.db
        if db is None:
            subprocess.run([py, "-c", CLI, "demo", "--out", tmp], env=env, check=True,
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            db = Path(tmp) / "joints.sqlite"
        rows = {
            "python -c pass (reference)": [py, "-c", "pass"],
            "import jointdb.fe": [py, "-c", "import jointdb.fe"],
            "jointdb --help": [py, "-c", CLI, "--help"],
            "jointdb query (demo database)": [py, "-c", CLI, "query", "--type", "tool-holder", "--torque", "35",
                                              "--db", str(db)],
        }
        goals = {"import jointdb.fe": 0.2, "jointdb --help": 0.2, "jointdb query (demo database)": 0.35}
        times: dict[str, list[float]] = {k: [] for k in rows}
        for _ in range(args.repeat):  # interleaved, so that all see the same machine load
            for name, cmd in rows.items():
                times[name].append(cpu_seconds(cmd, env))
        ref = statistics.median(times["python -c pass (reference)"])
        print(f"start-up CPU time (user + system), median of {args.repeat} fresh processes")
        for name, ts in times.items():
            med = statistics.median(ts)
            goal = f"   goal <= {goals[name]:.2f} s: {'met' if med <= goals[name] else 'NOT met'}" if name in goals else ""
            print(f"  {name:32s} {med:6.3f} s   {med / ref:5.1f} x python -c pass{goal}")
        if args.importtime:
            for name, cmd in rows.items():
                out = subprocess.run([cmd[0], "-X", "importtime", *cmd[1:]], env=env, capture_output=True, text=True)
                lines = [x for x in out.stderr.splitlines() if x.startswith("import time:") and "cumulative" not in x]
                top = sorted(lines, key=lambda x: -int(x.split("|")[1]))[:12]
                print(f"\n{name}: slowest imports (cumulative us | module)")
                for x in top:
                    print("   " + x.split("|", 1)[1].strip())


if __name__ == "__main__":
    main()
