"""Regenerate the tables of docs/validation/simulate.md: time-domain simulation vs semi-discretization.

    PYTHONPATH=. python docs/validation/make_simulate_table.py

The same cases as tests/optimize/test_simulate.py: the single-DOF benchmark of Insperger, Mann,
Stépán & Bayly (2003) at a/D = 0.05 and 1 (down-milling, 2 teeth), and the demo tip (4 teeth, a/D 0.5).
"""

from pathlib import Path

import numpy as np

from jointdb.io import read_frf_uff58
from jointdb.modal import ModalModel, fit_tool_tip
from jointdb.stability import MillingCut, milling_lobes_sd, simulate_milling

ROOT = Path(__file__).resolve().parents[2]


def table(title, model, cut, speeds, revolutions, steps):
    sd = milling_lobes_sd(model, cut, speeds, n_intervals=60)
    d = np.asarray(sd.depth_m)
    sims = simulate_milling(model, cut, np.concatenate([speeds, speeds]), np.concatenate([0.9 * d, 1.1 * d]),
                            feed_per_tooth_m=5e-5, revolutions=revolutions, steps_per_tooth=steps)
    n = speeds.size
    print(f"\n### {title}\n")
    print("| speed [rpm] | SD limit [mm] | kind | SD f_c [Hz] | 0.9×: verdict (statistic) | 1.1×: verdict (statistic) "
          "| simulated f_c [Hz] | f_c error |")
    print("|---|---|---|---|---|---|---|---|")
    ok_lo = ok_hi = 0
    worst = 0.0
    for i in range(n):
        lo, hi = sims[i], sims[n + i]
        ok_lo += not lo.chatter
        ok_hi += hi.chatter
        err = abs(hi.chatter_freq_hz - sd.chatter_freq_hz[i]) / sd.chatter_freq_hz[i] if hi.chatter else float("nan")
        worst = max(worst, err) if np.isfinite(err) else worst
        print(f"| {speeds[i]:.0f} | {d[i] * 1e3:.3f} | {sd.kind[i]} | {sd.chatter_freq_hz[i]:.1f} | "
              f"{'chatter' if lo.chatter else 'stable'} ({lo.statistic:.2g}) | "
              f"{'chatter' if hi.chatter else 'stable'} ({hi.statistic:.2g}) | {hi.chatter_freq_hz:.1f} | "
              f"{err * 100:.2f} % |")
    print(f"\nStable at 0.9×: {ok_lo}/{n}; chatter at 1.1×: {ok_hi}/{n}; largest chatter-frequency error "
          f"{worst * 100:.2f} %.")


def main():
    m, fn, zeta = 0.03993, 922.0, 0.011
    bench = ModalModel.from_modal_parameters([fn], [zeta], [m * (2 * np.pi * fn) ** 2], "1x")
    speeds = np.linspace(6000, 24000, 10)
    for imm in (0.05, 1.0):
        table(f"Single-DOF benchmark, a/D = {imm:g}, down-milling, 2 teeth (100 steps per tooth period, "
              f"200 revolutions)", bench, MillingCut(2, 6e8, 2e8, imm, True), speeds, 200, 100)
    model, _ = fit_tool_tip(read_frf_uff58(ROOT / "tests" / "optimize" / "data" / "demo-tip.uff"))
    table("Demo tip (x and y planes, pLSCF fit), 4 teeth, a/D = 0.5, down-milling (150 revolutions)", model,
          MillingCut(4, 7.96e8, 0.212 * 7.96e8, 0.5, True), np.linspace(8000, 26000, 10), 150, None)


if __name__ == "__main__":
    main()
