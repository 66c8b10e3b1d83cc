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

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import _stack_truth_c as tc  # noqa: E402
import _stack_validation as sv  # noqa: E402

#: (seed, index in draw) of the ten stacks
CASES = {"C02-23": (7302, 22), "C05-07": (7305, 6), "C05-08": (7305, 7), "C05-11": (7305, 10), "C05-21": (7305, 20),
         "C10-17": (7310, 16), "C12-10": (7312, 9), "C12-20": (7312, 19), "C11-07": (7311, 6), "C12-06": (7312, 5)}


def _plain(weights, z, tol=0.0):
    w = np.asarray(weights, float)
    return np.repeat(w[:, None], z.shape[1], axis=1), np.zeros(w.size, int)


def _imonly(weights, z, tol=1e-6):
    weights = np.asarray(weights, float)
    diag = np.diagonal(z, axis1=2, axis2=3)
    passive = np.all(diag.imag >= -tol * np.abs(diag), axis=2)
    w = weights[:, None] * passive
    total = w.sum(axis=0)
    keep = (total > 0) & ~np.all(passive, axis=0)
    w_lines = np.where(keep[None, :], w / np.where(total > 0, total, 1.0)[None, :], weights[:, None])
    return w_lines, np.count_nonzero(keep[None, :] & ~passive & (weights[:, None] > 0), axis=1)


def run(catalogue: Path, say=print) -> None:
    import jointdb.store._query as q
    from jointdb import usecases
    from jointdb.store import Repository

    t0 = time.time()
    say(f"load average at start: {', '.join(f'{v:.2f}' for v in os.getloadavg())}")
    catalogue.mkdir(parents=True, exist_ok=True)
    db = catalogue / "b.sqlite"
    fresh = not db.exists()
    product = q.passive_line_weights
    forms = {"plain": _plain, "imonly": _imonly, "product": product}
    with Repository(f"sqlite:///{db}") as repo:
        if fresh:
            tc.build_catalogue(catalogue, repo, say=lambda s: None)
            say(f"catalogue built in {time.time() - t0:.0f} s")
        say("| stack | truth dominant [Hz] | " + " | ".join(forms) + " |")
        say("|---|---|" + "---|" * len(forms))
        for key, (seed, i) in CASES.items():
            case = tc.draw(24, seed)[i]
            thz, tpk = sv._dominant(tc.truth_tip(case).values[:, 0, 0], tc.FREQ)
            cells = []
            for fn in forms.values():
                q.passive_line_weights = fn
                try:
                    res = usecases.predict_stack(tc.spec_for(case, tc.queries(case)), repo, tc.FREQ)
                finally:
                    q.passive_line_weights = product
                phz, ppk = sv._dominant(res.prediction.tip.values[:, 0, 0], tc.FREQ)
                cells.append(f"{ppk / tpk - 1:+.1%} ({phz:.0f})")
            say(f"| {key} | {thz:.0f} | " + " | ".join(cells) + " |")
    say(f"{time.time() - t0:.0f} s; load average at the end: {', '.join(f'{v:.2f}' for v in os.getloadavg())}")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--catalogue", type=Path, required=True,
                    help="family-C catalogue folder (bench_stack_bands.py --family c --catalogue); built if empty")
    run(ap.parse_args(argv).catalogue)


if __name__ == "__main__":
    main()
