"""Does exchanging the catalogued joints' clamped shank for the stack's fix the short tools' high modes? (issue 22)

The twelve family-C stacks of docs/validation/stack-bands-family-c.md's high-mode sections (100 Hz – 12 kHz
lines), each predicted twice in one process from the same catalogue: with the interpolated tool–holder joint's
shank inertia exchanged for the stack's (the product, ``jointdb/usecases/_stack_shank.py``) and without
(``shank_inertia`` switched off). Prints the dominant-peak error and the predicted dominant frequency.

    python bench/stack_shank_inertia.py --catalogue /tmp/c                          # campaigns record no insertion
    python bench/stack_shank_inertia.py --catalogue /tmp/cins --record-insertion    # they record insertion_m

Each catalogue folder is built on first use (~30 s); keep one folder per setting.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import _stack_truth_c as tc  # noqa: E402
import _stack_validation as sv  # noqa: E402
from stack_hfmode_cause import CASES as HIGH_MODES  # noqa: E402
from stack_hfmode_cause import family_c_repo, swapped  # noqa: E402

#: (seed, index in the draw) of the high-mode stacks, then of stacks whose 1 kHz peaks the passivity rule moved
CASES = {**HIGH_MODES, "C10-17": (7310, 16), "C12-10": (7312, 9), "C12-20": (7312, 19), "C11-07": (7311, 6),
         "C12-06": (7312, 5), "C13-18": (7313, 17), "C14-08": (7314, 7)}


def errors_with_and_without(family, case, repo) -> tuple[float, list[tuple[float, float]]]:
    """``(truth's dominant Hz, [(error, predicted dominant Hz) without the exchange, the same with it])`` of
    truth family ``family``'s stack ``case`` (its dominant-peak |H| error, on the family's lines)."""
    import jointdb.usecases._stack as stack_usecase
    from jointdb import usecases

    f = family.FREQ
    thz, tpk = sv._dominant(family.truth_tip(case).values[:, 0, 0], f)
    out = []
    for exchange in (False, True):
        with swapped(stack_usecase, "shank_inertia", None if exchange else (lambda spec: None)):
            res = usecases.predict_stack(family.spec_for(case, family.queries(case)), repo, f)
        phz, ppk = sv._dominant(res.prediction.tip.values[:, 0, 0], f)
        out.append((ppk / tpk - 1, phz))
    return thz, out


def run(catalogue: Path, say=print) -> None:
    with family_c_repo(catalogue, say) as repo:
        say("| stack | truth dominant [Hz] | without the exchange | with it (the product) |")
        say("|---|---|---|---|")
        for seed, i in CASES.values():
            case = tc.draw(24, seed)[i]
            thz, out = errors_with_and_without(tc, case, repo)
            say(f"| {case.name} | {thz:.0f} | " + " | ".join(f"{e:+.1%} ({hz:.0f})" for e, hz in out) + " |")


def translation_only() -> None:
    """Swap the product's shank mass matrix for its translational part ``diag(m, 0)`` (this process only)."""
    import jointdb.usecases._stack_shank as shank

    full = shank.inserted_shank_mass
    shank.inserted_shank_mass = lambda d, length, rho, start=0.0: np.diag([full(d, length, rho, start)[0, 0], 0.0])


def shank_options(ap: argparse.ArgumentParser, argv=None) -> argparse.Namespace:
    """``--catalogue``, ``--record-insertion`` and ``--translation-only`` added to ``ap`` and parsed; the variant
    switched on in this process when asked for."""
    ap.add_argument("--catalogue", type=Path, required=True, help="its own folder (built on first use)")
    ap.add_argument("--record-insertion", action="store_true",
                    help="the campaigns record their insertion depth (geometry.insertion_m); its own folder")
    ap.add_argument("--translation-only", action="store_true",
                    help="exchange only the shank's translational mass (a variant: the catalogued planar joints "
                         "are diagonal, and their Z_θθ shows no rotary inertia)")
    args = ap.parse_args(argv)
    if args.translation_only:
        translation_only()
    return args


def main(argv=None) -> None:
    args = shank_options(argparse.ArgumentParser(description=__doc__.splitlines()[0]), argv)
    tc.RECORD_INSERTION = args.record_insertion
    run(args.catalogue)


if __name__ == "__main__":
    main()
