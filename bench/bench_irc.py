#!/usr/bin/env python
"""Benchmark (b): full-matrix joint identification, nc = 12, L = 15, 10,000 lines.

Times :func:`jointdb.coupling.identify_joint_matrix` (batched, equilibrated
pseudo-inverses ``P = H_IC⁺ D H_CI⁺``) against the textbook Kronecker least
squares ``(H_CIᵀ ⊗ H_IC) vec P = vec D`` solved line by line with
``numpy.linalg.lstsq`` (225 × 144 per line), in the same process, and checks
that both give the same joint. Lines are processed in chunks to bound memory.

Usage: .venv/bin/python bench/bench_irc.py [--lines 10000] [--chunk 2000]
"""

from __future__ import annotations

import argparse
import os
import time

# single-threaded BLAS for both contenders (small matrices; avoids thread thrashing on shared machines)
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from jointdb.coupling import identify_joint_matrix  # noqa: E402
from _synthetic import modal_receptance  # noqa: E402  (bench/ is on sys.path when run as a script)
from jointdb.frf import DIRECTIONS, FRF, Dof  # noqa: E402



def main(argv=None) -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--lines", type=int, default=10_000)
    ap.add_argument("--chunk", type=int, default=2_000)
    ap.add_argument("--ref-lines", type=int, default=100,
                    help="lines per chunk solved by the (slow) textbook reference; its time is scaled per line")
    args = ap.parse_args(argv)
    # A: 8 measured + 6 contact DOFs; B: 7 measured + 6 contact -> L = 15, nc = 12
    a_meas = [Dof(i + 1, "x") for i in range(8)]
    b_meas = [Dof(i + 101, "x") for i in range(7)]
    a_c = [Dof(50, d) for d in DIRECTIONS]
    b_c = [Dof(150, d) for d in DIRECTIONS]
    la, lb = a_meas + a_c, b_meas + b_c
    measured = [("A", d) for d in a_meas] + [("B", d) for d in b_meas]
    t_ours = t_ref = 0.0
    max_diff = 0.0
    freq_all = np.linspace(20.0, 5000.0, args.lines)
    for start in range(0, args.lines, args.chunk):
        f = freq_all[start : start + args.chunk]
        HA, HB = modal_receptance(f, len(la), 3), modal_receptance(f, len(lb), 4)
        rng = np.random.default_rng(start)
        G = modal_receptance(f, 15, 5) + 0.01 * rng.standard_normal((f.size, 15, 15))
        G = 0.5 * (G + np.swapaxes(G, 1, 2))
        subs = {"A": FRF(f, HA, la, la), "B": FRF(f, HB, lb, lb)}
        assembly = FRF(f, G, a_meas + b_meas, a_meas + b_meas)
        t0 = time.perf_counter()
        res = identify_joint_matrix(assembly, subs, measured, "A", a_c, "B", b_c, symmetrize=False)
        t1 = time.perf_counter()
        # textbook: Kronecker least squares per line
        L, nc = 15, 12
        h_ii = np.zeros((f.size, L, L), complex)
        h_ic = np.zeros((f.size, L, nc), complex)
        h_cc = np.zeros((f.size, nc, nc), complex)
        h_ii[:, :8, :8], h_ii[:, 8:, 8:] = HA[:, :8, :8], HB[:, :7, :7]
        h_ic[:, :8, :6], h_ic[:, 8:, 6:] = HA[:, :8, 8:], HB[:, :7, 7:]
        h_cc[:, :6, :6], h_cc[:, 6:, 6:] = HA[:, 8:, 8:], HB[:, 7:, 7:]
        h_ci = np.swapaxes(h_ic, 1, 2)
        d = h_ii - G
        sub = np.unique(np.linspace(0, f.size - 1, min(args.ref_lines, f.size)).astype(int))
        hj_ref = np.empty((sub.size, nc, nc), complex)
        for j, k in enumerate(sub):
            kron = np.kron(h_ci[k].T, h_ic[k])
            vec_p = np.linalg.lstsq(kron, d[k].reshape(-1, order="F"), rcond=None)[0]
            hj_ref[j] = np.linalg.inv(vec_p.reshape(nc, nc, order="F")) - h_cc[k]
        t2 = time.perf_counter()
        t_ours += t1 - t0
        t_ref += (t2 - t1) * f.size / sub.size  # scaled to all lines of the chunk
        ours = res.joint.values[sub]
        rel = np.linalg.norm(ours - hj_ref, axis=(1, 2)) / np.linalg.norm(hj_ref, axis=(1, 2))
        max_diff = max(max_diff, float(np.median(rel)))
    print(f"full-matrix identification: nc = 12, L = 15, {args.lines} lines (chunks of {args.chunk})")
    print(f"  textbook Kronecker least squares, per-line lstsq (225 x 144) : {t_ref:8.3f} s "
          f"(timed on {args.ref_lines} lines per chunk, scaled per line)")
    print(f"  identify_joint_matrix (batched, equilibrated pinv)         : {t_ours:8.3f} s   ratio {t_ref / t_ours:6.1f}x faster")
    print(f"  per-line time: {1e6 * t_ours / args.lines:.1f} us (ours) vs {1e6 * t_ref / args.lines:.1f} us (textbook)")
    print(f"  median relative difference of the identified joints: {max_diff:.2e}")


if __name__ == "__main__":
    main()
