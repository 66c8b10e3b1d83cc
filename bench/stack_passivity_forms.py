"""The interpolation's passivity rule in three forms on the ten family-C stacks that tell them apart (issue 22).

docs/validation/stack-bands-family-c.md, *High modes*: short end mills whose 9–10 kHz tip peaks came out 8–10×
too high with plain barycentric weights (C02-23, C05-07, C05-08, C05-11, C05-21), and Ø12–Ø16 stacks whose 1 kHz
peaks the first forms of the rule moved (C10-17, C12-10, C12-20, C11-07, C12-06). For each, in one process on
one catalogue, the peak error of the dominant mode (and the predicted dominant frequency) with

* ``plain``: the barycentric weights on every line (the code before the rule);
* ``imonly``: the loss (Im Z) from the passive neighbours wherever *a neighbour* is non-passive;
* ``product``: the same, but only where the barycentric average is *itself* non-passive
  (``jointdb.store._query.passive_line_weights``, what ``predict`` uses).

    python bench/stack_passivity_forms.py --catalogue /tmp/c     # builds the family-C catalogue there if empty
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import _stack_truth_c as tc  # noqa: E402
import _stack_validation as sv  # noqa: E402
from stack_hfmode_cause import command_line, family_c_repo, plain_weights, predict_with  # noqa: E402

#: (seed, index in draw) of the ten stacks
CASES = {"C02-23": (7302, 22), "C05-07": (7305, 6), "C05-08": (7305, 7), "C05-11": (7305, 10), "C05-21": (7305, 20),
         "C10-17": (7310, 16), "C12-10": (7312, 9), "C12-20": (7312, 19), "C11-07": (7311, 6), "C12-06": (7312, 5)}


def _imonly(weights, z, tol=1e-6):
    """The rule's earlier form: the loss from the passive neighbours wherever *a neighbour* is non-passive."""
    weights = np.asarray(weights, float)
    diag = np.diagonal(z, axis1=2, axis2=3)
    passive = np.all(diag.imag >= -tol * np.abs(diag), axis=2)
    w = weights[:, None] * passive
    total = w.sum(axis=0)
    keep = (total > 0) & ~np.all(passive, axis=0)
    w_lines = np.where(keep[None, :], w / np.where(total > 0, total, 1.0)[None, :], weights[:, None])
    return w_lines, np.count_nonzero(keep[None, :] & ~passive & (weights[:, None] > 0), axis=1)


def run(catalogue: Path, say=print) -> None:
    forms = {"plain": plain_weights, "imonly": _imonly, "product": None}
    with family_c_repo(catalogue, say) as repo:
        say("| stack | truth dominant [Hz] | " + " | ".join(forms) + " |")
        say("|---|---|" + "---|" * len(forms))
        for key, (seed, i) in CASES.items():
            case = tc.draw(24, seed)[i]
            thz, tpk = sv._dominant(tc.truth_tip(case).values[:, 0, 0], tc.FREQ)
            cells = []
            for weights in forms.values():
                phz, ppk = sv._dominant(predict_with(case, repo, weights).prediction.tip.values[:, 0, 0], tc.FREQ)
                cells.append(f"{ppk / tpk - 1:+.1%} ({phz:.0f})")
            say(f"| {key} | {thz:.0f} | " + " | ".join(cells) + " |")


def main(argv=None) -> None:
    command_line(run, __doc__, argv)


if __name__ == "__main__":
    main()
