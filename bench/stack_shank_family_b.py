"""Does the shank-inertia exchange generalise to truth family B's high modes? (issue 22)

Family B's catalogue and stacks are on 100 Hz – 5 kHz lines; here its campaigns are "measured" and its stacks
predicted on 100 Hz – 12 kHz lines instead (its own catalogue folder, built on first use), so that the short
tools' 5–8 kHz modes are inside. Each stack of the given seeds is predicted twice in one process, with the
interpolated tool–holder joint's shank exchanged for the stack's (the product) and without; point predictions
only (no band). Prints each stack's dominant-peak error and, at the end, the medians for all stacks and for those
whose truth's dominant mode lies above 5 kHz.

    python bench/stack_shank_family_b.py --catalogue /tmp/b12 --seeds 7201 7202 7203 7204
    python bench/stack_shank_family_b.py --catalogue /tmp/b12ins --record-insertion --seeds 7201 7202 7203 7204

About 1.5–2 min for four seeds after the catalogue (~20 s). Numbers: docs/validation/stack-bands-family-c.md,
*The shank inside the holder*.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import _stack_truth_b as tb  # noqa: E402
import _stack_validation as sv  # noqa: E402

FMAX = 12000.0
HIGH = 5000.0  # a truth's dominant mode above this is a "high mode" here


def _errors(case, repo, say) -> tuple[float, float, float]:
    """``(truth dominant Hz, error without, error with)`` of one stack."""
    import jointdb.usecases._stack as stack_usecase
    from jointdb import usecases

    keep = stack_usecase.shank_inertia
    thz, tpk = sv._dominant(tb.truth_tip(case).values[:, 0, 0], tb.FREQ)
    out = []
    for exchange in (False, True):
        stack_usecase.shank_inertia = keep if exchange else (lambda spec: None)
        try:
            res = usecases.predict_stack(tb.spec_for(case, tb.queries(case)), repo, tb.FREQ)
        finally:
            stack_usecase.shank_inertia = keep
        phz, ppk = sv._dominant(res.prediction.tip.values[:, 0, 0], tb.FREQ)
        out.append((ppk / tpk - 1, phz))
    say(f"  {case.name}: truth {thz:.0f} Hz | without {out[0][0]:+.1%} ({out[0][1]:.0f} Hz) | "
        f"with {out[1][0]:+.1%} ({out[1][1]:.0f} Hz)")
    return thz, out[0][0], out[1][0]


def run(catalogue: Path, seeds, say=print) -> None:
    from jointdb.store import Repository

    t0 = time.time()
    catalogue.mkdir(parents=True, exist_ok=True)
    db = catalogue / "b.sqlite"
    fresh = not db.exists()
    with Repository(f"sqlite:///{db}") as repo:
        if fresh:
            tb.build_catalogue(catalogue, repo, say=lambda s: None)
            say(f"catalogue built in {time.time() - t0:.0f} s")
        rows = np.array([_errors(case, repo, say) for seed in seeds for case in tb.draw(24, seed)])
    for label, sel in (("all", np.ones(len(rows), bool)), (f"truth dominant > {HIGH:.0f} Hz", rows[:, 0] > HIGH)):
        e0, e1 = np.abs(rows[sel, 1]), np.abs(rows[sel, 2])
        if e0.size:
            say(f"{label} ({e0.size}): median |error| without {np.median(e0):.1%}, with {np.median(e1):.1%}; "
                f"within 20 %: {int(np.sum(e0 < 0.2))} / {int(np.sum(e1 < 0.2))}")
    say(f"{time.time() - t0:.0f} s")


def translation_only() -> None:
    """Swap the product's shank mass matrix for its translational part ``diag(m, 0)`` (this process only)."""
    import jointdb.usecases._stack_shank as shank

    full = shank.inserted_shank_mass
    shank.inserted_shank_mass = lambda d, length, rho, start=0.0: np.diag([full(d, length, rho, start)[0, 0], 0.0])


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--catalogue", type=Path, required=True, help="its own folder (built on first use)")
    ap.add_argument("--seeds", type=int, nargs="+", default=[7201, 7202, 7203, 7204])
    ap.add_argument("--record-insertion", action="store_true",
                    help="the campaigns record their insertion depth (geometry.insertion_m); its own folder")
    ap.add_argument("--translation-only", action="store_true",
                    help="exchange only the shank's translational mass (a variant: the catalogued planar joints "
                         "are diagonal, and their Z_θθ shows no rotary inertia)")
    args = ap.parse_args(argv)
    if args.translation_only:
        translation_only()
    tb.FREQ = np.arange(100.0, FMAX + 1e-9, 10.0)
    tb.CAMPAIGN_OPTIONS = {"smoothing": 9, "fit_band": [100.0, FMAX]}
    tb.RECORD_INSERTION = args.record_insertion
    run(args.catalogue, args.seeds)


if __name__ == "__main__":
    main()
