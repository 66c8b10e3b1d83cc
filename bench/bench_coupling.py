#!/usr/bin/env python
"""Benchmark (a): forward coupling, two 60-DOF substructures, 6 interface DOFs, 10,000 lines.

Compares :func:`jointdb.coupling.couple` (only the requested outputs, interface-
sized solve) with the textbook LM-FBS expression on the full matrix,
``Y − Y Bᵀ (B Y Bᵀ)⁻¹ B Y`` (120 × 120 per line), in the same process, and
checks that both agree. Lines are processed in chunks to bound memory; FRF
container construction is not timed.

Usage: .venv/bin/python bench/bench_coupling.py [--lines 10000] [--chunk 1000] [--repeat 3]
"""

from __future__ import annotations

import argparse
import os
import time

# single-threaded BLAS for both contenders (small matrices; avoids thread thrashing on shared machines)
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from jointdb.coupling import Interface, couple, spring_damper_joint  # noqa: E402
from _synthetic import modal_receptance  # noqa: E402  (bench/ is on sys.path when run as a script)
from jointdb.frf import FRF, Dof  # noqa: E402



def main(argv=None) -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--lines", type=int, default=10_000)
    ap.add_argument("--chunk", type=int, default=1_000)
    ap.add_argument("--repeat", type=int, default=1)
    args = ap.parse_args(argv)
    n = 60
    freq_all = np.linspace(10.0, 6000.0, args.lines)
    la = [Dof(i + 1, "x") for i in range(n)]
    lb = [Dof(i + 101, "x") for i in range(n)]
    ca, cb = list(range(54, 60)), list(range(0, 6))  # 6 interface DOF pairs
    outs = [("A", la[0]), ("B", lb[-1])]
    t_few = t_all = t_ref = 0.0
    max_err = 0.0
    for start in range(0, args.lines, args.chunk):
        f = freq_all[start : start + args.chunk]
        YA, YB = modal_receptance(f, n, 1), modal_receptance(f, n, 2)
        A, B = FRF(f, YA, la, la), FRF(f, YB, lb, lb)
        joint = spring_damper_joint(f, [5e7] * 6, [50.0] * 6, [la[i] for i in ca])
        iface = [Interface("A", [la[i] for i in ca], "B", [lb[i] for i in cb], joint)]
        hj = joint.values

        def ref():
            n_ = 2 * n
            Y = np.zeros((f.size, n_, n_), dtype=complex)
            Y[:, :n, :n], Y[:, n:, n:] = YA, YB
            Bm = np.zeros((6, n_))
            Bm[np.arange(6), ca] = 1.0
            Bm[np.arange(6), n + np.asarray(cb)] = -1.0
            BY = Bm @ Y
            return Y - (Y @ Bm.T) @ np.linalg.solve(BY @ Bm.T + hj, BY)

        for _ in range(args.repeat):
            t0 = time.perf_counter()
            g = couple({"A": A, "B": B}, iface, outs)
            t1 = time.perf_counter()
            gall = couple({"A": A, "B": B}, iface, [("A", d) for d in la] + [("B", d) for d in lb])
            t2 = time.perf_counter()
            G = ref()
            t3 = time.perf_counter()
        t_few += (t1 - t0)
        t_all += (t2 - t1)
        t_ref += (t3 - t2)
        sel = [0, 2 * n - 1]
        want = G[:, sel][:, :, sel]
        max_err = max(max_err, float(np.max(np.abs(g.values - want)) / np.max(np.abs(want))),
                      float(np.max(np.abs(gall.values - G)) / np.max(np.abs(G))))
    print(f"forward coupling: 2 x {n}-DOF substructures, 6 interface DOFs, {args.lines} lines "
          f"(chunks of {args.chunk}, last of {args.repeat} repeats per chunk)")
    print(f"  textbook full-matrix LM-FBS  Y - Y B^T (B Y B^T + H_J)^-1 B Y : {t_ref:8.3f} s")
    print(f"  couple(), 2 outputs x 2 inputs                              : {t_few:8.3f} s   ratio {t_ref / t_few:6.1f}x faster")
    print(f"  couple(), all 120 outputs x 120 inputs                      : {t_all:8.3f} s   ratio {t_ref / t_all:6.2f}x")
    print(f"  max relative difference vs textbook: {max_err:.2e}")


if __name__ == "__main__":
    main()
