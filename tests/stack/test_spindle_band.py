"""The band's spindle-estimate term (issue 22 item 1): a spindle estimated from extension-bar taps.

Known answers: a modelled spindle (the fixture stack's shaft on two bearing sets) is the truth; a Ø40 × 100 mm
bar fixed to its nose is tapped at 50 and 100 mm (the exact coupled assembly, then seeded relative complex noise);
the extension method recovers the spindle exactly from noise-free taps, so the term must vanish there, and with
noisy taps the band of the tip peak must contain the tip peak of the *exact* spindle about as often as it says.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from jointdb.coupling import Interface, couple, rotations_by_extension
from jointdb.fe import BeamModel, HystereticDamping, NamedPoint, Segment
from jointdb.stack import MeasuredSpindle, predict_tool_tip, prediction_grid, stack_from_dict
from jointdb.stack._band import tip_band
from jointdb.stack._predict import spindle_model
from jointdb.stack._spindle_band import SpindleEstimate, spindle_deviations, tap_noise_level

ROOT = Path(__file__).resolve().parents[2]
STACK = ROOT / "fixtures" / "stacks" / "endmill-modelled-spindle.json"
NOISE = 0.0075  # the issue's campaigns' tap noise


@pytest.fixture(scope="module")
def setup():
    spec = stack_from_dict(json.loads(STACK.read_text()))
    f = prediction_grid(spec)
    spindle = spindle_model(spec).frf(f, ["nose"], directions=("x", "ry"))  # node 5: the truth
    bar = BeamModel(segments=(Segment(0.10, 0.04),),
                    points=(NamedPoint("joint", 0.0, 10), NamedPoint("p1", 0.05, 11), NamedPoint("p2", 0.10, 12)),
                    ingredients=(HystereticDamping(0.002),), max_element_length=0.005)
    bar_frf = bar.frf(f)
    taps = couple({"A": spindle, "E": bar_frf}, [Interface("A", ["5x", "5ry"], "E", ["10x", "10ry"])],
                  [("E", "11x"), ("E", "12x")])
    exact = spec.replace(spindle=MeasuredSpindle("spindle.uff", 5, spindle))
    true_peak = float(np.abs(predict_tool_tip(exact, {}, f).tip.values[:, 0, 0]).max())
    return spec, f, spindle, bar_frf, taps, true_peak


def noisy(frf, level, seed):
    rng = np.random.default_rng(seed)
    z = (rng.standard_normal(frf.values.shape) + 1j * rng.standard_normal(frf.values.shape)) / np.sqrt(2)
    return frf.replace(values=frf.values * (1 + level * z))


def estimated(setup, taps, noise=None):
    """The stack on the spindle the extension method estimates from ``taps``, with its estimate record."""
    spec, _, _, bar_frf, _, _ = setup
    h33, _ = rotations_by_extension(taps, bar_frf, 10, (11, 12), 5)
    est = SpindleEstimate(taps, bar_frf, 10, (11, 12), noise)
    return spec.replace(spindle=MeasuredSpindle("spindle.uff", 5, h33, estimate=est)), est, h33


def test_tap_noise_level_recovers_the_seeded_level(setup):
    taps = setup[4]
    # ~4,800 real/imaginary parts: the median's standard error is ~2 %; the FRF's own curvature adds ~2 % at 0.2 %
    for level in (0.002, NOISE, 0.02):
        for seed in range(3):
            assert tap_noise_level(noisy(taps, level, seed)) / level == pytest.approx(1.0, abs=0.08)
    assert tap_noise_level(taps) < 1e-6  # noise-free: the fourth differences of a smooth FRF


def test_noise_free_taps_give_a_zero_spindle_term(setup):
    spec, f, spindle, _, taps, _ = setup
    s, est, h33 = estimated(setup, taps)
    assert np.max(np.abs(h33.values - spindle.values) / np.abs(spindle.values)) < 1e-6  # the estimate is exact
    b = tip_band(s, {}, None, f, n=200, seed=1, spindle_estimate=est)
    p = b.peak["x"]
    assert (p[2] - p[0]) / 2 / p[1] < 1e-4  # against ~0.4 with 0.75 % noise on the taps (below)
    zero = SpindleEstimate(taps, est.extension, 10, (11, 12), noise=0.0)
    assert not np.any(spindle_deviations(zero, f, 5, np.random.default_rng(0)))
    assert zero.noise_level() == (0.0, "stated") and est.noise_level()[1] == "estimated from the taps"


def test_band_covers_the_exact_spindle_about_as_often_as_it_says(setup):
    """40 independent noisy tap sets (0.75 %): does each band contain the tip of the *exact* spindle?

    Per line, the 5–95 % band of |H| must contain the exact tip's |H| on 90 % of the lines and tap sets: the
    200-sample percentiles put each tail's level within ±1.5 % (one standard error), so the mean over 40 × 599
    lines lies within ±3 % of 90 % (measured: 89.2 %, per tap set 85–92 %). The dominant peak's band contains the
    exact peak on ≥ 31 of 40 (binomial sd 4.7 % at 90 %: 3 sd; measured 37) — but not symmetrically: a per-line
    estimate puts spikes on the tip FRF, which only ever raise its largest |H|, so the exact peak sits in the
    lower part of the band (its rank among the samples has median ≈ 0.2, not 0.5)."""
    spec, f, spindle, _, taps, true_peak = setup
    exact = np.abs(predict_tool_tip(spec.replace(spindle=MeasuredSpindle("s.uff", 5, spindle)), {}, f)
                   .tip.values[:, 0, 0])
    per_line, ranks = [], []
    for t in range(40):
        s, est, _ = estimated(setup, noisy(taps, NOISE, 100 + t))
        b = tip_band(s, {}, None, f, n=200, seed=t, spindle_estimate=est)
        m = b.magnitude["x"]
        per_line.append(np.mean((m[0] <= exact) & (exact <= m[2])))
        ranks.append(float(np.mean(np.abs(b.tips["x"]).max(axis=1) < true_peak)))
    assert np.mean(per_line) == pytest.approx(0.90, abs=0.03), np.mean(per_line)
    ranks = np.array(ranks)
    assert int(np.sum((ranks >= 0.05) & (ranks <= 0.95))) >= 31
    assert np.median(ranks) < 0.5  # the documented skew (if this fails, the docs' wording must change too)


def test_a_noise_understated_tenfold_is_caught_by_the_coverage(setup):
    """The coverage check has power: stating a tenth of the taps' real noise leaves the exact spindle outside."""
    _, f, _, _, taps, true_peak = setup
    inside = 0
    for t in range(20):
        s, est, _ = estimated(setup, noisy(taps, NOISE, 300 + t), noise=NOISE / 10)
        p = tip_band(s, {}, None, f, n=200, seed=t, spindle_estimate=est).peak["x"]
        inside += bool(p[0] <= true_peak <= p[2])
    assert inside <= 10


def test_a_stack_file_names_the_taps_and_predict_reports_the_spindle_term(setup, tmp_path):
    """``spindle.estimate`` in a stack file: the taps and the bar's model are read beside it; `jointdb predict
    --json` reports the spindle-estimate term (it dominates: 0.75 % tap noise against 2 % for the path)."""
    from typer.testing import CliRunner

    from jointdb.cli import app
    from jointdb.fe import model_to_dict
    from jointdb.io import write_uff58
    from jointdb.stack import stack_to_dict
    from jointdb.usecases import load_stack

    spec, f, _, _, taps, _ = setup
    taps_n = noisy(taps, NOISE, 7)
    _, _, h33 = estimated(setup, taps_n)
    write_uff58(tmp_path / "taps.uff", taps_n)
    write_uff58(tmp_path / "spindle.uff", h33)
    bar = BeamModel(segments=(Segment(0.10, 0.04),),
                    points=(NamedPoint("joint", 0.0, 10), NamedPoint("p1", 0.05, 11), NamedPoint("p2", 0.10, 12)),
                    ingredients=(HystereticDamping(0.002),), max_element_length=0.005)
    (tmp_path / "bar.json").write_text(json.dumps(model_to_dict(bar)))
    doc = stack_to_dict(spec)
    doc["spindle"] = {"file": "spindle.uff", "node": 5, "estimate": {
        "taps": "taps.uff", "extension": "bar.json", "joint_point": "joint", "points": ["p1", "p2"]}}
    (tmp_path / "stack.json").write_text(json.dumps(doc))
    loaded = load_stack(tmp_path / "stack.json")
    est = loaded.spindle.estimate
    assert isinstance(est, SpindleEstimate) and est.e_points == (11, 12)
    assert est.noise_level()[0] == pytest.approx(NOISE, rel=0.1)
    assert stack_to_dict(stack_from_dict(doc))["spindle"]["estimate"]["taps"] == "taps.uff"  # round trip
    r = CliRunner().invoke(app, ["predict", str(tmp_path / "stack.json"), "--json"])
    assert r.exit_code == 0, r.output
    band = json.loads(r.stdout)["band"]
    assert band["dominant_term"] == "spindle estimate"
    rows = {t["term"]: t for t in band["terms"]}
    assert rows["spindle estimate"]["zero_because"] is None and rows["spindle estimate"]["peak_half_width"]["x"] > 0.05
    assert "validation assembly" in rows["substructure model"]["zero_because"]
    assert "band: the dominant term is spindle estimate" in r.stderr
    doc["spindle"]["estimate"]["points"] = ["p1", "nowhere"]
    (tmp_path / "bad.json").write_text(json.dumps(doc))
    bad = CliRunner().invoke(app, ["predict", str(tmp_path / "bad.json"), "--json"])
    from jointdb.errors import InputError

    assert bad.exit_code != 0 and isinstance(bad.exception, InputError)  # the CLI's main maps it to one line
    assert "spindle.estimate: unknown point 'nowhere'" in str(bad.exception)


def test_taps_that_are_not_reciprocal_give_deviations_without_an_offset(setup):
    """A measured tap matrix has G_12 ≠ G_21 (noise on every entry); the samples set G_21 = G_12, so the
    nominal estimate they are compared with must use the same reciprocal part: at a vanishing noise level
    the deviations vanish with it (an offset of (G_12 − G_21) / 2 would stay)."""
    from jointdb.stack._spindle_band import SpindleEstimate, spindle_deviations

    _, f, spindle, bar_frf, taps, _ = setup
    measured = noisy(taps, 0.0075, 3)
    v = measured.values
    assert np.median(np.abs(v[:, 0, 1] - v[:, 1, 0]) / np.abs(v[:, 0, 1])) > 0.005  # the case in point
    d = spindle_deviations(SpindleEstimate(measured, bar_frf, 10, (11, 12), 1e-9), f, 20, np.random.default_rng(0))
    h = np.abs(spindle.values[:, 0, 0])
    # linear in the noise level: 1e-9 relative noise moves the estimate by ~1e-9 × its conditioning (≤ 1e3 here)
    assert np.median(np.abs(d.mean(axis=0)[:, 0, 0]) / h) < 1e-5
