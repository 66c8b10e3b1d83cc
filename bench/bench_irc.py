#!/usr/bin/env python
"""Benchmark: full-matrix joint identification, 12 x 12 joint, L = 15 measured DOFs, 10,000 lines.

All timed in this process on the same data (one BLAS thread, interleaved runs, medians):

- ``plain pinv``: the formula written with batched ``numpy.linalg.pinv``,
  ``P = H_IC⁺ D H_CI⁺``, ``H^J = P⁺ − H_CC`` (three batched SVDs; no
  conditioning, no residual) — the reference of the issue's table;
- ``normal equations``: ``P = (H_ICᴴH_IC)⁻¹ H_ICᴴ D H_CIᴴ (H_CI H_CIᴴ)⁻¹``,
  ``H^J = P⁻¹ − H_CC`` by batched ``solve``/``inv`` (no conditioning, no residual);
- ``identify_joint_matrix`` (``symmetrize=False``, as the references), which also
  returns the condition number per line and the residual of the re-coupled
  measurement: once with reciprocal substructures (their receptance matrices
  exactly symmetric, as FE models and reciprocity-completed measurements are)
  and once with slightly non-reciprocal ones (no symmetry to reuse).

Printed as ratios against ``plain pinv`` (goal <= 0.25) with the median
relative differences between the identified joints, and (not timed) the
reported condition numbers against ``cond₂`` by SVD of the equilibrated
``H_IC``, ``H_CI``, in units of ``eps·(κ_l² + κ_r²)``. ``--kron`` adds the
textbook Kronecker least squares ``(H_CIᵀ ⊗ H_IC) vec P = vec D`` solved line
by line with ``lstsq`` on a subset of lines (slow; a check, not a timing).

Usage: .venv/bin/python bench/bench_irc.py [--lines 10000] [--repeat 3] [--kron]
"""

from __future__ import annotations

import argparse
import os

# single-threaded BLAS for every contender (small matrices; avoids thread thrashing on shared machines)
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from _synthetic import interleaved_timing, modal_receptance  # noqa: E402  (bench/ is on sys.path when run as a script)
from jointdb.coupling import identify_joint_matrix  # noqa: E402
from jointdb.frf import DIRECTIONS, FRF, Dof  # noqa: E402


def rel(a, b):
    """Median over lines of ‖a − b‖_F / ‖b‖_F."""
    return float(np.median(np.linalg.norm(a - b, axis=(1, 2)) / np.linalg.norm(b, axis=(1, 2))))


def main(argv=None) -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--lines", type=int, default=10_000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--kron", action="store_true", help="also check against per-line Kronecker lstsq (100 lines)")
    args = ap.parse_args(argv)
    # A: 8 measured + 6 contact DOFs; B: 7 measured + 6 contact -> L = 15, nc = 12
    a_meas = [Dof(i + 1, "x") for i in range(8)]
    b_meas = [Dof(i + 101, "x") for i in range(7)]
    a_c = [Dof(50, d) for d in DIRECTIONS]
    b_c = [Dof(150, d) for d in DIRECTIONS]
    la, lb = a_meas + a_c, b_meas + b_c
    measured = [("A", d) for d in a_meas] + [("B", d) for d in b_meas]
    f = np.linspace(20.0, 5000.0, args.lines)
    ha, hb = modal_receptance(f, len(la), 3), modal_receptance(f, len(lb), 4)
    rng = np.random.default_rng(0)
    g = modal_receptance(f, 15, 5) + 0.01 * rng.standard_normal((f.size, 15, 15))
    g = 0.5 * (g + np.swapaxes(g, 1, 2))
    assembly = FRF(f, g, a_meas + b_meas, a_meas + b_meas)
    subs = {"A": FRF(f, ha, la, la), "B": FRF(f, hb, lb, lb)}
    # non-reciprocal variant: a 1e-6 relative asymmetry in both substructures
    skew = [1e-6 * np.abs(h).max() * (rng.standard_normal(h.shape) + 1j * rng.standard_normal(h.shape))
            for h in (ha, hb)]
    subs_nr = {"A": FRF(f, ha + skew[0], la, la), "B": FRF(f, hb + skew[1], lb, lb)}

    # the same blocks as plain arrays for the references
    L, nc = 15, 12
    h_ii = np.zeros((f.size, L, L), complex)
    h_ic = np.zeros((f.size, L, nc), complex)
    h_cc = np.zeros((f.size, nc, nc), complex)
    h_ii[:, :8, :8], h_ii[:, 8:, 8:] = ha[:, :8, :8], hb[:, :7, :7]
    h_ic[:, :8, :6], h_ic[:, 8:, 6:] = ha[:, :8, 8:], hb[:, :7, 7:]
    h_cc[:, :6, :6], h_cc[:, 6:, 6:] = ha[:, 8:, 8:], hb[:, 7:, 7:]
    h_ci = np.swapaxes(h_ic, 1, 2).copy()
    d = h_ii - g

    def plain():
        p = np.linalg.pinv(h_ic) @ d @ np.linalg.pinv(h_ci)
        return np.linalg.pinv(p) - h_cc

    def normal():
        a_h, b_h = np.conj(np.swapaxes(h_ic, 1, 2)), np.conj(np.swapaxes(h_ci, 1, 2))
        x = np.linalg.solve(a_h @ h_ic, a_h @ d @ b_h)  # (A^H A)^-1 A^H D B^H
        p = np.swapaxes(np.linalg.solve(np.swapaxes(h_ci @ b_h, 1, 2), np.swapaxes(x, 1, 2)), 1, 2)
        return np.linalg.inv(p) - h_cc

    def ours(s):
        return identify_joint_matrix(assembly, s, measured, "A", a_c, "B", b_c, symmetrize=False)

    contenders = {
        "plain": plain,
        "normal": normal,
        "ours": lambda: ours(subs),
        "ours_nr": lambda: ours(subs_nr),
    }
    out, ratio, med = interleaved_timing(contenders, args.repeat)
    hj = out["plain"]
    print(f"full-matrix identification: nc = {nc}, L = {L}, {args.lines} lines "
          f"(median of {args.repeat} interleaved runs; ratios are medians of per-run ratios)")
    print(f"  plain batched pinv (reference)               : {med['plain']:7.3f} s")
    print(f"  normal equations (solve/inv)                 : {med['normal']:7.3f} s   / plain = {ratio['normal']:5.2f}")
    print(f"  identify_joint_matrix, reciprocal subs       : {med['ours']:7.3f} s   / plain = {ratio['ours']:5.2f}"
          "   (goal <= 0.25, and <= 0.2 s)")
    print(f"  identify_joint_matrix, non-reciprocal subs   : {med['ours_nr']:7.3f} s   / plain = {ratio['ours_nr']:5.2f}")
    print("  median relative difference of the joints vs plain pinv: "
          f"normal {rel(out['normal'], hj):.1e}, ours {rel(out['ours'].joint.values, hj):.1e}, "
          f"non-reciprocal {rel(out['ours_nr'].joint.values, hj):.1e} (its data differ by 1e-6)")
    print(f"  condition (ours): median {np.median(out['ours'].condition):.3g}, max {np.max(out['ours'].condition):.3g}; "
          f"residual median {np.median(out['ours'].residual):.3g}")
    # the reported condition number against the 2-norm one by SVD of the equilibrated H_IC, H_CI (not timed)
    for key, subs_k in (("ours", (ha, hb)), ("ours_nr", tuple(h + k for h, k in zip((ha, hb), skew)))):
        ic = np.zeros((f.size, L, nc), complex)
        ci = np.zeros((f.size, nc, L), complex)
        ic[:, :8, :6], ic[:, 8:, 6:] = subs_k[0][:, :8, 8:], subs_k[1][:, :7, 7:]
        ci[:, :6, :8], ci[:, 6:, 8:] = subs_k[0][:, 8:, :8], subs_k[1][:, 7:, :7]
        kl = np.linalg.cond(ic / np.linalg.norm(ic, axis=1)[:, None, :])
        kr = np.linalg.cond(ci / np.linalg.norm(ci, axis=2)[:, :, None])
        err = np.abs(out[key].condition - kl * kr) / (kl * kr) / (np.finfo(float).eps * (kl**2 + kr**2))
        print(f"  condition vs SVD ({'reciprocal' if key == 'ours' else 'non-reciprocal'}): "
              f"largest relative difference {err.max():.2g} eps·(κ_l² + κ_r²) (median {np.median(err):.2g})")
    if args.kron:
        sub = np.unique(np.linspace(0, f.size - 1, 100).astype(int))
        ref = np.empty((sub.size, nc, nc), complex)
        for j, k in enumerate(sub):
            kron = np.kron(h_ci[k].T, h_ic[k])
            vec_p = np.linalg.lstsq(kron, d[k].reshape(-1, order="F"), rcond=None)[0]
            ref[j] = np.linalg.inv(vec_p.reshape(nc, nc, order="F")) - h_cc[k]
        print(f"  Kronecker lstsq check on {sub.size} lines: median relative difference "
              f"{rel(out['ours'].joint.values[sub], ref):.1e}")


if __name__ == "__main__":
    main()
