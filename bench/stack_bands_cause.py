"""Where does the stack prediction of truth family B go wrong? Error against the stack's variables (issue 22).

Two tables, both on the tuning seeds' family only (no reported seed is drawn):

1. the dominant-peak error of every stack of the tuning seeds, grouped by where it lies against the catalogue
   (on a diameter line or between two; torque on a line or not) and by the variables the catalogue holds at one
   value (insertion, gauge, fluted section), with how often the prediction under-estimates the peak;
2. stacks *on catalogued conditions* (no joint choice at all) whose tool differs from the campaign's
   (45 mm gauge, 35 mm inserted, blank): the error of carrying a per-line joint to another tool.

    python bench/stack_bands_cause.py --catalogue /tmp/b [--n 24] [--json out.json]

(``--catalogue``: the folder ``bench/bench_stack_bands.py --catalogue`` built and keeps.)
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import _stack_truth_b as tb  # noqa: E402
import _stack_validation as sv  # noqa: E402

DIAMETER_LINES = tuple(d * 1e3 for d, _ in tb.TH_GRID)
TORQUE_LINES = tb.TH_GRID[0][1]
GROUPS = (
    ("on a diameter line", lambda r: r["d"] in DIAMETER_LINES),
    ("between Ø8 and Ø12", lambda r: 8 < r["d"] < 12),
    ("between Ø12 and Ø16", lambda r: 12 < r["d"] < 16),
    ("on a diameter line, torque between lines", lambda r: r["d"] in DIAMETER_LINES and r["T"] not in TORQUE_LINES),
    ("insertion 32–34 mm", lambda r: r["ins"] <= 34),
    ("insertion 35 mm (the campaigns')", lambda r: r["ins"] == 35),
    ("insertion 36–38 mm", lambda r: r["ins"] >= 36),
    ("gauge ≤ 40 mm", lambda r: r["g"] <= 40),
    ("gauge 41–55 mm", lambda r: 40 < r["g"] <= 55),
    ("gauge > 55 mm", lambda r: r["g"] > 55),
    ("fluted", lambda r: r["fl"] > 0),
    ("blank", lambda r: r["fl"] == 0),
)
#: Tools on catalogued conditions (shank Ø, torque, drawbar force) that differ from the campaign's tool.
TRANSFER = tuple((d, t, f, g, ins, fl) for d, t, f in ((0.008, 30.0, 10e3), (0.012, 70.0, 25e3), (0.016, 150.0, 10e3))
                 for g, ins, fl in ((0.045, 0.035, 0.0), (0.045, 0.032, 0.0), (0.045, 0.038, 0.0),
                                    (max(0.030, 3 * d), 0.035, 0.0), (0.065, 0.035, 0.0), (0.045, 0.035, 0.025),
                                    (max(0.030, 3 * d), 0.032, 0.0)))


def peak_error(case, repo) -> float:
    from jointdb import usecases

    truth = tb.truth_tip(case).values[:, 0, 0]
    h = usecases.predict_stack(tb.spec_for(case, tb.queries(case)), repo, tb.FREQ).prediction.tip.values[:, 0, 0]
    return sv._dominant(h)[1] / sv._dominant(truth)[1] - 1


def tabulate(rows: list[dict]) -> list[dict]:
    out = []
    for name, sel in GROUPS:
        e = np.array([r["peak_err"] for r in rows if sel(r)])
        if e.size:
            out.append({"group": name, "stacks": int(e.size), "median_error": float(np.median(e)),
                        "under_estimated": int((e < 0).sum()), "beyond_5_percent": int((np.abs(e) > 0.05).sum())})
    return out


def run(repo, n: int, say=print) -> dict:
    rows = []
    for seed in tb.TUNING_SEEDS:
        for c in tb.draw(n, seed):
            rows.append({"seed": seed, "case": c.name, "d": round(c.diameter * 1e3), "g": round(c.gauge * 1e3),
                         "ins": round(c.insertion * 1e3), "fl": round(c.fluted * 1e3), "T": c.torque,
                         "F": c.drawbar / 1e3, "peak_err": peak_error(c, repo)})
            say(f"  {c.name}: insertion {rows[-1]['ins']} mm, peak {rows[-1]['peak_err']:+.1%}")
    transfer = []
    for d, t, f, g, ins, fl in TRANSFER:
        c = sv.Case(f"Ø{d * 1e3:.0f}, {t:.0f} N·m, {f / 1e3:.0f} kN: {g * 1e3:.0f} mm gauge, {ins * 1e3:.0f} mm "
                    f"inserted{', fluted' if fl else ''}", d, g, ins, t, "HSK-A63", f, fl)
        transfer.append({"case": c.name, "peak_err": peak_error(c, repo)})
        say(f"  {c.name}: peak {transfer[-1]['peak_err']:+.1%}")
    return {"groups": tabulate(rows), "rows": rows, "transfer": transfer}


def main(argv=None) -> None:
    from jointdb.store import Repository

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--catalogue", type=Path, required=True)
    ap.add_argument("--n", type=int, default=24)
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args(argv)
    with Repository(f"sqlite:///{args.catalogue / 'b.sqlite'}") as repo:
        res = run(repo, args.n)
    for g in res["groups"]:
        print(f"{g['group']:45s} {g['stacks']:3d} stacks, median {g['median_error']:+.1%}, under-estimated "
              f"{g['under_estimated']}, |error| > 5 %: {g['beyond_5_percent']}")
    if args.json is not None:
        args.json.write_text(json.dumps(res, indent=1) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
