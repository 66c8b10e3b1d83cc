"""Why are the bands of short end mills' 8.7–9 kHz peaks skewed upward? (issue 22; family C, seed 7314's misses)

For C13-18 and C14-08 (truth family C, seeds 7313 / 7314, 100 Hz – 12 kHz lines), in one process:

1. the truth's and the prediction's dominant peak, and the joint-choice band alone (200 draws, seed 1, as
   ``bench/bench_stack_bands.py`` draws it) as multiples of the predicted peak;
2. the tool–holder joint's dynamic stiffness Z_xx at the truth's peak line;
3. how many draws make a joint non-passive (Im Z_xx or Im Z_θθ < 0) within ±4 % of the predicted peak where the
   prediction's own joint is passive, and the band of the draws that do not;
4. the half-power damping ratio of the draws at the 5th, 50th, 95th and 99th percentile of the peak.

    python bench/stack_band_skew.py --catalogue /tmp/c      # builds the family-C catalogue there if empty (~30 s)

The numbers are in docs/validation/stack-bands-family-c.md, *Fresh seeds 7315 / 7316*.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import _stack_truth_c as tc  # noqa: E402
import _stack_validation as sv  # noqa: E402
from stack_hfmode_cause import _z_at, command_line, family_c_repo  # noqa: E402

CASES = {"C13-18": (7313, 17), "C14-08": (7314, 7)}
NEAR = 0.04  # lines within ±4 % of the predicted peak count for passivity


def _zeta(h: np.ndarray, f: np.ndarray) -> float:
    """Half-power damping ratio of |h|'s largest peak: the contiguous band around it above |h|max/√2, over twice the
    peak frequency (0 when the band is narrower than a line)."""
    mag = np.abs(h)
    m = int(np.argmax(mag))
    below = mag <= mag[m] / np.sqrt(2)
    lo = m - int(np.argmax(below[m::-1])) if below[:m].any() else 0
    hi = m + int(np.argmax(below[m:])) if below[m:].any() else f.size - 1
    return float((f[hi - 1] - f[lo + 1]) / (2 * f[m]))


def _non_passive_draws(res, f, peak_hz: float, n: int) -> np.ndarray:
    """``(n,)`` True for the draws whose tool–holder or holder–spindle joint is non-passive near the peak on a line
    where the prediction's joint is passive (the draws are those of the band: the same generator and order)."""
    from jointdb.stack._band import _interface_samples
    from jointdb.stack._predict import _joint_planes
    from jointdb.stack._spec import INTERFACE_NAMES
    from jointdb.usecases._stack_band import choice_perturbation

    rng = np.random.default_rng([1, 104729])  # tip_band's generator for seed 1
    choice = {k: choice_perturbation(r, f) for k, r in res.joints.items()}
    resolved = {k: r.frf for k, r in res.joints.items() if r.frf is not None}
    near = np.abs(f - peak_hz) < NEAR * peak_hz
    bad = np.zeros(n, bool)
    for name in INTERFACE_NAMES:
        s = _interface_samples(name, res.spec, resolved, f, n, 1, {}, choice, rng, None)
        if s is None:
            continue
        z, z0 = np.linalg.inv(s["x"]), np.linalg.inv(_joint_planes(name, res.spec, resolved, f)[0]["x"])
        loss = np.minimum(z[..., 0, 0].imag, z[..., 1, 1].imag)
        loss0 = np.minimum(z0[:, 0, 0].imag, z0[:, 1, 1].imag)
        bad |= ((loss < 0) & (loss0 >= 0) & near).any(axis=1)
    return bad


def run(catalogue: Path, say=print) -> None:
    from jointdb import usecases
    from jointdb.usecases._stack_band import prediction_band

    f, n = tc.FREQ, 200
    with family_c_repo(catalogue, say) as repo:
        for key, (seed, i) in CASES.items():
            case = tc.draw(24, seed)[i]
            truth = tc.truth_tip(case).values[:, 0, 0]
            thz, tpk = sv._dominant(truth, f)
            res = usecases.predict_stack(tc.spec_for(case, tc.queries(case)), repo, f)
            phz, ppk = sv._dominant(res.prediction.tip.values[:, 0, 0], f)
            band, _ = prediction_band(res, n, 1, ("joint choice",))
            peaks = np.array([sv._dominant(s, f)[1] for s in band.tips["x"]]) / ppk
            q = np.quantile(peaks, [0.05, 0.5, 0.95])
            say(f"{case.name}\n  truth {thz:.0f} Hz, prediction {phz:.0f} Hz; truth / predicted peak {tpk / ppk:.2f}; "
                f"joint-choice band p05 {q[0]:.2f}, p50 {q[1]:.2f}, p95 {q[2]:.2f} (× predicted)")
            z = _z_at(res.joints["tool-holder"].frf, thz)
            say(f"  tool-holder Z_xx at {thz:.0f} Hz: {z[0, 0]:.3e} N/m")
            bad = _non_passive_draws(res, f, phz, n)
            kept = np.quantile(peaks[~bad], [0.05, 0.95]) if (~bad).sum() > 1 else (np.nan, np.nan)
            say(f"  draws non-passive within ±{NEAR:.0%} of the peak where the prediction is passive: {bad.sum()} / {n};"
                f" the others span {kept[0]:.2f}–{kept[1]:.2f}×")
            order = np.argsort(peaks)
            for pct in (5, 50, 95, 99):
                j = order[min(n - 1, int(round(pct / 100 * (n - 1))))]
                say(f"  draw at p{pct}: peak {peaks[j]:.2f}×, half-power damping ratio {_zeta(band.tips['x'][j], f):.4f}")
            say(f"  prediction's damping ratio {_zeta(res.prediction.tip.values[:, 0, 0], f):.4f}, "
                f"truth's {_zeta(truth, f):.4f}")


def main(argv=None) -> None:
    command_line(run, __doc__, argv)


if __name__ == "__main__":
    main()
