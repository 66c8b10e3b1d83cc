#!/usr/bin/env python
"""Bench: coverage of the 5–95 % bands carried from the tap test to the tool tip and the lobes (issue 13).

Synthetic campaign: the Table 4.1 planar joint (k = 2e6 N/m, c = 100 N·s/m, k_θ = 8e4 N·m/rad,
c_θ = 80 N·m·s/rad) between a clamped Ø30 mm beam (A) and a Ø16 mm, 0.15 m tool (B);
600 lines 5–3000 Hz. For each noise draw (1 % complex noise on G_11, G_12):

1. the joint is fitted by output error (``fit_planar_joint``) → θ and its covariance;
2. 200 joints θ_s ~ N(θ, Σ) are coupled, all at once, to a *different* tool (0.12 m) — a
   prediction for an assembly never measured;
3. the 5–95 % band of the tip peak |G| and of the critical depths is compared with the truth
   (the same assembly coupled with the true joint).

Critical depths: turning (K_f = 1e9 N/m², b = −1/(2 K_f min Re G)), and milling (ZOA, 2 teeth,
K_t = 6e8, K_r = 2e8 N/m², slotting, the x FRF used for y too) at 25 spindle speeds.
Coverage = fraction of draws whose band holds the truth (nominal 90 %).

Reported seeds start at 7000 (development used others).
Usage: PYTHONPATH=. .venv/bin/python bench/bench_uncertainty.py [--draws 120] [--samples 200] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "coupling"))

import numpy as np  # noqa: E402
from coupling_beams import beam, labels_for  # noqa: E402
from coupling_cases import add_noise  # noqa: E402
from test_coupling_planar import CR, CX, KR, KX, build_case  # noqa: E402

from jointdb.coupling import fit_planar_joint, spring_damper_joint  # noqa: E402
from jointdb.coupling._matrices import receptance_from_matrices  # noqa: E402
from jointdb.coupling._oe_core import coupled_blocks  # noqa: E402
from jointdb.coupling._propagate import (  # noqa: E402
    ensemble_coupled,
    spring_damper_samples,
    spring_pairs_stiffness,
    uncertainty_record,
)
from jointdb.frf import FRF  # noqa: E402
from jointdb.stability import MillingCut, milling_lobes_zoa  # noqa: E402

FREQ = np.linspace(5.0, 3000.0, 600)
KF = 1e9
CUT = MillingCut(2, 6e8, 2e8, 1.0, True)
SPEEDS = np.linspace(6000, 30000, 25)


def new_tool(length=0.12):
    kb, mb = beam(length, 0.016, 3, eta=0.01)
    return receptance_from_matrices(FREQ, kb, mb, labels_for([2, 201, 202, 1]))


def milling_depths(tips: np.ndarray) -> np.ndarray:
    """ZOA limiting depth per speed for each tip receptance row (n, nf) → (n, n_speeds)."""
    out = []
    for h in tips:
        frf = FRF(FREQ, h[:, None, None], ["1x"], ["1x"], "receptance")
        fy = FRF(FREQ, h[:, None, None], ["1y"], ["1y"], "receptance")
        out.append(milling_lobes_zoa(frf, CUT, fy, spindle_speed_rpm=SPEEDS).depth_m)
    return np.array(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--draws", type=int, default=120)
    ap.add_argument("--samples", type=int, default=200)
    ap.add_argument("--json", type=Path)
    a = ap.parse_args()
    A, B, G = build_case(FREQ)
    B2 = new_tool()
    blocks = coupled_blocks({"A": A, "B": B2}, "A", ["3x", "3ry"], "B", ["2x", "2ry"], [("B", "1x")], [("B", "1x")])
    true_joint = spring_damper_joint(FREQ, [KX, KR], [CX, CR], ["3x", "3ry"])
    g_true = ensemble_coupled(blocks, spring_pairs_stiffness(true_joint.values[None]))[0, :, 0, 0]
    peak_true = np.abs(g_true).max()
    turn_true = -1 / (2 * KF * g_true.real.min())
    mill_true = milling_depths(g_true[None])[0]
    hit = {"tip peak |G|": [], "turning critical depth": [], "milling critical depth (min over speeds)": [],
           "milling depth per speed (mean over speeds)": []}
    widths = {k: [] for k in hit}
    t0 = time.perf_counter()
    for seed in range(7000, 7000 + a.draws):
        fit = fit_planar_joint(add_noise(G, 0.01, seed), A, 3, B, 2, 1)
        rec = uncertainty_record(fit)
        hj = spring_damper_samples(rec, FREQ, a.samples, seed=seed + 10_000)
        tips = ensemble_coupled(blocks, spring_pairs_stiffness(hj))[:, :, 0, 0]  # (samples, nf)
        for key, samples, truth in (
                ("tip peak |G|", np.abs(tips).max(axis=1), peak_true),
                ("turning critical depth", -1 / (2 * KF * tips.real.min(axis=1)), turn_true)):
            lo, hi = np.quantile(samples, [0.05, 0.95])
            hit[key].append(lo <= truth <= hi)
            widths[key].append((hi - lo) / truth)
        md = milling_depths(tips)
        lo, hi = np.nanquantile(md, [0.05, 0.95], axis=0)
        hit["milling depth per speed (mean over speeds)"].append(np.mean((lo <= mill_true) & (mill_true <= hi)))
        widths["milling depth per speed (mean over speeds)"].append(np.median((hi - lo) / mill_true))
        crit = np.nanmin(md, axis=1)
        lo, hi = np.quantile(crit, [0.05, 0.95])
        hit["milling critical depth (min over speeds)"].append(lo <= np.nanmin(mill_true) <= hi)
        widths["milling critical depth (min over speeds)"].append((hi - lo) / np.nanmin(mill_true))
    dt = time.perf_counter() - t0
    print(f"{a.draws} noise draws × {a.samples} sampled joints, 1 % complex noise, prediction for a 0.12 m tool "
          f"never measured ({dt:.0f} s)")
    print(f"truth: tip peak {peak_true:.4g} m/N, turning b_crit {turn_true * 1e3:.4g} mm, "
          f"milling b_crit {np.nanmin(mill_true) * 1e3:.4g} mm")
    print(f"{'quantity':<44} {'coverage of 90 % band':>22} {'median band width':>18}")
    res = {}
    for k in hit:
        cov, wid = float(np.mean(hit[k])), float(np.median(widths[k]))
        res[k] = {"coverage": cov, "median_relative_width": wid}
        print(f"{k:<44} {cov:22.1%} {wid:18.2%}")
    if a.json:
        a.json.write_text(json.dumps({"draws": a.draws, "samples": a.samples, "results": res}, indent=2) + "\n")


if __name__ == "__main__":
    main()
