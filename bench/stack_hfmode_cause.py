"""Why were short end mills' 9–10 kHz tip peaks predicted 8–10× too high on truth family C? (issue 22)

For the five seen family-C stacks whose dominant mode lies at 8.9–10.3 kHz in the truth or the prediction
(C02-23, C05-07, C05-08, C05-11, C05-21; 100 Hz – 12 kHz lines), in one process:

1. the truth's dominant peak (frequency, |H|);
2. the prediction as it is now: the interpolation takes no weight from a neighbour's non-passive lines where another
   neighbour is passive (``jointdb.store._query.passive_line_weights``);
3. the reference: the same prediction with the plain barycentric weights on every line (the code before);
4. for C05-21 only, the joints identified from campaigns *at the stack's own conditions* (the catalogue's 50 mm
   blank geometry, the same 0.2 % noise) — the prediction's error when no joint has to be interpolated — and the
   tool–holder joint's dynamic stiffness at the truth's peak line: interpolated (now / before) against that one.

    python bench/stack_hfmode_cause.py --catalogue /tmp/c      # builds the family-C catalogue there if empty (~30 s)

Prints the load average and the time taken; the lead's quiet-machine numbers go to docs/validation/performance.md.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import _stack_truth_c as tc  # noqa: E402
import _stack_validation as sv  # noqa: E402

#: the five stacks of docs/validation/stack-bands-family-c.md, *Lines that cover the modes*: (seed, index in draw)
CASES = {"C02-23": (7302, 22), "C05-07": (7305, 6), "C05-08": (7305, 7), "C05-11": (7305, 10), "C05-21": (7305, 20)}


def plain_weights(weights, z, tol=0.0):
    """The reference: barycentric weights on every line (no passivity rule)."""
    w = np.asarray(weights, float)
    return np.repeat(w[:, None], z.shape[1], axis=1), np.zeros(w.size, int)


@contextlib.contextmanager
def swapped(module, name: str, value):
    """``module.name`` set to ``value`` inside the block (None: left as it is), restored after it."""
    keep = getattr(module, name)
    setattr(module, name, keep if value is None else value)
    try:
        yield
    finally:
        setattr(module, name, keep)


def predict_with(case, repo, weights=None):
    """``predict_stack`` of family-C stack ``case`` with the interpolation's per-line weights from ``weights``
    (a stand-in for ``jointdb.store._query.passive_line_weights``; None: the product's own)."""
    import jointdb.store._query as q
    from jointdb import usecases

    with swapped(q, "passive_line_weights", weights):
        return usecases.predict_stack(tc.spec_for(case, tc.queries(case)), repo, tc.FREQ)


@contextlib.contextmanager
def family_repo(family, catalogue: Path, say=print):
    """A truth family's catalogue (``family``: e.g. the module ``_stack_truth_b``) in ``catalogue`` (built there if
    empty), with the load average and the time taken said before and after."""
    from jointdb.store import Repository

    t0 = time.time()
    say(f"load average at start: {', '.join(f'{v:.2f}' for v in os.getloadavg())}")
    catalogue.mkdir(parents=True, exist_ok=True)
    db = catalogue / "b.sqlite"
    fresh = not db.exists()
    with Repository(f"sqlite:///{db}") as repo:
        if fresh:
            family.build_catalogue(catalogue, repo, say=lambda s: None)
            say(f"catalogue built in {time.time() - t0:.0f} s")
        yield repo
    say(f"{time.time() - t0:.0f} s; load average at the end: {', '.join(f'{v:.2f}' for v in os.getloadavg())}")


def family_c_repo(catalogue: Path, say=print):
    """:func:`family_repo` of truth family C."""
    return family_repo(tc, catalogue, say)


def command_line(run, doc: str, argv=None) -> None:
    """``run(catalogue)`` from a command line with one option, ``--catalogue DIR``."""
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--catalogue", type=Path, required=True,
                    help="family-C catalogue folder (bench_stack_bands.py --family c --catalogue); built if empty")
    run(ap.parse_args(argv).catalogue)


def _own_conditions(case) -> dict:
    """Both joints identified from noisy campaigns at the stack's torque, diameter and drawbar force (catalogue
    geometry), catalogued into a scratch store."""
    from jointdb import usecases
    from jointdb.store import Repository

    tmp = Path(tempfile.mkdtemp(prefix="hfmode-"))
    with Repository(f"sqlite:///{tmp}/own.sqlite") as repo:
        hs_case = sv.Case("own-hs", 0.016, tc.CAMPAIGN_GAUGE, tc.CAMPAIGN_INSERTION, 60.0, "BT40", case.drawbar)
        usecases.catalogue_campaign(repo, tc.write_hs_campaign(tmp / hs_case.name, hs_case))
        hs = repo.load_frf(repo.get(hs_case.name))
        th_case = sv.Case("own-th", case.diameter, tc.CAMPAIGN_GAUGE, tc.CAMPAIGN_INSERTION, case.torque, "BT40",
                          case.drawbar)
        usecases.catalogue_campaign(repo, tc.write_th_campaign(tmp / th_case.name, th_case, hs))
        return {"tool-holder": repo.load_frf(repo.get(th_case.name)), "holder-spindle": hs}


def _z_at(frf, f_hz: float) -> np.ndarray:
    m = int(np.argmin(abs(frf.freq - f_hz)))
    return np.linalg.inv(frf.values[m])


def run(catalogue: Path, say=print) -> None:
    from jointdb.stack import predict_tool_tip

    f = tc.FREQ
    with family_c_repo(catalogue, say) as repo:
        say("| stack | truth dominant [Hz] | now: error (at Hz) | plain weights (before): error (at Hz) |")
        say("|---|---|---|---|")
        for key, (seed, i) in CASES.items():
            case = tc.draw(24, seed)[i]
            thz, tpk = sv._dominant(tc.truth_tip(case).values[:, 0, 0], f)
            cells, zs = [], {}
            for plain in (False, True):
                res = predict_with(case, repo, plain_weights if plain else None)
                phz, ppk = sv._dominant(res.prediction.tip.values[:, 0, 0], f)
                cells.append(f"{ppk / tpk - 1:+.1%} ({phz:.0f})")
                zs["plain weights" if plain else "now"] = _z_at(res.joints["tool-holder"].frf, thz)
            say(f"| {case.name} | {thz:.0f} | {cells[0]} | {cells[1]} |")
            if key == "C05-21":
                own = _own_conditions(case)
                own_tip = predict_tool_tip(tc.spec_for(case, tc.queries(case)), own, f).tip.values[:, 0, 0]
                ohz, opk = sv._dominant(own_tip, f)
                zo = _z_at(own["tool-holder"], thz)
                say(f"  C05-21 with joints identified at its own conditions: {opk / tpk - 1:+.1%} ({ohz:.0f} Hz)")
                for label, z in zs.items():
                    say(f"  Z_xx at {thz:.0f} Hz, {label}: {z[0, 0]:.3e} N/m; own-conditions joint {zo[0, 0]:.3e} "
                        f"(Im ratio {z[0, 0].imag / zo[0, 0].imag:+.3f}, Re ratio {z[0, 0].real / zo[0, 0].real:+.3f})")


def main(argv=None) -> None:
    command_line(run, __doc__, argv)


if __name__ == "__main__":
    main()
