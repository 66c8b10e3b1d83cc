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
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import _stack_truth_b as tb  # noqa: E402
from stack_hfmode_cause import family_repo  # noqa: E402
from stack_shank_inertia import errors_with_and_without, shank_options  # noqa: E402

FMAX = 12000.0
HIGH = 5000.0  # a truth's dominant mode above this is a "high mode" here


def _errors(case, repo, say) -> tuple[float, float, float]:
    """``(truth dominant Hz, error without, error with)`` of one stack, said as a line."""
    thz, ((e0, hz0), (e1, hz1)) = errors_with_and_without(tb, case, repo)
    say(f"  {case.name}: truth {thz:.0f} Hz | without {e0:+.1%} ({hz0:.0f} Hz) | with {e1:+.1%} ({hz1:.0f} Hz)")
    return thz, e0, e1


def run(catalogue: Path, seeds, say=print) -> None:
    with family_repo(tb, catalogue, say) as repo:
        rows = np.array([_errors(case, repo, say) for seed in seeds for case in tb.draw(24, seed)])
    for label, sel in (("all", np.ones(len(rows), bool)), (f"truth dominant > {HIGH:.0f} Hz", rows[:, 0] > HIGH)):
        e0, e1 = np.abs(rows[sel, 1]), np.abs(rows[sel, 2])
        if e0.size:
            say(f"{label} ({e0.size}): median |error| without {np.median(e0):.1%}, with {np.median(e1):.1%}; "
                f"within 20 %: {int(np.sum(e0 < 0.2))} / {int(np.sum(e1 < 0.2))}")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[7201, 7202, 7203, 7204])
    args = shank_options(ap, argv)
    tb.FREQ = np.arange(100.0, FMAX + 1e-9, 10.0)
    tb.CAMPAIGN_OPTIONS = {"smoothing": 9, "fit_band": [100.0, FMAX]}
    tb.RECORD_INSERTION = args.record_insertion
    run(args.catalogue, args.seeds)


if __name__ == "__main__":
    main()
