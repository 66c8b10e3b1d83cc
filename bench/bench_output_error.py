#!/usr/bin/env python
"""Bench: output-error joint identification under 1 % complex noise, many seeds (issue 13).

For each seed the assembly FRFs get independent 1 % complex Gaussian noise
(``G (1 + 0.01 z)``, ``z`` unit complex normal) and the joint is identified

- by the per-line IRC + constant (k, c) fit on its reliable lines (the old route), and
- by the output-error fit (all lines at once, relative weights, started from the IRC estimate).

Printed per parameter: the largest and the 90th-percentile |relative error| of each
route, the median relative standard error reported by the output-error fit, and the
fraction of seeds with |error| ≤ 2σ (the coverage of the standard error; ≈ 95 % expected).

Cases: Table 4.1 planar joint (600 lines, 5–3000 Hz; fitted G_11, G_12), and the Table 5.1
n-point springs (100 lines, 20–2000 Hz; 6 × 6 measured block).
Reported seeds start at 5000 (development used 1000.. and 2000.., the tests 100.. and 200..).

Usage: PYTHONPATH=. .venv/bin/python bench/bench_output_error.py [--seeds 60] [--json out.json]
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
from coupling_cases import TABLE_5_1_C, TABLE_5_1_K, add_noise, plate_frfs, plates  # noqa: E402
from test_coupling_planar import CR, CX, KR, KX, build_case  # noqa: E402

from jointdb.coupling import (  # noqa: E402
    fit_constant_kc,
    fit_n_point_joints,
    fit_planar_joint,
    identify_n_point_joints,
    identify_planar_joint,
)
from jointdb.frf import Dof  # noqa: E402


def _rows(names, true, irc, oe, sd):
    irc, oe, sd = np.abs(np.array(irc) / true - 1), np.array(oe), np.array(sd)
    err = np.abs(oe / true - 1)
    cover = np.abs(oe - true) <= 2 * sd
    out = []
    for j, n in enumerate(names):
        out.append({"parameter": n, "irc_max": float(irc[:, j].max()), "irc_p90": float(np.quantile(irc[:, j], 0.9)),
                    "oe_max": float(err[:, j].max()), "oe_p90": float(np.quantile(err[:, j], 0.9)),
                    "oe_rel_se_median": float(np.median(sd[:, j] / true[j])),
                    "coverage_2sigma": float(cover[:, j].mean())})
    return out


def planar(seeds):
    A, B, G = build_case()
    true = np.array([KX, CX, KR, CR])
    irc, oe, sd, names = [], [], [], None
    for s in seeds:
        g = add_noise(G, 0.01, s)
        r = identify_planar_joint(g, A, 3, B, 2, 1)
        kc = fit_constant_kc(r.joint, mask=~r.unreliable)
        irc.append(np.ravel(np.column_stack([kc.k, kc.c])))
        f = fit_planar_joint(g, A, 3, B, 2, 1)
        oe.append(f.values)
        sd.append(f.std_error)
        names = f.names
    return _rows(names, true, irc, oe, sd)


def n_point(seeds):
    freq = np.linspace(20.0, 2000.0, 100)
    case = plates(freq)
    fa, fb, g0 = plate_frfs(freq, case)
    z = lambda ns: [Dof(n, "z") for n in ns]  # noqa: E731
    args = (z(case["internal"]), z(case["a_bolts"]))
    true = np.ravel(np.column_stack([TABLE_5_1_K, TABLE_5_1_C]))
    irc, oe, sd, names = [], [], [], None
    for s in seeds:
        g = add_noise(g0, 0.01, s)
        r = identify_n_point_joints(g, fa, *args, fb, z(case["b_bolts"]))
        kc = fit_constant_kc(r.joint, mask=~r.unreliable)
        irc.append(np.ravel(np.column_stack([kc.k, kc.c])))
        f = fit_n_point_joints(g, fa, *args, fb, z(case["b_bolts"]))
        oe.append(f.values)
        sd.append(f.std_error)
        names = f.names
    return _rows(names, true, irc, oe, sd)


def planning(seeds):
    """Table 4.1: default points (1x/1x, 1x/2x) vs the A-optimal pair for k_θ, c_θ; same noise, same count."""
    from jointdb.coupling._oe_core import SpringDamperModel, coupled_blocks, fit
    from jointdb.coupling._plan import plan_measurements

    A, B, _ = build_case()
    cands = [("B", "1x"), ("B", "201x"), ("B", "202x"), ("B", "2x"), ("A", "3x"), ("A", "103x")]
    bl = coupled_blocks({"A": A, "B": B}, "A", ["3x", "3ry"], "B", ["2x", "2ry"], cands, cands)
    m = SpringDamperModel((Dof(3, "x"), Dof(3, "ry")))
    th = m.start(np.array([KX, KR]), np.array([CX, CR]))
    true = np.array([KX, CX, KR, CR])
    targets = ["k 3ry", "c 3ry"]
    best = plan_measurements(m, th, bl, targets=targets).rows[0]
    default = plan_measurements(m, th, bl, targets=targets, must_include=[(0, 0), (0, 3)], top=1).rows[0]
    label = {f"{bl.outputs[o]}/{bl.inputs[i]}": (o, i) for o in range(6) for i in range(6)}
    g = m.evaluate(th, bl, False)[0]
    out = []
    for row in (default, best):
        ent = np.zeros(g.shape[1:], bool)
        for s in row["measurements"]:
            ent[label[s]] = True
        err = []
        for seed in seeds:
            rng = np.random.default_rng(seed)
            noisy = g * (1 + 0.01 * (rng.standard_normal(g.shape) + 1j * rng.standard_normal(g.shape)) / np.sqrt(2))
            start = m.start(np.array([KX * 1.1, KR * 0.8]), np.array([CX * 1.2, CR * 0.6]))
            err.append(fit(m, bl, noisy, np.abs(noisy), start, ent).values / true - 1)
        rms = np.sqrt(np.mean(np.square(err), axis=0))
        out.append({"measurements": row["measurements"], "names": m.names,
                    "predicted_std_rel": [row["std_rel"][n] for n in m.names], "rms_error": rms.tolist()})
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=60)
    ap.add_argument("--json", type=Path)
    a = ap.parse_args()
    seeds = range(5000, 5000 + a.seeds)
    res = {}
    for name, fn in (("planar (Table 4.1)", planar), ("n-point (Table 5.1)", n_point)):
        t = time.perf_counter()
        rows = fn(seeds)
        res[name] = rows
        print(f"\n{name}: {a.seeds} seeds, 1 % complex noise, no smoothing ({time.perf_counter() - t:.1f} s)")
        print(f"{'parameter':<10} {'IRC max':>9} {'IRC p90':>9} {'OE max':>9} {'OE p90':>9} {'OE σ/θ':>9} {'|e|≤2σ':>8}")
        for r in rows:
            print(f"{r['parameter']:<10} {r['irc_max']:9.2%} {r['irc_p90']:9.2%} {r['oe_max']:9.3%} "
                  f"{r['oe_p90']:9.3%} {r['oe_rel_se_median']:9.3%} {r['coverage_2sigma']:8.0%}")
    rows = planning(range(8000, 8000 + a.seeds))
    res["planning"] = rows
    print(f"\nplanning (Table 4.1, {a.seeds} seeds, 1 % noise, 2 FRFs each): predicted σ / RMS error")
    for r in rows:
        cells = "  ".join(f"{n} {p:.3%}/{e:.3%}" for n, p, e in zip(r["names"], r["predicted_std_rel"], r["rms_error"]))
        print(f"{' + '.join(r['measurements']):<20} {cells}")
    if a.json:
        a.json.write_text(json.dumps(res, indent=2) + "\n")


if __name__ == "__main__":
    main()
