#!/usr/bin/env python
"""Benchmark: forward coupling, two 60-DOF substructures, 6 interface DOFs, 10,000 lines, 2 outputs.

Three contenders, all timed in this process on the same data (one BLAS thread):

- ``full``: the textbook LM-FBS expression on the whole assembled matrix,
  ``Y − Y Bᵀ (B Y Bᵀ + H_J)⁻¹ B Y`` (120 × 120 per line);
- ``floor``: the outputs-only expression written by hand on the raw arrays,
  ``G_oi = H_oi − H_oC Bᵀ (B H_CC Bᵀ + H_J)⁻¹ B H_Ci`` with basic slices (views)
  wherever the DOFs are contiguous — what any implementation has to compute;
- ``couple()``: :func:`jointdb.coupling.couple` on FRF containers (the
  containers are built outside the timing, like measured data already loaded).

``couple()`` and the floor run on all lines in one call, interleaved
``--repeat`` times (medians); the full expression runs once, in chunks of
lines (memory). Printed as ratios: ``full / couple`` (goal >= 100) and
``couple / floor`` (goal <= 1.5), with the largest differences between the
three results.

Usage: .venv/bin/python bench/bench_coupling.py [--lines 10000] [--chunk 2500] [--repeat 7]
"""

from __future__ import annotations

import argparse
import os
import time

# single-threaded BLAS for every contender (small matrices; avoids thread thrashing on shared machines)
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from _synthetic import modal_receptance  # noqa: E402  (bench/ is on sys.path when run as a script)
from jointdb.coupling import Interface, couple, spring_damper_joint  # noqa: E402
from jointdb.frf import FRF, Dof  # noqa: E402


def main(argv=None) -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--lines", type=int, default=10_000)
    ap.add_argument("--chunk", type=int, default=2_500, help="lines per chunk of the full expression (120x120)")
    ap.add_argument("--repeat", type=int, default=7, help="interleaved runs of couple() and the floor (median)")
    args = ap.parse_args(argv)
    n, nj = 60, 6
    freq = np.linspace(10.0, 6000.0, args.lines)
    la = [Dof(i + 1, "x") for i in range(n)]
    lb = [Dof(i + 101, "x") for i in range(n)]
    ca, cb = np.arange(n - nj, n), np.arange(nj)  # interface: the last 6 DOFs of A to the first 6 of B
    outs = [("A", la[0]), ("B", lb[-1])]  # 2 outputs = 2 inputs
    ya, yb = modal_receptance(freq, n, 1), modal_receptance(freq, n, 2)
    sub_a, sub_b = FRF(freq, ya, la, la), FRF(freq, yb, lb, lb)
    joint = spring_damper_joint(freq, [5e7] * nj, [50.0] * nj, [la[i] for i in ca])
    ifaces = [Interface("A", [la[i] for i in ca], "B", [lb[i] for i in cb], joint)]
    hj = np.asarray(joint.values)

    def floor():
        # outputs A:0 and B:59; B = [I, -I] over (A's contacts, B's contacts); slices are views
        sa, sb = slice(ca[0], ca[-1] + 1), slice(cb[0], cb[-1] + 1)
        z = ya[:, sa, sa] + yb[:, sb, sb] + hj
        u = np.concatenate([ya[:, 0:1, sa], -yb[:, n - 1 : n, sb]], axis=1)  # H_oC Bᵀ  (nf, 2, 6)
        v = np.concatenate([ya[:, sa, 0:1], -yb[:, sb, n - 1 : n]], axis=2)  # B H_Ci  (nf, 6, 2)
        g = -(u @ np.linalg.solve(z, v))
        g[:, 0, 0] += ya[:, 0, 0]
        g[:, 1, 1] += yb[:, n - 1, n - 1]
        return g

    def full(lines: slice):
        m = 2 * n
        y = np.zeros((lines.stop - lines.start, m, m), dtype=complex)
        y[:, :n, :n], y[:, n:, n:] = ya[lines], yb[lines]
        bm = np.zeros((nj, m))
        bm[np.arange(nj), ca] = 1.0
        bm[np.arange(nj), n + cb] = -1.0
        by = bm @ y
        return y - (y @ bm.T) @ np.linalg.solve(by @ bm.T + hj[lines], by)

    t_couple, t_floor, ratios = [], [], []
    for _ in range(args.repeat):  # interleaved, so that both see the same machine load
        t0 = time.perf_counter()
        g_couple = couple({"A": sub_a, "B": sub_b}, ifaces, outs)
        t1 = time.perf_counter()
        g_floor = floor()
        t2 = time.perf_counter()
        t_couple.append(t1 - t0)
        t_floor.append(t2 - t1)
        ratios.append((t1 - t0) / (t2 - t1))
    t_full = 0.0
    sel = [0, 2 * n - 1]
    err = {"couple": 0.0, "floor": 0.0}
    scale = np.max(np.abs(g_floor))
    for start in range(0, args.lines, args.chunk):
        lines = slice(start, min(start + args.chunk, args.lines))
        t0 = time.perf_counter()
        g_full = full(lines)
        t_full += time.perf_counter() - t0
        want = g_full[:, sel][:, :, sel]
        err["couple"] = max(err["couple"], float(np.max(np.abs(g_couple.values[lines] - want)) / scale))
        err["floor"] = max(err["floor"], float(np.max(np.abs(g_floor[lines] - want)) / scale))
    tc, tf = float(np.median(t_couple)), float(np.median(t_floor))
    print(f"forward coupling: 2 x {n}-DOF substructures, {nj} interface DOFs, {args.lines} lines, 2 outputs x 2 inputs")
    print(f"  full LM-FBS  Y - Y B^T (B Y B^T + H_J)^-1 B Y (reference, chunks of {args.chunk}) : {t_full:8.3f} s")
    print(f"  outputs-only floor on the raw arrays (reference, median of {args.repeat})       : {tf:8.4f} s")
    print(f"  couple() (median of {args.repeat})                                              : {tc:8.4f} s")
    print(f"  full / couple   = {t_full / tc:7.1f}   (goal >= 100)")
    print(f"  couple / floor  = {float(np.median(ratios)):7.2f}   (median of the interleaved pairs; goal <= 1.5; "
          f"range {min(ratios):.2f}-{max(ratios):.2f})")
    print(f"  max difference vs full, relative to max|G|: couple {err['couple']:.1e}, floor {err['floor']:.1e}")


if __name__ == "__main__":
    main()
