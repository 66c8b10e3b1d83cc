"""Identifiability before naming, and the words of a verdict (units, mode and segment names, no
statement about an effect the recording does not show). Unit tests on hand-made fits and signatures."""

import numpy as np
import pytest

from jointdb.diagnose._compare import ModePair, Peak, Signature, pair_modes
from jointdb.diagnose._fit import Fit
from jointdb.diagnose._identify import IDENTIFIED, damping_grows, unidentified
from jointdb.diagnose._levels import level_outliers
from jointdb.diagnose._verdict import implausibility_text, rank_text, shift_text, unidentified_verdict
from jointdb.diagnose.physics import Candidate, Param


class _Joint(Candidate):
    family = "joint_compliance"
    explanation = "a compliant joint at point 'tip-25mm'"
    location = "point 'tip-25mm'"
    position = 0.055
    params = (Param("k_x", "N/m", 1e5, 1e10, 1e7, either="stiffness", show=1e-6, show_unit="N/µm"),
              Param("k_ry", "N·m/rad", 1e2, 1e7, 1e4, either="stiffness", show=1e-3, show_unit="kN·m/rad"),
              Param("eta_joint", "-", 1e-3, 2.0, 0.1))


def _fit(cand, values, sigmas, at_bound=(), mismatch=0.05, p=None):
    return Fit(cand, dict(values), dict(sigmas), 1.0, 100, p or len(values), 0.0, mismatch, np.array([mismatch]),
               at_bound=list(at_bound))


def test_a_joint_with_no_stiffness_identified_is_not_identified():
    # the case: k_x 1.07e7 ± 1.2e9 N/m (σ 100x the value), and the rotation no better
    f = _fit(_Joint(), {"k_x": 1.07e7, "k_ry": 2e4, "eta_joint": 0.05},
             {"k_x": 1.2e9, "k_ry": 3e4, "eta_joint": 0.01})
    assert set(unidentified(f)) == {"k_x", "k_ry"}
    assert unidentified(f)["k_x"] == pytest.approx(1.2e9 / 1.07e7)


def test_one_identified_stiffness_of_the_pair_suffices_but_every_other_key_parameter_counts():
    f = _fit(_Joint(), {"k_x": 1.07e7, "k_ry": 2e4, "eta_joint": 0.05},
             {"k_x": 1.2e9, "k_ry": 2e3, "eta_joint": 0.01})
    assert unidentified(f) == {}
    # a loss factor at the bound of its range is one-sided (flat likelihood): not identified, whatever σ says
    g = _fit(_Joint(), {"k_x": 1.07e7, "k_ry": 2e4, "eta_joint": 1e-3},
             {"k_x": 1e6, "k_ry": 2e3, "eta_joint": 1e-4}, at_bound=["eta_joint"])
    assert list(unidentified(g)) == ["eta_joint"] and not np.isfinite(unidentified(g)["eta_joint"])
    # the threshold is σ ≤ 0.5 × value
    h = _fit(_Joint(), {"k_x": 1e7, "k_ry": 2e4, "eta_joint": 0.1},
             {"k_x": 1e6, "k_ry": 2e3, "eta_joint": 0.1 * IDENTIFIED * 1.01})
    assert list(unidentified(h)) == ["eta_joint"]


def test_not_resolved_values_are_said_so_and_units_are_never_a_dash():
    c = _Joint()
    text = c.describe({"k_x": 1.07e7, "k_ry": 2e4, "eta_joint": 0.2}, {"k_x": 1.2e9, "k_ry": 2e3, "eta_joint": 0.02})
    assert "k_x ≈ 10.7 N/µm (not resolved by these measurements)" in text
    assert "k_ry = 20 ± 2 kN·m/rad" in text
    assert "eta_joint = 0.2 ± 0.02" in text and " -" not in text and "± 1.2e" not in text
    eq = Param("insertion", "m", 0.01, 0.1, 0.03, show=1e3, show_unit="mm", equivalent=True)
    assert eq.shown(0.0094, 0.00017) == "equivalent insertion = 9.4 ± 0.17 mm"


def test_the_unidentified_verdict_names_a_size_a_place_and_the_measurement_not_the_physics():
    f = _fit(_Joint(), {"k_x": 1.07e7, "k_ry": 2e4, "eta_joint": 0.05},
             {"k_x": 1.2e9, "k_ry": 3e4, "eta_joint": 0.01}, mismatch=0.031)
    text = unidentified_verdict(f, unidentified(f), "the 98 Hz mode is 1.0 % low in the recording", 0.12,
                                "record at two points")
    assert "A joint compliance of this size at point 'tip-25mm'" in text
    assert "not identifiable from these measurements" in text and "nothing is named" in text
    assert "To identify it, record at two points." in text
    assert "k_x 10.7 N/µm ± 11215 %" in text


class _Slip(Candidate):
    family = "softening_joint"
    per_level = True
    explanation = "an amplitude-dependent joint"
    levels = (0.5, 5.0, 25.0)
    params = (Param("eta_0", "-", 1e-3, 1.0, 0.05), Param("eta_max", "-", 1e-3, 1.5, 0.1))

    def state(self, values, level):
        r = self.levels[level] / 5.0
        return 1.0, values["eta_0"] + values["eta_max"] * r / (1 + r)


def test_a_level_dependent_joint_whose_loss_cannot_grow_does_not_explain_growing_damping():
    grows = _fit(_Slip(), {"eta_0": 0.02, "eta_max": 0.2}, {})
    assert damping_grows(grows)
    at_bound = _fit(_Slip(), {"eta_0": 0.02, "eta_max": 1e-3}, {}, at_bound=["eta_max"])
    assert not damping_grows(at_bound)
    tiny = _fit(_Slip(), {"eta_0": 0.2, "eta_max": 0.01}, {})      # 0.2 → 0.208: < ×1.1
    assert not damping_grows(tiny)
    assert not damping_grows(_fit(_Joint(), {"k_x": 1e7, "k_ry": 1e4, "eta_joint": 0.1}, {}))


def test_one_level_off_its_neighbours_trend_is_an_outlier_a_trend_is_not():
    # six levels, 98.4 → 97.4 Hz, the fourth a spike (cf. 18.799 Hz among 18.71–18.73 Hz)
    f = np.array([98.4, 98.2, 98.0, 98.9, 97.8, 97.4])
    sf = np.full(6, 0.02)
    assert level_outliers(f, sf, range(6)) == (3,)
    f = np.array([18.73, 18.725, 18.72, 18.799, 18.715, 18.71])
    assert level_outliers(f, np.full(6, 0.003), [5, 4, 3, 2, 1, 0]) == (3,)
    assert level_outliers(np.array([98.4, 98.2, 98.0, 97.8, 97.6, 97.4]), sf, range(6)) == ()
    assert level_outliers(np.array([98.4, 99.0, 97.4]), sf[:3], range(3)) == ()      # too few levels to tell


def _pair(f_model, f_rec, damping_ratio=1.0, mismatch=0.02, mode=1):
    return ModePair(mode, Peak(f_model, 0.01, 1.0, 0), Peak(f_rec, 0.01, 1.0, 0), f_rec / f_model - 1,
                    damping_ratio, 0.0, mismatch, ("1x",))


def _sig(pairs, overall, delay_s=0.0, delay_r2=0.0, gain_db=0.0):
    return Signature(overall, 0.0, 0.0, {}, pairs, [], [], gain_db, delay_s, delay_r2)


def test_modes_are_named_by_frequency_and_effects_the_recording_does_not_show_are_not_stated():
    # the recording equals the model: no damping ratio, no phase drift, no gain
    sig = _sig([_pair(98.4, 98.4, damping_ratio=0.18), _pair(410.0, 410.5, damping_ratio=0.026, mode=2)], 0.02,
               delay_s=306e-6, delay_r2=0.9, gain_db=0.8)
    text = shift_text(sig)
    assert text == "the 98 and 410 Hz modes are unchanged in frequency"
    # a real departure is stated, mode by frequency
    sig = _sig([_pair(120.0, 111.4, damping_ratio=2.0, mismatch=0.4), _pair(410.0, 410.5, mode=2)], 0.3,
               delay_s=50e-6, delay_r2=0.9)
    text = shift_text(sig)
    assert text.startswith("the 111 Hz mode (120 Hz in the model) is 7.2 % low in the recording; "
                           "the 410 Hz mode is unchanged")
    assert "recorded damping is ×2 the model's at the 111 Hz mode" in text and "410 Hz mode at" not in text
    assert "≈ 50 µs" in text and "mode 1" not in text and "mode 2" not in text


def test_peaks_are_paired_by_shape_as_well_as_frequency():
    # a model mode at 120 Hz with shape (1, 1); recorded peaks at 98 Hz (shape (1, 1)) and 118 Hz (1, −1):
    # by frequency alone 118 Hz would be its partner; by shape it is 98 Hz, and 118 Hz is an extra peak
    model = [Peak(120.0, 0.01, 1.0, 0)]
    rec = [Peak(98.0, 0.01, 1.0, 0), Peak(118.0, 0.01, 1.0, 1)]
    pairs, extra, missing = pair_modes(model, rec, model_shapes=[np.array([1.0, 1.0])],
                                       rec_shapes=[np.array([1.0, 1.0]), np.array([1.0, -1.0])])
    assert pairs == [(0, 0)] and extra == [118.0] and missing == []
    pairs, *_ = pair_modes(model, rec)
    assert pairs == [(0, 1)]


def test_an_implausible_value_is_shown_with_digits_that_show_it_outside():
    q = Param("diameter", "m", 0.006, 0.014, 0.01, show=1e3, show_unit="mm", plausible=(0.008, 0.012))

    class _D(Candidate):
        params = (q,)
    f = _fit(_D(), {"diameter": 0.00796}, {})
    f.implausible = {"diameter": q.implausibility(0.00796)}
    assert "diameter 7.96 mm, plausible 8–12 mm" in implausibility_text(f)


def test_the_verdict_says_why_rank_one_beats_the_next():
    best = _fit(_Joint(), {"k_x": 1e7, "k_ry": 1e4, "eta_joint": 0.1}, {}, mismatch=0.03)
    best.score = -100.0
    worse = _fit(_Slip(), {"eta_0": 0.02, "eta_max": 0.2}, {}, mismatch=0.09)
    worse.score = -50.0
    text = rank_text(best, worse, lambda f: True)
    assert text == " The next ranked, an amplitude-dependent joint, leaves 9.0 % on the fit lines against 3.0 %."
    assert "cannot follow the recorded change" in rank_text(best, worse, lambda f: f is best)


class _Contact(Candidate):
    family = "joint_compliance"
    explanation = "a compliant contact over an insertion"
    params = (Param("k_contact", "N/m²", 1e10, 1e14, 1e12, equivalent=True, either="contact"),
              Param("insertion", "m", 0.005, 0.08, 0.03, equivalent=True, either="contact"))


def test_equivalent_parameters_that_trade_off_are_identified_by_their_combination_only():
    from jointdb.diagnose._identify import combination_note

    # k' and L each ±100 % (log σ 1), correlation −0.99: their product is known to ±14 % — named, and said so
    cov = np.array([[1.0, -0.99], [-0.99, 1.0]])
    f = _fit(_Contact(), {"k_contact": 4.7e12, "insertion": 0.0215}, {"k_contact": 4.7e12, "insertion": 0.0215})
    f.cov_u = cov
    assert unidentified(f) == {}
    assert "equivalent k_contact and equivalent insertion trade off" in combination_note(f)
    # uncorrelated, both ±100 %: nothing is identified
    f.cov_u = np.eye(2)
    assert set(unidentified(f)) == {"k_contact", "insertion"} and combination_note(f) == ""
