"""Benchmark: FRF synthesis of a 200-DOF stepped shaft over 5,000 lines (the spectral path).

All timed in this process (one BLAS thread, interleaved runs, medians):

- ``plain``: the reference — ``scipy.linalg.eigh(K, M)`` of the free DOFs, the
  modal damping and loss ``φ_rᵀ C φ_r``, ``φ_rᵀ K_loss φ_r`` and
  ``einsum("ir,fr,jr->fij", φ, 1/(ω_r² + iκ_r + iωc_r − ω²), φ, optimize=True)``;
- ``frf_direct(algorithm="spectral")`` on the assembled matrices (which also
  counts the rigid-body modes and checks that the damping is classical);
- ``BeamModel.frf(method="direct")``: the same from the model, including the
  assembly and the ingredients (modal damping needs an eigen-solution of its own).

Printed as ratios against ``plain`` (goal: ``frf_direct`` <= 1), with the
largest differences. ``--lu`` adds the batched LU path, modal superposition and
a Python loop of solves on 500 lines (slow; reference only).

Run: ``python bench/bench_fe_synthesis.py [--repeat 7] [--lu]``
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import scipy.linalg  # noqa: E402

from _synthetic import interleaved_timing  # noqa: E402  (bench/ is on sys.path when run as a script)

from jointdb.fe import BeamModel, Clamp, ModalDamping, NamedPoint, Segment, frf_direct  # noqa: E402


def stepped_shaft() -> BeamModel:
    segs = (
        Segment(0.10, 0.040, 0.010, "steel"),
        Segment(0.12, 0.032, 0.010, "steel"),
        Segment(0.08, 0.024, 0.0, "steel"),
        Segment(0.096, 0.012, 0.0, "carbide"),
    )
    points = (NamedPoint("tip", 0.396, 1), NamedPoint("gauge", 0.30, 2), NamedPoint("flange", 0.10, 3))
    # 0.396 m / 0.004 m = 99 elements, 100 nodes, 200 DOFs (planar: x, ry)
    return BeamModel(segs, points, (Clamp(0.0), ModalDamping(0.02)), max_element_length=0.004)


def timed(fn, repeat=3):
    best = np.inf
    result = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        result = fn()
        best = min(best, time.perf_counter() - t0)
    return best, result


def plain_spectral(mats, freq, idx):
    """The reference: eigh, modal damping/loss, einsum(optimize=True)."""
    free = ~mats.fixed
    kf, mf = mats.K[np.ix_(free, free)], mats.M[np.ix_(free, free)]
    cf, lf = mats.C[np.ix_(free, free)], mats.K_loss[np.ix_(free, free)]
    lam, phi = scipy.linalg.eigh(kf, mf)
    c = np.einsum("ir,ij,jr->r", phi, cf, phi, optimize=True)
    kappa = np.einsum("ir,ij,jr->r", phi, lf, phi, optimize=True)
    pos = np.cumsum(free)[idx] - 1
    w = 2 * np.pi * freq[:, None]
    den = lam[None, :] + 1j * kappa[None, :] + 1j * w * c[None, :] - w**2
    return np.einsum("ir,fr,jr->fij", phi[pos], 1.0 / den, phi[pos], optimize=True)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--lu", action="store_true", help="also the LU, modal and looped paths (slow)")
    args = ap.parse_args(argv)
    model = stepped_shaft()
    mats = model.assemble()
    n_dof = mats.K.shape[0]
    freq = np.linspace(1.0, 10000.0, 5000)
    mesh = model.mesh()
    idx = [mesh.dof(mesh.node_at(p.position), d) for p in model.points for d in ("x", "ry")]
    print(f"model: {n_dof} DOF ({int((~mats.fixed).sum())} free), {freq.size} lines {freq[0]:g}-{freq[-1]:g} Hz, "
          f"outputs {len(idx)} DOFs (3 points x, ry); median of {args.repeat} interleaved runs")
    contenders = {
        "plain": lambda: plain_spectral(mats, freq, idx),
        "frf_direct": lambda: frf_direct(mats, freq, idx, algorithm="spectral"),
        "model.frf": lambda: model.frf(freq, method="direct"),
    }
    out, ratio, med = interleaved_timing(contenders, args.repeat)
    ref = out["plain"]
    scale = np.abs(ref).max()
    print(f"  plain eigh + einsum(optimize=True) (reference) : {med['plain'] * 1e3:8.1f} ms")
    print(f"  frf_direct(algorithm='spectral')               : {med['frf_direct'] * 1e3:8.1f} ms   / plain = "
          f"{ratio['frf_direct']:5.2f}   (goal <= 1)")
    print(f"  BeamModel.frf(method='direct'), with assembly  : {med['model.frf'] * 1e3:8.1f} ms   / plain = "
          f"{ratio['model.frf']:5.2f}")
    print(f"  max |frf_direct - plain| / max|H| = {np.abs(out['frf_direct'] - ref).max() / scale:.1e}, "
          f"max |model.frf - plain| / max|H| = {np.abs(out['model.frf'].values - ref).max() / scale:.1e}")
    if args.lu:
        lu_paths(model, mats, freq, idx, out["model.frf"])


def lu_paths(model, mats, freq, idx, direct) -> None:
    t_auto, _ = timed(lambda: model.frf(freq, method="direct"))  # spectral: classical damping
    t_modal, modal = timed(lambda: model.frf(freq, method="modal"))
    t_lu, direct_lu = timed(lambda: model.frf(freq, method="direct", algorithm="lu"), repeat=1)

    # reference for the LU path: the same equations, one line at a time in Python (500 lines)
    free = ~mats.fixed
    K, M, C = (a[np.ix_(free, free)] for a in (mats.K + 1j * mats.K_loss, mats.M, mats.C))
    pos = np.cumsum(free)[idx] - 1
    rhs = np.zeros((K.shape[0], len(idx)))
    rhs[pos, np.arange(len(idx))] = 1.0
    sub = freq[::10]

    def loop():
        out = np.empty((sub.size, len(idx), len(idx)), dtype=complex)
        for k, f in enumerate(sub):
            w = 2 * np.pi * f
            out[k] = np.linalg.solve(K + 1j * w * C - w**2 * M, rhs)[pos]
        return out

    t_loop, looped = timed(loop, repeat=1)
    t_batched_sub, batched_sub = timed(lambda: frf_direct(mats, sub, idx, algorithm="lu"), repeat=1)

    n_modes = int(np.sum(model.modes().freq_hz < 2 * freq[-1]))
    scale = np.abs(direct_lu.values).max()
    print(f"direct, spectral (default)   : {t_auto * 1e3:10.1f} ms")
    print(f"direct, batched LU           : {t_lu * 1e3:10.1f} ms   LU / spectral = {t_lu / t_auto:8.1f}")
    print(f"modal ({n_modes} modes + residual) : {t_modal * 1e3:10.1f} ms   direct(spectral) / modal = "
          f"{t_auto / t_modal:6.2f}   direct(LU) / modal = {t_lu / t_modal:8.1f}")
    print(f"500 lines: Python loop of solves {t_loop * 1e3:.1f} ms vs batched LU {t_batched_sub * 1e3:.1f} ms "
          f"(loop / batched = {t_loop / t_batched_sub:.2f})")
    print(f"max |spectral - LU| / max|H|  = {np.abs(direct.values - direct_lu.values).max() / scale:.1e}")
    print(f"max |batched - loop| / max|H| = {np.abs(batched_sub - looped).max() / np.abs(looped).max():.1e}")
    tip = direct_lu.entry("1x", "1x")
    print(f"max |LU - modal| / max|H|     = {np.abs(direct_lu.values - modal.values).max() / scale:.1e}  "
          f"(tip 1x/1x: {np.abs(tip - modal.entry('1x', '1x')).max() / np.abs(tip).max():.1e})")


if __name__ == "__main__":
    main()
