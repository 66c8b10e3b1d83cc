"""How much of a tool–holder joint's identification-assembly error should the band carry? (issue 22)

The band's substructure-model term takes, for a tool–holder version without a validation assembly, the error of
its own identification assembly re-coupled with the catalogued joint, times the identification factor ι
(``jointdb.usecases._stack_band.IDENTIFICATION_CALIBRATION``). This script predicts each family-C stack once and
samples its full band at every ι of a grid (same draws, n = 200, seed 1, as ``bench/bench_stack_bands.py``), then
says per ι how many true peaks and lobe floors lie inside and how wide the band is against the error.

    python bench/stack_model_calibration.py --catalogue /tmp/c --seeds 7301 7302 --rows-out /tmp/k1.json
    python bench/stack_model_calibration.py --table /tmp/k1.json /tmp/k2.json      # pooled, with the rule's choice

The rule (written before the seen seeds were run, docs/validation/stack-bands-family-c.md): on the seen seeds
7301–7312 the smallest ι of the grid whose pooled coverage is ≥ 90 % for peaks and for floors.
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
import bench_stack_bands as bsb  # noqa: E402
from _stack_bands_table import _cells  # noqa: E402
from stack_hfmode_cause import family_c_repo, swapped  # noqa: E402

GRID = (1.0, 0.75, 0.5, 0.25)
#: The coverage the rule asks of the seen seeds, for peaks and floors each (the band's nominal level).
NOMINAL = 0.90


def stack_rows(case, repo, grid=GRID, n: int = bsb.N_SAMPLES) -> dict[str, dict]:
    """ι (as a string) → the stack's truth, prediction and band verdict (:func:`bench_stack_bands.band_verdict`)."""
    import jointdb.usecases._stack_band as stack_band
    from jointdb import usecases

    f = tc.FREQ
    truth = tc.truth_tip(case).values[:, 0, 0]
    result = usecases.predict_stack(tc.spec_for(case, tc.queries(case)), repo, f)
    h = result.prediction.tip.values[:, 0, 0]
    base = {"case": case.name, "truth_peak": sv._dominant(truth, f)[1], "truth_floor": sv._floor(truth, f),
            "pred_peak": sv._dominant(h, f)[1], "pred_floor": sv._floor(h, f)}
    out = {}
    for kappa in grid:
        with swapped(stack_band, "IDENTIFICATION_CALIBRATION", kappa):
            band, _ = stack_band.prediction_band(result, n=n, seed=1)
            sigma = stack_band.model_error(result.joints)[0]
        out[f"{kappa:g}"] = {**base, "model_sigma": sigma, **bsb.band_verdict(band, base, f)}
    return out


def run(catalogue: Path, seeds, n_stacks: int, say=print) -> dict:
    res: dict = {}
    with family_c_repo(catalogue, say) as repo:
        for seed in seeds:
            per_kappa: dict[str, list] = {}
            for case in tc.draw(n_stacks, seed):
                for k, row in stack_rows(case, repo).items():
                    per_kappa.setdefault(k, []).append(row)
                say(f"  {case.name}: " + "; ".join(
                    f"ι {k} peak {'in' if r[-1].get('peak_covered') else 'OUT'} floor "
                    f"{'in' if r[-1].get('floor_covered') else 'OUT'}" for k, r in per_kappa.items()))
            res[str(seed)] = per_kappa
    return res


def table(res: dict, say=print) -> float:
    """Pooled coverage and width per ι; returns the rule's ι."""
    pooled: dict[str, list] = {}
    for per_kappa in res.values():
        for k, rows in per_kappa.items():
            pooled.setdefault(k, []).extend(rows)
    say("| ι | peak inside | half-width / abs error | floor inside | half-width / abs error |")
    say("|---|---|---|---|---|")
    meets = []
    for k in sorted(pooled, key=float, reverse=True):
        cells, ok = [], True
        for key in ("peak", "floor"):
            i, m, h, e = _cells(pooled[k], key)
            ok &= m > 0 and i / m >= NOMINAL
            cells += [f"{i} / {m} ({i / m:.1%})", f"{h:.1%} / {e:.1%} ({h / e:.2f}×)"]
        say(f"| {k} | " + " | ".join(cells) + " |")
        if ok:
            meets.append(float(k))
    choice = min(meets) if meets else 1.0
    say(f"rule (smallest ι with both ≥ {NOMINAL:.0%}): ι = {choice:g}")
    return choice


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--catalogue", type=Path, help="family-C catalogue folder (built if empty)")
    ap.add_argument("--seeds", type=int, nargs="*", default=list(tc.SEEN_SEEDS))
    ap.add_argument("--n", type=int, default=24, help="stacks per seed")
    ap.add_argument("--rows-out", type=Path, default=None)
    ap.add_argument("--table", type=Path, nargs="*", default=None, help="pool these --rows-out files instead")
    args = ap.parse_args(argv)
    if args.table:
        res = {}
        for p in args.table:
            res.update(json.loads(p.read_text(encoding="utf-8")))
        table(res)
        return
    if args.catalogue is None:
        ap.error("give --catalogue (or --table)")
    res = run(args.catalogue, args.seeds, args.n)
    if args.rows_out is not None:
        args.rows_out.write_text(json.dumps(res, default=float) + "\n", encoding="utf-8")
    table(res)


if __name__ == "__main__":
    main()
