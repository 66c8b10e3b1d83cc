"""Prediction from the catalogue on a tool tip it never saw (truth: contact layers at both interfaces, spindle
with its rotor on bearings), and the extrapolation warning outside the catalogued range.

A reduced version of bench/bench_stack_prediction.py: 4 holder–spindle and 12 tool–holder campaigns; the
held-out draw and the spindle estimated from noisy translations."""

from __future__ import annotations

import pytest


@pytest.fixture(scope="module")
def sv(load_script):
    return load_script("bench/_stack_validation.py")


@pytest.fixture(scope="module")
def ho(sv, load_script):
    return load_script("bench/_stack_heldout.py")


@pytest.fixture(scope="module")
def repo(sv, tmp_path_factory):
    from jointdb.store import Repository

    tmp = tmp_path_factory.mktemp("validation")
    hs = [c for c in sv.HS_CAMPAIGNS if (c.taper, c.drawbar) in
          (("HSK-A63", 12e3), ("HSK-A63", 24e3), ("BT40", 8e3), ("BT40", 16e3))]
    # HSK: Ø12 at 40 / 80 N·m, Ø10 at 40 / 120 N·m (a Ø10 90 N·m request's two nearest include a Ø12 joint:
    # the inverse-distance failure of issue 15); BT40: Ø12 at 40 / 80 N·m; each on both machines of its family
    th = [c for c in sv.TH_CAMPAIGNS if (c.taper == "HSK-A63" and (c.diameter, c.torque) in
          ((0.012, 40.0), (0.012, 80.0), (0.010, 40.0), (0.010, 120.0)))
          or (c.taper == "BT40" and (c.diameter, c.torque) in ((0.012, 40.0), (0.012, 80.0)))]
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
    # no warning; notes (e.g. which neighbours' non-passive lines the interpolation left out) are information
    assert not row["extrapolating"] and not [w for w in row["warnings"] if not w.startswith("note:")]
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


@pytest.mark.slow
def test_a_request_between_torques_is_interpolated_along_the_torque_axis_not_from_another_shank(sv, repo):
    case = sv.Case("Ø10 end mill, 40 mm gauge, 90 N·m, HSK-A63 18 kN", 0.010, 0.040, 0.032, 90.0, "HSK-A63",
                   18e3, 0.020)
    row = sv.validate(case, repo, before=True)
    used = row["joints"]["tool-holder"]
    assert "d10-040nm" in used and "d10-120nm" in used and "d12" not in used and "bt40" not in used
    assert abs(row["cat_freq_err"]) < 0.03 and abs(row["cat_peak_err"]) < 0.20 and abs(row["cat_floor_err"]) < 0.20
    # the inverse-distance weights of the two nearest take a Ø12 joint
    assert "d12" in row["idw_joints"]["tool-holder"]


def test_the_held_out_draw_is_fixed_and_inside_the_catalogued_range(sv, ho):
    cases = ho.draw_heldout()
    assert [c.name for c in cases] == [c.name for c in ho.draw_heldout()] and len(set(c.name for c in cases)) == 18
    forces = {t: [c.drawbar for c in sv.HS_CAMPAIGNS if c.taper == t] for t in sv.TAPERS}
    for c in cases:
        assert 0.010 <= c.diameter <= 0.016 and 40.0 <= c.torque <= 120.0 and 0 <= c.fluted < c.gauge
        assert min(forces[c.taper]) <= c.drawbar <= max(forces[c.taper])
    assert {c.taper for c in cases} == set(sv.TAPERS) and any(c.fluted for c in cases) and not all(c.fluted for c in cases)


def test_the_spindle_from_noisy_translations_is_as_close_as_its_noise_amplification_says(sv, ho):
    import numpy as np

    from jointdb.frf import Dof

    frf, est = ho.spindle_by_extension("HSK-A63")
    d = [Dof(5, "x"), Dof(5, "ry")]
    exact = sv.spindle_frf("HSK-A63").block(d, d)
    for (i, j), key in (((0, 0), "h"), ((1, 0), "n"), ((1, 1), "p")):
        err = np.abs(frf.values[:, i, j] / exact[:, i, j] - 1)
        # one noisy draw: its median relative error is about the amplification × the noise (RMS over draws);
        # a factor 3 either way allows for one draw and the median vs RMS of a Rayleigh-like error
        expected = est.amplification[key][0] * sv.NOISE
        assert expected / 3 < np.median(err) < 3 * expected


@pytest.mark.slow
def test_tool_holder_joints_are_taken_from_the_stacks_taper_family(sv, repo):
    case = sv.Case("Ø12 blank, 40 mm gauge, 45 N·m, BT40 15 kN", 0.012, 0.040, 0.037, 45.0, "BT40", 15e3)
    row = sv.validate(case, repo, before=True)
    used = row["joints"]["tool-holder"]
    assert "th-bt40-08kn-d12-040nm" in used and "th-bt40-16kn-d12-040nm" in used and "th-hsk" not in used
    assert abs(row["cat_freq_err"]) < 0.03 and abs(row["cat_peak_err"]) < 0.20 and abs(row["cat_floor_err"]) < 0.20
    # (the same torque and shank identified on the HSK-A63 machines is a separate row: with the linear combination of
    # the per-line joints it made a spurious 4.3 kHz resonance the largest peak; with the power-law combination it
    # does not here, so no claim either way is tested)
