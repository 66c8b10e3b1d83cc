"""Prediction from the catalogue on a tool tip it never saw (truth: contact layers at both interfaces, spindle
with its rotor on bearings), and the extrapolation warning outside the catalogued range.

A reduced version of bench/bench_stack_prediction.py: 2 holder–spindle and 2 tool–holder campaigns."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def sv():
    spec = importlib.util.spec_from_file_location("_stack_validation", ROOT / "bench" / "_stack_validation.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules["_stack_validation"] = module
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def repo(sv, tmp_path_factory):
    from jointdb.store import Repository

    tmp = tmp_path_factory.mktemp("validation")
    hs = [c for c in sv.HS_CAMPAIGNS if c.taper == "HSK-A63" and c.drawbar in (12e3, 18e3, 24e3)]
    th = [c for c in sv.TH_CAMPAIGNS if c.diameter == 0.012 and c.torque in (40.0, 120.0)]
    with Repository(f"sqlite:///{tmp / 'j.sqlite'}") as r:
        old = sv.HS_CAMPAIGNS, sv.TH_CAMPAIGNS
        sv.HS_CAMPAIGNS, sv.TH_CAMPAIGNS = hs, th
        try:
            sv.build_catalogue(tmp, r, say=lambda s: None)
        finally:
            sv.HS_CAMPAIGNS, sv.TH_CAMPAIGNS = old
        yield r


@pytest.mark.slow
def test_unseen_stack_inside_the_range_is_predicted_within_the_goals_and_far_better_than_rigid(sv, repo):
    case = sv.Case("Ø12 blank, 65 mm gauge, 60 N·m, HSK-A63 15 kN", 0.012, 0.065, 0.032, 60.0, "HSK-A63", 15e3)
    row = sv.validate(case, repo)
    assert not row["extrapolating"] and not row["warnings"]
    # the goals: 3 % / 20 % / 20 %
    assert abs(row["cat_freq_err"]) < 0.03 and abs(row["cat_peak_err"]) < 0.20 and abs(row["cat_floor_err"]) < 0.20
    # rigid joints miss the dominant mode by tens of per cent: the catalogue is several times better
    assert abs(row["rigid_freq_err"]) > 5 * abs(row["cat_freq_err"])


@pytest.mark.slow
def test_outside_the_catalogued_range_the_extrapolation_warning_fires(sv, repo):
    case = sv.Case("Ø12, 200 N·m, HSK-A63 30 kN", 0.012, 0.055, 0.035, 200.0, "HSK-A63", 30e3)
    row = sv.validate(case, repo)
    assert row["extrapolating"]
    text = " ".join(row["warnings"])
    assert "torque_nm" in text and "preload_n" in text and "outside the catalogued range" in text
