"""Benchmark: FRF synthesis of a 200-DOF stepped shaft over 5,000 lines.

Prints wall times and ratios, all measured in this process:
- direct solution, default algorithm (exact sum over all modes: the damping
  here is classical),
- direct solution by batched LU (one ``np.linalg.solve`` per memory chunk of
  stacked ``(n_chunk, n, n)`` dynamic stiffness matrices),
- modal superposition with static residual (``method="modal"``),
- on 500 of the lines: the LU equations solved line by line in a Python loop
  (reference only; the library never does this) vs the batched LU,
and the largest differences between them. Not a test: no timing assertions.

Run: ``python bench/bench_fe_synthesis.py``
"""

from __future__ import annotations

import time

import numpy as np

from jointdb.fe import BeamModel, Clamp, ModalDamping, NamedPoint, Segment, frf_direct


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


def main() -> None:
    model = stepped_shaft()
    mats = model.assemble()
    n_dof = mats.K.shape[0]
    freq = np.linspace(1.0, 10000.0, 5000)
    print(f"model: {n_dof} DOF ({int((~mats.fixed).sum())} free), {freq.size} lines {freq[0]:g}-{freq[-1]:g} Hz, "
          f"outputs {len(model.points) * 2} DOFs (3 points x, ry)")

    t_auto, direct = timed(lambda: model.frf(freq, method="direct"))  # spectral: classical damping
    t_modal, modal = timed(lambda: model.frf(freq, method="modal"))
    t_lu, direct_lu = timed(lambda: model.frf(freq, method="direct", algorithm="lu"), repeat=1)

    # reference for the LU path: the same equations, one line at a time in Python (500 lines)
    mesh = model.mesh()
    idx = [mesh.dof(mesh.node_at(p.position), d) for p in model.points for d in ("x", "ry")]
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
