"""The band contains the truth on truth family B (bench/_stack_truth_b.py), a reduced catalogue and three stacks
(the full check, 24 stacks with the calibration's tuning seeds kept apart, is bench/bench_stack_bands.py).

Catalogue: holder–spindle at 10 / 15 / 25 kN; tool–holder on the 10 kN machine only (Ø8 / Ø12 / Ø16 at
30 / 70 / 150 N·m), so a stack on another drawbar force uses them with a note. Tolerance: the truth's dominant
peak |H| and lobe floor lie inside the 90 % band widened by 1 % of the truth (the 200-sample percentiles'
own scatter). Width is judged by the bench on the full catalogue (a 3 × 3 grid on one machine leaves one interior
joint for the leave-one-out, so bands here are wide); here only that the nominal prediction lies inside its band.
"""

from __future__ import annotations

import pytest


@pytest.fixture(scope="module")
def bench(load_script):
    load_script("bench/_stack_validation.py")
    load_script("bench/_stack_family.py")
    tb = load_script("bench/_stack_truth_b.py")
    bb = load_script("bench/bench_stack_bands.py")
    return tb, bb


@pytest.fixture(scope="module")
def repo(bench, tmp_path_factory):
    from jointdb.store import Repository

    tb, _ = bench
    tmp = tmp_path_factory.mktemp("truth-b")
    old = tb.HS_CAMPAIGNS, tb.TH_CAMPAIGNS, tb.TH_MACHINES
    tb.HS_CAMPAIGNS = [c for c in tb.HS_CAMPAIGNS if c.drawbar in (10e3, 15e3, 25e3)]
    tb.TH_CAMPAIGNS = [c for c in tb.TH_CAMPAIGNS if c.drawbar == 10e3]
    tb.TH_MACHINES = (10e3,)
    try:
        with Repository(f"sqlite:///{tmp / 'b.sqlite'}") as r:
            tb.build_catalogue(tmp, r, say=lambda s: None)
            yield r
    finally:
        tb.HS_CAMPAIGNS, tb.TH_CAMPAIGNS, tb.TH_MACHINES = old


@pytest.mark.slow
@pytest.mark.parametrize("i", [0, 1, 2])
def test_the_band_contains_the_true_peak_and_floor(bench, repo, i):
    import _stack_validation as sv

    tb, bb = bench
    cases = [sv.Case("Ø12 end mill, 55 mm gauge, 100 N·m, 18 kN", 0.012, 0.055, 0.035, 100.0, "HSK-A63", 18e3,
                     0.025),
             sv.Case("Ø10 blank, 45 mm gauge, 50 N·m, 12 kN", 0.010, 0.045, 0.034, 50.0, "HSK-A63", 12e3),
             sv.Case("Ø14 end mill, 60 mm gauge, 120 N·m, 22 kN", 0.014, 0.060, 0.036, 120.0, "HSK-A63", 22e3,
                     0.030)]
    row = bb.band_row(cases[i], repo, n=200)
    # a per-line joint that makes the tip non-passive is replaced by its constant k, c (marked, and still banded)
    methods = {k: v.removesuffix(" (constant k, c fallback)") for k, v in row["methods"].items()}
    assert methods == {"tool-holder": "simplex interpolation", "holder-spindle": "simplex interpolation"}
    assert not row["extrapolating"]  # the single tool–holder drawbar force is a note, not an extrapolation
    for key, truth in (("peak", row["truth_peak"]), ("floor", row["truth_floor"])):
        lo, _, hi = row[f"{key}_band"]
        assert lo - 0.01 * truth <= truth <= hi + 0.01 * truth, (key, row)
        nominal = row["pred_peak"] if key == "peak" else row["pred_floor"]
        assert lo <= nominal <= hi, (key, row)
