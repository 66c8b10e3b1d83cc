"""How wide should the band's calibrated terms be? A grid of the band's constants, one prediction per stack (issue 22).

The band takes constants that its own records cannot fix: the identification factor ι on a tool–holder
version's identification-assembly error (``jointdb.usecases._stack_band.IDENTIFICATION_CALIBRATION``), the lean of a
line left out (``LINE_BIAS``), the spread of lines left out (``jointdb.usecases._stack.LINE_CALIBRATION``, λ), the
prediction path's σ (``MODEL_FORM_SIGMA``) and the factor k of the feature-position term
(``FEATURE_POSITION_FACTOR``). (Session 11's sampled feature shift, grids ``shift`` / ``shift2``, is no longer in the
product; its rows are in docs/validation/stack-bands-family-c-session11.json.) This script predicts each
stack once and samples its full band at every configuration of a grid (same draws, n = 200, seed 1, as
``bench/bench_stack_bands.py``), then says per configuration how many true peaks and lobe floors lie
inside and how wide the band is against the error.

    python bench/stack_model_calibration.py --catalogue /tmp/c --seeds 7301 7302 --rows-out /tmp/k1.json
    python bench/stack_model_calibration.py --table /tmp/k1.json /tmp/k2.json      # pooled, with the rule's choice
    python bench/stack_model_calibration.py --family b --catalogue /tmp/b --seeds 7101 --rows-out /tmp/b1.json

The rule (written before the seen seeds were run, docs/validation/stack-bands-family-c.md): on the seen seeds
7301–7312 the configurations whose pooled coverage is ≥ 90 % for peaks and for floors are admissible; of them the
one with the narrowest median peak band (then floor band). Session 9's grid varied ι alone (``--grid iota``), where
the narrowest admissible band is the smallest admissible ι.
"""

from __future__ import annotations

import argparse
import json
import sys
from contextlib import ExitStack
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import _stack_truth_b as tb  # noqa: E402
import _stack_truth_c as tc  # noqa: E402
import _stack_validation as sv  # noqa: E402
import bench_stack_bands as bsb  # noqa: E402
from _stack_bands_table import _cells  # noqa: E402
from stack_hfmode_cause import family_repo, swapped  # noqa: E402

#: (LINE_BIAS, ι, λ, σ_pp, k) per configuration; σ_pp and k may be left off: 0.02 and 0, what the product had before
#: session 12. "iota": session 9 (the first was the product then); "session10": the lean removed, ι and λ lowered (the
#: product then, (0.5, 1, 0.5), and (0.5, 0.5, 0.5) are in session 9's rows); "sensitivity4" / "sensitivity5":
#: session 11's grid 4 and session 12's grid 5 (the feature-position term with factor k, and ι, λ, σ_pp scaled by a
#: from (1, 0.5, 0.02): written (a, k) = (0.35, 1), (0.25, 1), (0.5, 0.5) and (0.35, 0.5), (0.25, 0.5), (0.5, 0.35)).
GRIDS = {
    "iota": ((0.5, 1.0, 0.5), (0.5, 0.75, 0.5), (0.5, 0.5, 0.5), (0.5, 0.25, 0.5)),
    "session10": ((0.0, 1.0, 0.5), (0.0, 0.75, 0.5), (0.0, 0.5, 0.5), (0.0, 0.75, 0.35), (0.0, 0.5, 0.35)),
    "sensitivity4": tuple((0.5, a, 0.5 * a, 0.02 * a, k) for a, k in ((0.35, 1.0), (0.25, 1.0), (0.5, 0.5))),
    "sensitivity5": tuple((0.5, a, 0.5 * a, 0.02 * a, k) for a, k in ((0.35, 0.5), (0.25, 0.5), (0.5, 0.35))),
    # session 12, after its fresh seeds: the product with the prediction path's σ back at 2 %
    "session12b": ((0.5, 0.5, 0.25, 0.02, 0.5),),
}
#: The coverage the rule asks of the seen seeds, for peaks and floors each (the band's nominal level).
NOMINAL = 0.90
#: σ_pp and k of a configuration that does not give them.
_DEFAULTS = (0.02, 0.0)


def _full(config) -> tuple[float, float, float, float, float]:
    return tuple(float(v) for v in (*config, *_DEFAULTS[len(config) - 3:]))


def _product() -> tuple[float, float, float, float, float]:
    """The product's (LINE_BIAS, ι, λ, σ_pp, k)."""
    import jointdb.usecases._stack as stack
    import jointdb.usecases._stack_band as stack_band

    return (stack_band.LINE_BIAS, stack_band.IDENTIFICATION_CALIBRATION, stack.LINE_CALIBRATION,
            stack_band.MODEL_FORM_SIGMA, stack_band.FEATURE_POSITION_FACTOR)


def config_key(config) -> str:
    """``"bias 0.5 ι 1 λ 0.5"`` (``… σ 0.01 k 0.5`` when σ_pp or k differ from 0.02, 0): a configuration's key."""
    bias, iota, lam, sigma, k = _full(config)
    return f"bias {bias:g} ι {iota:.4g} λ {lam:.4g}" + (
        f" σ {sigma:.4g} k {k:g}" if (sigma, k) != _DEFAULTS else "")


def _constants(config):
    """Context manager setting the band's constants to ``config`` (:data:`GRIDS`)."""
    import jointdb.usecases._stack as stack
    import jointdb.usecases._stack_band as stack_band

    bias, iota, lam, sigma, k = _full(config)
    block = ExitStack()
    block.enter_context(swapped(stack_band, "LINE_BIAS", bias))
    block.enter_context(swapped(stack_band, "IDENTIFICATION_CALIBRATION", iota))
    block.enter_context(swapped(stack, "LINE_CALIBRATION", lam))
    block.enter_context(swapped(stack_band, "MODEL_FORM_SIGMA", sigma))
    block.enter_context(swapped(stack_band, "FEATURE_POSITION_FACTOR", k))
    return block


def stack_rows(family, case, repo, grid, n: int = bsb.N_SAMPLES) -> dict[str, dict]:
    """Configuration key → the stack's truth, prediction and band verdict (:func:`bench_stack_bands.band_verdict`)."""
    import jointdb.usecases._stack_band as stack_band
    from jointdb import usecases

    f = family.FREQ
    truth = family.truth_tip(case).values[:, 0, 0]
    result = usecases.predict_stack(family.spec_for(case, family.queries(case)), repo, f)
    h = result.prediction.tip.values[:, 0, 0]
    base = {"case": case.name, "truth_peak": sv._dominant(truth, f)[1], "truth_floor": sv._floor(truth, f),
            "pred_peak": sv._dominant(h, f)[1], "pred_floor": sv._floor(h, f)}
    with swapped(stack_band, "FEATURE_POSITION_FACTOR", 1.0):  # k = 1: s itself
        s = stack_band.feature_position(result.spec, result.joints, result.prediction.tip)[0]
    out = {}
    for config in grid:
        with _constants(config):
            band, _ = stack_band.prediction_band(result, n=n, seed=1, feature_sigma=_full(config)[4] * s)
            sigma = stack_band.model_error(result.joints)[0]
        out[config_key(config)] = {**base, "model_sigma": sigma, "sensitivity": s, **bsb.band_verdict(band, base, f)}
    return out


def run(family, catalogue: Path, seeds, n_stacks: int, grid, say=print) -> dict:
    res: dict = {}
    with family_repo(family, catalogue, say) as repo:
        for seed in seeds:
            per_config: dict[str, list] = {}
            for case in family.draw(n_stacks, seed):
                for k, row in stack_rows(family, case, repo, grid).items():
                    per_config.setdefault(k, []).append(row)
                say(f"  {case.name}: " + "; ".join(
                    f"{k}: {'in' if r[-1].get('peak_covered') else 'OUT'}/"
                    f"{'in' if r[-1].get('floor_covered') else 'OUT'}" for k, r in per_config.items()))
            res[str(seed)] = per_config
    return res


def table(res: dict, say=print) -> str | None:
    """Pooled coverage and width per configuration; returns the rule's choice (None: none admissible)."""
    pooled: dict[str, list] = {}
    for per_config in res.values():
        for k, rows in per_config.items():
            pooled.setdefault(k, []).extend(rows)
    say("| configuration | peak inside | half-width / abs error | floor inside | half-width / abs error |")
    say("|---|---|---|---|---|")
    admissible = []
    for k, rows in pooled.items():
        cells, ok, widths = [], True, []
        for key in ("peak", "floor"):
            i, m, h, e = _cells(rows, key)
            ok &= m > 0 and i / m >= NOMINAL
            widths.append(h)
            cells += [f"{i} / {m} ({i / m:.1%})", f"{h:.1%} / {e:.1%} ({h / e:.2f}×)"]
        say(f"| {k} | " + " | ".join(cells) + " |")
        if ok:
            admissible.append((tuple(widths), k))
    choice = min(admissible)[1] if admissible else None
    say(f"rule (narrowest peak band of those with both ≥ {NOMINAL:.0%}): {choice}")
    return choice


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--catalogue", type=Path, help="catalogue folder of the family (built if empty)")
    ap.add_argument("--family", choices=("b", "c"), default="c")
    ap.add_argument("--grid", choices=(*GRIDS, "product"), default="session10",
                    help="a grid of configurations, or the product's constants alone")
    ap.add_argument("--seeds", type=int, nargs="*", default=None,
                    help="default: family C's seen seeds, family B's tuning seeds")
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
    family = tc if args.family == "c" else tb
    seeds = args.seeds or (list(tc.SEEN_SEEDS) if args.family == "c" else list(tb.TUNING_SEEDS))
    res = run(family, args.catalogue, seeds, args.n, GRIDS[args.grid] if args.grid != "product" else (_product(),))
    if args.rows_out is not None:
        args.rows_out.write_text(json.dumps(res, default=float) + "\n", encoding="utf-8")
    table(res)


if __name__ == "__main__":
    main()
