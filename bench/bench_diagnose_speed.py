"""Speed of ``jointdb diagnose`` and of the case generator: this tree against a reference commit,
in one run, with the results compared case by case (not a test: prints numbers).

Usage::

    .venv/bin/python bench/bench_diagnose_speed.py [--reference a4619c1] [--cases joint_damping:0,...]
        [--repeat 1] [--json out.json]

The reference is the code of a git commit (default: the last commit before the speed-ups of
round 3 session 6, task "diagspeed"; ``--reference d22c5f5`` measures against the code before
those of session 5), extracted with ``git archive`` into a temporary directory. Each side runs
in its own subprocess on one BLAS thread (``OPENBLAS_NUM_THREADS=1``), alternately case by
case (reference, this tree, reference, ...), so that a change of the machine's load hits both
alike. Timed per case: the CPU time of generating the case (the benchmark's truth models) and of
diagnosing it (``diagnose_case``); the ratio reference / this tree is the speed-up.

Agreement (printed per case): the verdict's words, the named explanation, the ranking's first
three names and the located position must be identical; each fitted value must agree within
``TOL_SIGMA`` of its reported σ (the fit's own uncertainty: a change well inside it is no change
of the answer), and the mismatch before and after within 1e-4 relative. The engine's changes are
exact (bit-identical fits on the same recordings); the generator's harmonic balance changes the
recordings of a softening joint by round-off (~1e-15), which moves that fit by ~1e-3 σ.

Session 6 ("diagspeed"): models of one geometry share a mesh, DOF labels, bare beam matrices and
rigid-body motions; an insertion's contact layer is added in one ``np.add.at``; the evaluator
synthesises at the recorded DOFs without building an FRF object. All exact: the same fits bit for
bit (checked here case by case, and by tests/fe/test_fe_mesh_sharing.py).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: the last commit before the speed-ups of round 3, session 6 (task "diagspeed"); d22c5f5: before session 5's
REFERENCE = "a4619c1"
#: a fixed workload: beam cases with one and with three levels, chain effects, a stack case
CASES = ("joint_damping:0", "sensor_mass:0", "gain:1", "fluted_diameter:0", "softening_joint:0", "interface_joint:0")
#: fitted values must agree within this fraction of their reported σ
TOL_SIGMA = 0.05

_WORKER = r"""
import json, sys, time
from jointdb.diagnose_bench import diagnose_case, generate_case, single_blas_thread
for line in sys.stdin:
    effect, seed = line.split()
    with single_blas_thread():
        t = time.process_time()
        case = generate_case(effect, int(seed))
        t_gen = time.process_time() - t
        t = time.process_time()
        model, d = diagnose_case(case)
        t_diag = time.process_time() - t
    b = d.best
    cand = None if b is None else (b.candidate.parts[0] if hasattr(b.candidate, "parts") else b.candidate)
    print(json.dumps({"case": f"{effect}-{seed}", "gen_cpu": t_gen, "diag_cpu": t_diag, "verdict": d.verdict,
                      "best": None if b is None else b.name, "ranking": [f.name for f in d.ranking[:3]],
                      "position": getattr(cand, "position", None),
                      "values": {} if b is None else b.values, "sigmas": {} if b is None else b.sigmas,
                      "mismatch": [d.mismatch_before, d.mismatch_after]}, default=float), flush=True)
"""


def _extract(rev: str, into: str) -> str:
    """The ``jointdb`` package of commit ``rev`` under ``into`` (returns the directory for PYTHONPATH)."""
    tar = Path(into) / "ref.tar"
    with open(tar, "wb") as fh:
        subprocess.run(["git", "-C", str(ROOT), "archive", rev, "jointdb"], stdout=fh, check=True)
    with tarfile.open(tar) as tf:
        tf.extractall(into, filter="data")
    return into


def _worker(path: str) -> subprocess.Popen:
    env = dict(os.environ, PYTHONPATH=path, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    return subprocess.Popen([sys.executable, "-c", _WORKER], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                            text=True, env=env, cwd=path)


def _ask(proc: subprocess.Popen, case: str) -> dict:
    effect, seed = case.split(":")
    proc.stdin.write(f"{effect} {seed}\n")
    proc.stdin.flush()
    line = proc.stdout.readline()
    if not line:
        raise RuntimeError(f"the worker died on {case}")
    return json.loads(line)


_NUMBER = re.compile(r"[-+]?\d[\d,]*(?:\.\d+)?(?:e[-+]?\d+)?")


def compare(old: dict, new: dict) -> list[str]:
    """What differs between two results of the same case (empty: the same answer). The verdict's
    words must be identical; its numbers are the fitted values, which may move within TOL_SIGMA σ."""
    bad = [k for k in ("best", "ranking", "position") if old[k] != new[k]]
    if _NUMBER.sub("#", old["verdict"]) != _NUMBER.sub("#", new["verdict"]):
        bad.append("verdict words")
    for k, v in old["values"].items():
        s = old["sigmas"].get(k) or 0.0
        w = new["values"].get(k)
        if w is None or abs(w - v) > TOL_SIGMA * s + 1e-12 * abs(v):
            bad.append(f"value {k}: {v!r} -> {w!r} (sigma {s:.3g})")
    for a, b in zip(old["mismatch"], new["mismatch"]):
        if abs(a - b) > 1e-4 * abs(a):
            bad.append(f"mismatch {a!r} -> {b!r}")
    return bad


def identical(old: dict, new: dict) -> bool:
    """The same answer bit for bit: every fitted value, σ and mismatch equal (JSON keeps a float exactly)."""
    return all(old[k] == new[k] for k in ("verdict", "best", "ranking", "position", "values", "sigmas", "mismatch"))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--reference", default=REFERENCE, help="git commit of the reference code")
    ap.add_argument("--cases", default=",".join(CASES), help="effect:seed, comma-separated")
    ap.add_argument("--repeat", type=int, default=1, help="runs of the whole workload (best CPU kept)")
    ap.add_argument("--json", default=None, help="write every result to this file")
    args = ap.parse_args()
    cases = [c.strip() for c in args.cases.split(",") if c.strip()]
    print("load average at start: %.2f %.2f %.2f (1, 5, 15 min)" % os.getloadavg(), flush=True)
    with tempfile.TemporaryDirectory() as tmp:
        ref = _worker(_extract(args.reference, tmp))
        cur = _worker(str(ROOT))
        rows, out = [], []
        try:
            for case in cases:
                runs = [(_ask(ref, case), _ask(cur, case)) for _ in range(args.repeat)]
                old, new = runs[0]
                best = {side: {k: min(r[i][k] for r in runs) for k in ("gen_cpu", "diag_cpu")}
                        for i, side in enumerate(("old", "new"))}
                diff = compare(old, new)
                exact = identical(old, new)
                rows.append((case, best, diff, exact))
                out.append({"case": case, "old": old, "new": new, "cpu": best, "differences": diff,
                            "bit_identical": exact})
                print(f"{case:22s} diagnose {best['old']['diag_cpu']:6.1f} -> {best['new']['diag_cpu']:6.1f} s "
                      f"({best['old']['diag_cpu'] / best['new']['diag_cpu']:.2f}x)  generate "
                      f"{best['old']['gen_cpu']:5.1f} -> {best['new']['gen_cpu']:5.1f} s  "
                      f"{('same answer' + (', bit-identical' if exact else '')) if not diff else 'DIFFERS: ' + '; '.join(diff)}",
                      flush=True)
        finally:
            for p in (ref, cur):
                p.stdin.close()
                p.wait()
    tot = {side: {k: sum(r[1][side][k] for r in rows) for k in ("gen_cpu", "diag_cpu")} for side in ("old", "new")}
    print(f"total CPU: diagnose {tot['old']['diag_cpu']:.1f} -> {tot['new']['diag_cpu']:.1f} s "
          f"({tot['old']['diag_cpu'] / tot['new']['diag_cpu']:.2f}x); generate {tot['old']['gen_cpu']:.1f} -> "
          f"{tot['new']['gen_cpu']:.1f} s ({tot['old']['gen_cpu'] / max(tot['new']['gen_cpu'], 1e-9):.2f}x); "
          f"same answer in {sum(not r[2] for r in rows)} / {len(rows)} cases, bit-identical in "
          f"{sum(r[3] for r in rows)} (reference {args.reference})")
    print("load average at end: %.2f %.2f %.2f (1, 5, 15 min)" % os.getloadavg())
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=1, default=float))


if __name__ == "__main__":
    main()
