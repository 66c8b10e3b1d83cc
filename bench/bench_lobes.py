"""Benchmark: stability lobes of the Insperger–Stépán milling benchmark.

300 spindle speeds (5000–25000 rpm), by the zero-order approximation (ZOA) and by
first-order semi-discretization (SD, 40 intervals) with the direct critical-depth
search; then the classical dense depth-grid SD (spectral radius on a speed × depth
grid, 200 depths 0–6 mm) on a subset of the speeds, in the same process, and the
cost ratio per spindle speed. Prints ratios, not absolute claims.

Run: .venv/bin/python bench/bench_lobes.py
"""

import os

# one BLAS thread: the 100-dimensional eigenproblems are slower multi-threaded on a shared machine
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import time  # noqa: E402

import numpy as np  # noqa: E402

from jointdb.modal import ModalModel  # noqa: E402
from jointdb.stability import (  # noqa: E402
    MillingCut,
    critical_depth,
    milling_lobes_sd,
    milling_lobes_sd_grid,
    milling_lobes_zoa,
    sd_system,
)

M, FN, ZETA = 0.03993, 922.0, 0.011
K = M * (2 * np.pi * FN) ** 2
MODEL = ModalModel.from_modal_parameters([FN], [ZETA], [K], "1x")
SPEEDS = np.linspace(5000, 25000, 300)
GRID_DEPTHS = np.linspace(0.0, 6e-3, 201)[1:]
GRID_SUBSET = SPEEDS[::20]  # 15 speeds for the dense-grid reference


def timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t0


def main() -> None:
    frf = MODEL.synthesize(np.arange(300, 2000, 0.05))
    print(f"Insperger–Stépán benchmark: 2 teeth, Kt 6e8, Kn 2e8 N/m², fn {FN} Hz, ζ {ZETA}, m {M} kg; "
          f"{SPEEDS.size} speeds {SPEEDS[0]:.0f}–{SPEEDS[-1]:.0f} rpm; BLAS threads {os.environ['OPENBLAS_NUM_THREADS']}")
    for immersion in (1.0, 0.1):
        cut = MillingCut(2, 6e8, 2e8, immersion, True)
        zoa, t_zoa = timed(lambda: milling_lobes_zoa(frf, cut, spindle_speed_rpm=SPEEDS))
        sd, t_sd = timed(lambda: milling_lobes_sd(MODEL, cut, SPEEDS, n_intervals=40))
        sub = milling_lobes_sd(MODEL, cut, GRID_SUBSET, n_intervals=40)
        grid, t_grid = timed(lambda: milling_lobes_sd_grid(MODEL, cut, GRID_SUBSET, GRID_DEPTHS, n_intervals=40))
        per_zoa = t_zoa / SPEEDS.size
        per_sd = t_sd / SPEEDS.size
        per_grid = t_grid / GRID_SUBSET.size
        evals = sd.info["evaluations"] / SPEEDS.size
        dev = np.abs(np.where(np.isfinite(grid.depth_m), grid.depth_m, np.nan) - sub.depth_m)
        print(f"\na/D = {immersion:g}, down-milling")
        note = (f" (analytic slotting floor 2kζ(1+ζ)/(N·Kn/4) = {2 * K * ZETA * (1 + ZETA) / 1e8 * 1e3:.4f} mm)"
                if immersion == 1.0 else "")
        print(f"  ZOA : {per_zoa * 1e3:8.3f} ms per speed   floor {zoa.min_depth_m * 1e3:.4f} mm{note}")
        print(f"  SD  : {per_sd * 1e3:8.3f} ms per speed   {evals:.1f} monodromy evaluations per speed, "
              f"floor {sd.min_depth_m * 1e3:.4f} mm, flip at {int(np.sum(sd.kind == 'flip'))} of {SPEEDS.size} speeds")
        print(f"  SD dense grid ({GRID_DEPTHS.size} depths, {GRID_SUBSET.size} speeds): {per_grid * 1e3:8.3f} ms per speed; "
              f"resolution {(GRID_DEPTHS[1] - GRID_DEPTHS[0]) * 1e6:.0f} µm, max |grid − direct| {np.nanmax(dev) * 1e6:.1f} µm")
        print(f"  cost ratio dense-grid / direct SD = {per_grid / per_sd:.1f}x ; SD / ZOA = {per_sd / per_zoa:.1f}x")

    print("\nSD convergence with intervals m (a/D = 0.1): critical depth [mm], kind; error vs m = 320")
    sysm = sd_system(MODEL, MillingCut(2, 6e8, 2e8, 0.1, True))
    for speed in (8000.0, 17000.0):
        ref = critical_depth(sysm, speed, 320, rtol=1e-8)[0]
        cells = []
        for m in (10, 20, 40, 80, 160):
            a, _, kind, _, _ = critical_depth(sysm, speed, m, rtol=1e-8)
            cells.append(f"m={m}: {a * 1e3:.4f} ({kind}, {abs(a - ref) / ref:.1e})")
        print(f"  {speed:.0f} rpm: " + "; ".join(cells))


if __name__ == "__main__":
    main()
