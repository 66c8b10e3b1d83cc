"""Does the tail of family C's peak errors follow where the tool–holder joints' features sit? (issue 22, session 11)

A diagnostic, one point prediction per stack (no band), in one process per mode:

* ``--mode none``: the prediction as it is;
* ``--mode shift --eps 0.03`` (and ``-0.03``): every catalogued tool–holder joint read at ``f (1 + eps)``
  (:func:`jointdb.stack._feature.frequency_shifted`) — the sensitivity of each stack's dominant peak to where the
  joints' frequency features sit;
* ``--mode smooth``: the tool–holder joints' lines between 0.5 and 1.5 kHz that depart from a robust trend
  (Re Z = a + b f², Im Z = c + d f, fitted per diagonal entry with 3-MAD rejection) by more than 20 % replaced by
  the trend — the "repair" of what looked like IRC artefacts.

``--compare none.json plus.json minus.json`` prints the correlation of ln |error| with ln s, s the RMS of the two
shifts' peak changes, and |error| by quartile of s. Session 11 (seen seeds 7301–7312, 0.2 % catalogue): correlation
0.50; |error| / s at 50 / 80 / 90 / 95 %: 0.58 / 1.05 / 1.51 / 1.97; the smoothing made the median |peak error|
3.5 % → 9.7 % (docs/validation/stack-bands-family-c.md, *Feature position*). ``--offline ROWS KEY`` adds an offline
estimate (not a band) of a band term proportional to ``s`` with the product's other terms scaled down.

    python bench/stack_feature_proxy.py --catalogue /tmp/c --mode shift --eps 0.03 --seeds 7301 --out /tmp/p.json
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import _stack_truth_c as tc  # noqa: E402
import _stack_validation as sv  # noqa: E402
from stack_hfmode_cause import family_c_repo  # noqa: E402


def _robust_trend(f, y, basis, iters: int = 6):
    a = np.stack([b(f) for b in basis], 1)
    keep = np.ones(y.size, bool)
    for _ in range(iters):
        c, *_ = np.linalg.lstsq(a[keep], y[keep], rcond=None)
        r = y - a @ c
        keep = np.abs(r) <= 3 * 1.4826 * np.median(np.abs(r[keep])) + 1e-300
    return a @ c


def smoothed(frf, lo=500.0, hi=1500.0, tol=0.2):
    """``frf`` (a 2×2 joint receptance) with its departing lines in ``[lo, hi]`` replaced by the robust trend."""
    f, z = frf.freq, np.linalg.inv(frf.values)
    trend, bad = z.copy(), np.zeros(f.size, bool)
    for i in range(2):
        for j in range(2):
            t = (_robust_trend(f, z[:, i, j].real, [np.ones_like, np.square])
                 + 1j * _robust_trend(f, z[:, i, j].imag, [np.ones_like, lambda x: x]))
            if i == j:
                bad |= (np.abs(z[:, i, j] - t) > tol * np.abs(t)) & (f > lo) & (f < hi)
            trend[:, i, j] = t
    return replace(frf, values=np.linalg.inv(np.where(bad[:, None, None], trend, z)))


def peak_sensitivity(base, plus, minus) -> tuple[np.ndarray, np.ndarray]:
    """``(error, s)`` per stack: the peak error as predicted, and the RMS of its change under the two shifts."""
    e = np.array([r["peak_err"] for r in base])
    s = np.sqrt(((np.array([r["peak_err"] for r in plus]) - e) ** 2
                 + (np.array([r["peak_err"] for r in minus]) - e) ** 2) / 2)
    return e, s


def _patched(repo, mode: str, eps: float):
    """``repo.load_frf`` wrapped so tool–holder joints come back shifted
    (:func:`jointdb.stack._feature.read_shifted`) or smoothed."""
    from jointdb.stack._feature import read_shifted

    load = repo.load_frf

    def load_frf(version, number=None):
        frf = load(version, number)
        name = version if isinstance(version, str) else version.name
        if not name.startswith("c-th") or mode == "none":
            return frf
        if mode == "smooth":
            return smoothed(frf)
        return read_shifted(frf, eps)

    repo.load_frf = load_frf


def run(catalogue: Path, mode: str, eps: float, seeds, say=print) -> list[dict]:
    from jointdb import usecases

    rows, f = [], tc.FREQ
    with family_c_repo(catalogue, say) as repo:
        _patched(repo, mode, eps)
        for seed in seeds:
            for case in tc.draw(24, seed):
                th, tp = sv._dominant(tc.truth_tip(case).values[:, 0, 0], f)
                h = usecases.predict_stack(tc.spec_for(case, tc.queries(case)), repo, f).prediction.tip.values[:, 0, 0]
                ph, pp = sv._dominant(h, f)
                rows.append({"case": case.name, "truth_hz": th, "pred_hz": ph, "peak_err": pp / tp - 1})
                say(f"  {case.name[:7]} truth {th:.0f} Hz, predicted {ph:.0f} Hz, peak {pp / tp - 1:+.1%}")
    e = np.abs([r["peak_err"] for r in rows])
    say(f"{mode} {eps:g}: {len(e)} stacks, median |peak error| {np.median(e):.1%}, 90th percentile "
        f"{np.quantile(e, 0.9):.1%}")
    return rows


def compare(base, plus, minus, say=print) -> None:
    e, s = peak_sensitivity(base, plus, minus)
    say(f"correlation of ln|error| with ln s: {np.corrcoef(np.log(np.abs(e) + 1e-4), np.log(s + 1e-4))[0, 1]:.2f}")
    for q in np.array_split(np.argsort(s), 4):
        say(f"  quartile of s (median {np.median(s[q]):.1%}): median |error| {np.median(np.abs(e[q])):.1%}, "
            f"90th percentile {np.quantile(np.abs(e[q]), 0.9):.1%}")
    say("|error| / s at 50 / 80 / 90 / 95 %: "
        + " / ".join(f"{v:.2f}" for v in np.quantile(np.abs(e) / np.maximum(s, 1e-3), [0.5, 0.8, 0.9, 0.95])))


def offline_band(band_rows, base, plus, minus, say=print) -> None:
    """An offline estimate, not a band: coverage and width if the product's peak half-widths ``h`` (``band_rows``:
    one configuration's rows of bench/stack_model_calibration.py, same stacks in the same order) were scaled by ``a``
    and a term ``k·s`` added in quadrature, with |error| ≤ half-width as "inside" (the band's lean and asymmetry
    ignored: the product shows 97.9 % this way against 95.1 % with its real edges)."""
    e = np.array([r["peak_err"] for r in band_rows])
    h = np.array([r["peak_half"] for r in band_rows])
    if [r["case"] for r in band_rows] != [r["case"] for r in base]:
        raise SystemExit("the band rows and the proxy rows are not the same stacks in the same order")
    s = peak_sensitivity(base, plus, minus)[1]
    say("| a (other terms) | k (on s) | inside (symmetric) | median half-width / median abs error |")
    say("|---|---|---|---|")
    for a in (1.0, 0.5, 0.35, 0.25):
        for k in (0.0, 0.5, 1.0, 1.5):
            hw = np.hypot(a * h, k * s)
            say(f"| {a:g} | {k:g} | {np.mean(np.abs(e) <= hw):.1%} | {np.median(hw):.1%} / {np.median(np.abs(e)):.1%} "
                f"({np.median(hw) / np.median(np.abs(e)):.2f}×) |")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--catalogue", type=Path, help="family-C catalogue folder (built if empty)")
    ap.add_argument("--mode", choices=("none", "shift", "smooth"), default="none")
    ap.add_argument("--eps", type=float, default=0.03, help="relative shift of --mode shift")
    ap.add_argument("--seeds", type=int, nargs="*", default=list(range(7301, 7313)))
    ap.add_argument("--out", type=Path)
    ap.add_argument("--compare", type=Path, nargs=3, metavar=("NONE", "PLUS", "MINUS"))
    ap.add_argument("--offline", type=Path, nargs=2, metavar=("ROWS_JSON", "KEY"),
                    help="with --compare: an offline estimate against one configuration's band rows (a JSON file of "
                         "seed → configuration → rows, and the key of the block holding it, e.g. "
                         "docs/validation/stack-bands-family-c-session10.json contact_rule_seen_7301_7312)")
    args = ap.parse_args(argv)
    if args.compare:
        base, plus, minus = (json.loads(p.read_text(encoding="utf-8")) for p in args.compare)
        compare(base, plus, minus)
        if args.offline:
            block = json.loads(args.offline[0].read_text(encoding="utf-8"))[str(args.offline[1])]
            rows = [r for seed in sorted(block) for per in block[seed].values() for r in per]
            offline_band(rows, base, plus, minus)
        return
    if args.catalogue is None:
        ap.error("--catalogue is needed to run a mode")
    rows = run(args.catalogue, args.mode, args.eps, args.seeds)
    if args.out:
        args.out.write_text(json.dumps(rows, indent=1), encoding="utf-8")


if __name__ == "__main__":
    main()
