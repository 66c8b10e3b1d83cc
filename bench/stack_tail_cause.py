"""Where does family C's heavy tail of peak errors come from? (issue 22, round 3 session 10; a diagnostic)

1. ``--rows F`` (a bench_stack_bands.py rows file): the |peak error| and the misses by the truth's dominant-mode
   frequency. On the seen seeds 7301–7312 the stacks whose dominant mode lies at 1.05–1.15 kHz err by a median
   10–12 % and hold half the misses; below 900 Hz and at 2–5 kHz by 2–3 %.
2. ``--own C30-24 ...``: each named stack predicted with joints identified from campaigns at its *own* conditions
   (no joint to choose): within ~4 % for the five misses of the fresh seeds 7329–7332, so the tail is the joint
   choice, not the substructure model.
3. ``--joints 600 1139 2000``: the catalogued tool–holder joints' Z_xx and Z_θθ at those lines: over about
   0.9–1.3 kHz the per-line joints jump (Re Z_θθ of the Ø20 joints at 20 kN turns negative, the 8 kN joints' Re Z_xx
   too) — for every bore, whatever its campaign's own dominant mode (session 11: these features are needed, smoothing
   them makes predictions worse; bench/stack_feature_proxy.py) — and a stack whose dominant mode lies there takes
   those lines.

    python bench/stack_tail_cause.py --catalogue /tmp/c --rows /tmp/7329.json --own C30-24 --joints 600 1139
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import _stack_truth_c as tc  # noqa: E402
import _stack_validation as sv  # noqa: E402
from stack_hfmode_cause import _own_conditions, _z_at, family_c_repo  # noqa: E402

BANDS_HZ = (0, 900, 1000, 1050, 1100, 1150, 1250, 2000, 5000, 13000)


def by_frequency(rows: list[dict], say=print) -> None:
    """Median and 90th percentile of |peak error|, and misses, per band of the truth's dominant frequency."""
    hz = np.array([r["truth_hz"] for r in rows])
    err = np.array([abs(r["peak_err"]) for r in rows])
    miss = np.array([not r["peak_covered"] for r in rows])
    say("| truth's dominant mode [Hz] | stacks | median abs peak error | 90th percentile | peaks outside |")
    say("|---|---|---|---|---|")
    for lo, hi in zip(BANDS_HZ[:-1], BANDS_HZ[1:]):
        m = (hz >= lo) & (hz < hi)
        if m.any():
            say(f"| {lo}–{hi} | {m.sum()} | {np.median(err[m]):.1%} | {np.quantile(err[m], 0.9):.1%} "
                f"| {miss[m].sum()} |")


def own_conditions(names, say=print) -> None:
    """Each named stack (``C30-24``: seed 7330, stack 24) predicted with joints identified at its own conditions."""
    from jointdb.stack import predict_tool_tip

    f = tc.FREQ
    for name in names:
        seed, i = 7300 + int(name[1:3]), int(name[4:6]) - 1
        case = tc.draw(24, seed)[i]
        thz, tpk = sv._dominant(tc.truth_tip(case).values[:, 0, 0], f)
        tip = predict_tool_tip(tc.spec_for(case, tc.queries(case)), _own_conditions(case), f).tip.values[:, 0, 0]
        phz, ppk = sv._dominant(tip, f)
        say(f"{case.name}: truth {thz:.0f} Hz; joints at its own conditions: {phz:.0f} Hz, peak {ppk / tpk - 1:+.1%}")


def joints_at(repo, lines_hz, say=print) -> None:
    """The catalogued tool–holder joints' diagonal dynamic stiffness at ``lines_hz``."""
    for name in sorted({v.name for v in repo.list_joints("tool-holder")}):
        frf = repo.load_frf(repo.get(name))
        cells = [f"{f:.0f} Hz: Z_xx {(z := _z_at(frf, f))[0, 0]:.2e}, Z_θθ {z[1, 1]:.2e}" for f in lines_hz]
        say(f"{name}: " + "; ".join(cells))


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--catalogue", type=Path, help="family-C catalogue folder (for --joints; built if empty)")
    ap.add_argument("--rows", type=Path, nargs="*", default=(), help="bench_stack_bands.py rows files (--rows-out)")
    ap.add_argument("--own", nargs="*", default=(), help="stacks by name, e.g. C30-24")
    ap.add_argument("--joints", type=float, nargs="*", default=(), help="lines [Hz] to show the joints at")
    args = ap.parse_args(argv)
    rows = [r for p in args.rows for k, v in json.loads(p.read_text(encoding="utf-8")).items()
            if isinstance(v, dict) for r in v.get("rows", ()) if r.get("peak_band")]
    if rows:
        by_frequency(rows)
    if args.own:
        own_conditions(args.own)
    if args.joints:
        if args.catalogue is None:
            ap.error("--joints needs --catalogue")
        with family_c_repo(args.catalogue, lambda s: None) as repo:
            joints_at(repo, args.joints)


if __name__ == "__main__":
    main()
