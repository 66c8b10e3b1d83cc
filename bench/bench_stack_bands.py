"""Do the prediction bands contain the truth? Held-out check on truth family B (issue 22).

Builds the family-B catalogue (``bench/_stack_truth_b.py``), predicts stacks drawn with the
tuning seeds and, separately, the reported seed, each with its 5–95 % band (measurement noise +
joint choice), and compares the band with the truth's dominant peak |H| and lobe floor.

    python bench/bench_stack_bands.py [--n 24] [--samples 200] [--report docs/validation/stack-prediction.md]
    # on a shared machine, one process per seed, then merge:
    python bench/bench_stack_bands.py --catalogue /tmp/b --seeds 7201 --rows-out /tmp/7201.json   # (build first)
    python bench/bench_stack_bands.py --merge /tmp/72*.json --report docs/validation/stack-prediction.md
    # a quick look (≈ 3 min on a quiet machine, catalogue included):
    python bench/bench_stack_bands.py --n 3 --seeds 7205
    # campaigns measured at 0.75 % noise instead of 0.2 % (the level of the issue's own trial; keep its own catalogue):
    python bench/bench_stack_bands.py --family c --noise 0.0075 --catalogue /tmp/c075 --seeds 7301 --rows-out /tmp/n.json
    # tool-holder campaigns that record their insertion depth (the shank each joint carries; own catalogue folder):
    python bench/bench_stack_bands.py --family c --record-insertion --catalogue /tmp/cins --seeds 7301 --rows-out /tmp/i.json
    # the spindle estimated from each stack's noisy extension-bar taps (issue 22 item 1):
    python bench/bench_stack_bands.py --catalogue /tmp/b --seeds 7207 --spindle-estimate --rows-out /tmp/7207s.json

The calibration factor (``jointdb.usecases._stack.CHOICE_CALIBRATION``) is set from the tuning seeds'
coverage only; the reported seed's table is what it is. With ``--report`` the *Bands* section of the page
is rewritten.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import _stack_truth_b as tb  # noqa: E402
import _stack_validation as sv  # noqa: E402

N_SAMPLES = 200
#: Suffix of a seed's key when its stacks' spindle is estimated from extension-bar taps (``--spindle-estimate``).
SPINDLE_TAG = "+spindle-estimate"


def seed_key(k: str):
    """A rows file's seed key: the seed as an int, or ``"7207+spindle-estimate"`` as it is."""
    return int(k) if k.isdigit() else k


def band_row(case, repo, n: int = N_SAMPLES, spindle_estimated: bool = False) -> dict:
    """Truth vs prediction and band for one stack: dominant peak |H| (x) and lobe floor (``spindle_estimated``:
    the prediction's spindle is its extension-bar estimate from the stack's own noisy taps)."""
    from jointdb import usecases
    from jointdb.usecases._stack_band import band_terms

    truth = tb.truth_tip(case).values[:, 0, 0]
    result = usecases.predict_stack(tb.spec_for(case, tb.queries(case), spindle_estimated), repo, tb.FREQ)
    terms = band_terms(result, n=n, seed=1)
    h = result.prediction.tip.values[:, 0, 0]
    f = tb.FREQ
    truth_hz, at = sv._dominant(truth, f)
    lt = sv._floor(truth, f)
    pred_hz, pred_peak = sv._dominant(h, f)
    row = {"case": case.name, "truth_peak": at, "truth_floor": lt, "pred_peak": pred_peak,
           "pred_floor": sv._floor(h, f), "truth_hz": truth_hz, "pred_hz": pred_hz, "grid_hz": [f[0], f[-1]], "dominant_term": terms.dominant, "half_widths": terms.half_width,
           "methods": {k: r.method + (" (constant k, c fallback)" if any("constant k, c fit" in w for w in r.warnings)
                                      else "") for k, r in result.joints.items()},
           "extrapolating": any(r.extrapolating for r in result.joints.values()),
           "spindle_estimated": spindle_estimated}
    row.update(band_verdict(terms.band, row, f))
    return row


def band_verdict(b, row: dict, f: np.ndarray) -> dict:
    """The band ``b`` (a TipBand or None) of one stack against its truth: the 5/50/95 % of the dominant peak |H|, its
    frequency and the lobe floor, whether the truth lies inside, the prediction's error and the relative half-width
    (``row``: the truth and prediction keys of :func:`band_row`; ``f``: the lines [Hz] of the band's tips)."""
    if b is None:
        return {"peak_band": None, "floor_band": None}
    peaks = np.array([sv._dominant(s, f) for s in b.tips["x"]])
    floors = np.array([sv._floor(s, f) for s in b.tips["x"]])
    out = {"peak_band": np.quantile(peaks[:, 1], [0.05, 0.5, 0.95]).tolist(),
           "peak_hz_band": np.quantile(peaks[:, 0], [0.05, 0.5, 0.95]).tolist(),
           "floor_band": np.quantile(floors, [0.05, 0.5, 0.95]).tolist()}
    for key in ("peak", "floor"):
        lo, _, hi = out[f"{key}_band"]
        truth_v, pred_v = row[f"truth_{key}"], row[f"pred_{key}"]
        out[f"{key}_covered"] = bool(lo <= truth_v <= hi)
        out[f"{key}_err"] = pred_v / truth_v - 1
        out[f"{key}_half"] = (hi - lo) / 2 / pred_v
    return out


def summary(rows: list[dict]) -> dict:
    out = {}
    for key in ("peak", "floor"):
        banded = [r for r in rows if r.get(f"{key}_band")]
        out[key] = {"stacks": len(rows), "banded": len(banded),
                    "covered": sum(r[f"{key}_covered"] for r in banded),
                    "median_half": float(np.median([r[f"{key}_half"] for r in banded])) if banded else float("nan"),
                    "median_abs_err": float(np.median([abs(r[f"{key}_err"]) for r in banded])) if banded else
                    float("nan")}
    return out


def run(n: int, samples: int, seeds, say=print, catalogue: Path | None = None, spindle_estimated: bool = False) -> dict:
    """Build (or reuse, ``catalogue``: a folder kept between runs) the family-B catalogue and check the bands of
    ``n`` stacks per seed."""
    from jointdb.store import Repository

    t0 = time.time()
    say(f"load average at start: {', '.join(f'{v:.2f}' for v in os.getloadavg())}")
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(catalogue) if catalogue is not None else Path(tmp)
        folder.mkdir(parents=True, exist_ok=True)
        db = folder / "b.sqlite"
        fresh = not db.exists()
        with Repository(f"sqlite:///{db}") as repo:
            if fresh:
                say(f"catalogue of family {tb.NOISE_TAG}:")
                tb.build_catalogue(folder, repo, say=say)
            else:
                say(f"catalogue of family {tb.NOISE_TAG} reused from {folder}")
            out = _seeds(repo, n, samples, seeds, say, spindle_estimated)
    out["seconds"] = time.time() - t0
    out["load_average"] = list(os.getloadavg())
    say(f"{out['seconds']:.0f} s; load average at the end: {', '.join(f'{v:.2f}' for v in out['load_average'])}")
    return out


def _seeds(repo, n: int, samples: int, seeds, say, spindle_estimated: bool = False) -> dict:
    out = {}
    for seed in seeds:
        rows = []
        for case in tb.draw(n, seed):
            rows.append(band_row(case, repo, samples, spindle_estimated))
            r = rows[-1]
            say(f"  {r['case']}: peak {r.get('peak_err', float('nan')):+.1%} band ±{r.get('peak_half', 0):.1%} "
                f"{'in' if r.get('peak_covered') else 'OUT'}; floor {r.get('floor_err', float('nan')):+.1%} band "
                f"±{r.get('floor_half', 0):.1%} {'in' if r.get('floor_covered') else 'OUT'}; "
                f"dominant term: {r['dominant_term']}")
        key = f"{seed}{SPINDLE_TAG}" if spindle_estimated else seed
        out[key] = {"rows": rows, "summary": summary(rows)}
        say(f"seed {key}: {out[key]['summary']}")
    return out


def main(argv=None) -> None:
    global tb
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=24)
    ap.add_argument("--samples", type=int, default=N_SAMPLES)
    ap.add_argument("--tuning", action="store_true", help="run the tuning seeds instead of the reported one")
    ap.add_argument("--report", type=Path, default=None)
    ap.add_argument("--catalogue", type=Path, default=None,
                    help="folder to keep the family-B catalogue in and reuse on the next run (built if empty)")
    ap.add_argument("--seeds", type=int, nargs="*", default=None, help="these seeds instead (e.g. one per process)")
    ap.add_argument("--rows-out", type=Path, default=None, help="write this run's rows as JSON (to merge later)")
    ap.add_argument("--spindle-estimate", action="store_true",
                    help="predict with the spindle estimated from each stack's noisy extension-bar taps "
                         "(bench/_stack_truth_b.py: estimated_spindle) instead of its exact receptance")
    ap.add_argument("--merge", type=Path, nargs="*", default=None,
                    help="write --report from these --rows-out files (seeds run in separate processes) instead")
    ap.add_argument("--family", choices=("b", "c"), default="b",
                    help="truth family: b (bench/_stack_truth_b.py) or c (bench/_stack_truth_c.py: never used to "
                         "tune the band; its reported seeds only: rows with --rows-out, page by "
                         "bench/bench_stack_bands_c.py)")
    ap.add_argument("--noise", type=float, default=None,
                    help=f"relative measurement noise of the campaigns' taps (default {sv.NOISE}); a catalogue folder "
                         "built at one level must not be reused at another")
    ap.add_argument("--record-insertion", action="store_true",
                    help="the tool-holder campaigns record their insertion depth (geometry.insertion_m), so the "
                         "prediction knows each catalogued joint's shank; keep such a catalogue in its own folder")
    ap.add_argument("--law", choices=("power-law", "linear"), default=None,
                    help="how the interpolation combines the neighbours' dynamic stiffness "
                         "(jointdb.store._query.INTERPOLATION_LAW; default: the product's)")
    args = ap.parse_args(argv)
    if args.law is not None:
        import jointdb.store._query as query

        query.INTERPOLATION_LAW = args.law
    if args.noise is not None:
        if not 0.0 <= args.noise < 0.2:
            ap.error(f"--noise {args.noise}: give a relative level in [0, 0.2), e.g. 0.0075")
        sv.NOISE = args.noise  # read by _stack_validation._noisy at each call
    if args.family == "c":
        import _stack_truth_c as tb
        if args.report is not None:
            ap.error("--report rewrites family B's section of stack-prediction.md; for family C use --rows-out")
    if args.record_insertion:
        if args.report is not None:
            ap.error("--record-insertion is a check beside the report; use --rows-out")
        tb.RECORD_INSERTION = True
    seeds = tb.TUNING_SEEDS if args.tuning else tb.REPORT_SEEDS
    seeds = args.seeds or seeds
    if args.merge:
        res = {"seconds": 0.0}
        for part in args.merge:
            got = json.loads(part.read_text(encoding="utf-8"))
            res["seconds"] = max(res["seconds"], got.pop("seconds"))
            got.pop("load_average", None)
            res.update({seed_key(k): v for k, v in got.items()})
        seeds = sorted((k for k in res if k != "seconds"), key=str)
    else:
        res = run(args.n, args.samples, seeds, catalogue=args.catalogue, spindle_estimated=args.spindle_estimate)
        seeds = [f"{s}{SPINDLE_TAG}" if args.spindle_estimate else s for s in seeds]
    if args.rows_out is not None:
        args.rows_out.write_text(json.dumps({str(k): v for k, v in res.items()}, default=str) + "\n", encoding="utf-8")
    if args.report is not None and not args.tuning:
        from _stack_bands_report import write_section

        write_section(args.report, {seed: res[seed] for seed in seeds}, res["seconds"])
        args.report.with_name("stack-bands.json").write_text(
            json.dumps({str(k): v for k, v in res.items()}, indent=1, default=str) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
