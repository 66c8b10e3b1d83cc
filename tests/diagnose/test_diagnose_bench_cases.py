"""The benchmark's stack cases (tool in holder) and how the benchmark scores them.

Seeds here are development seeds (< 1000); the reported benchmark starts at 1000.
"""

import numpy as np
import pytest

from jointdb.diagnose_bench import EFFECTS, generate_case
from jointdb.diagnose_bench._run import (
    BenchResult,
    CaseResult,
    expected_families,
    placement_tolerance,
    truth_position,
)
from jointdb.errors import InputError
from jointdb.fe import model_from_dict

STACK = ("interface_joint", "interface_softening", "interface_none")
_CACHE: dict = {}


def _case(effect, seed):
    if (effect, seed) not in _CACHE:
        _CACHE[(effect, seed)] = generate_case(effect, seed)
    return _CACHE[(effect, seed)]


def _load(model: dict):
    """The nominal model through jointdb.fe, or skip if this jointdb cannot read insertions yet."""
    try:
        return model_from_dict(model)
    except InputError as exc:
        if "insertions" in model and "insertions" in str(exc):
            pytest.skip(f"jointdb.fe does not read model-file insertions yet: {exc}")
        raise


def test_stack_effects_are_part_of_the_benchmark():
    assert all(e in EFFECTS for e in STACK)
    assert EFFECTS[:10] == ("none", "joint_compliance", "joint_damping", "sensor_mass", "shear_rotary",
                            "fluted_diameter", "hysteretic_damping", "gain", "delay", "softening_joint")


@pytest.mark.parametrize("effect", STACK)
def test_cases_are_deterministic_per_seed(effect):
    a, b = _case(effect, 2), generate_case(effect, 2)
    assert a.model == b.model and a.truth == b.truth and a.point_map == b.point_map
    for ra, rb in zip(a.recordings, b.recordings, strict=True):
        assert np.array_equal(ra.frf.values, rb.frf.values) and np.array_equal(ra.coherence, rb.coherence)
    other = generate_case(effect, 3)
    assert other.truth["geometry"] != a.truth["geometry"]


@pytest.mark.parametrize("effect", STACK)
def test_truth_records_the_interface_and_the_nominal_model_is_what_a_user_writes(effect):
    c = _case(effect, 1)
    t = c.truth
    for key in ("interface_z_m", "insertion_m", "contact_stiffness_n_per_m2", "contact_loss",
                "nominal_variant", "rigid_clamp_shift_modes_1_3", "base_stiffness", "noise_rel", "geometry"):
        assert key in t, key
    assert 0.020 <= t["insertion_m"] <= 0.045
    # the spindle face is stiff: a rigid clamp changes modes 1-3 by less than 1.5 %
    assert all(0 < s < 0.015 for s in t["rigid_clamp_shift_modes_1_3"])
    m = c.model
    seg = m["segments"]
    assert m["clamps"] == [{"position": 0.0}] and m["max_element_length"] <= 0.005
    # holder body + nose from the spindle face, then the tool: the face is where the tool starts
    assert seg[0]["length"] + seg[1]["length"] == pytest.approx(t["interface_z_m"], abs=1e-9)
    pts = {p["name"]: p["position"] for p in m["points"]}
    total = sum(s["length"] for s in seg)
    assert pts["tip"] == pytest.approx(total, abs=1e-9) and max(pts.values()) == pts["tip"]
    assert t["interface_z_m"] < pts["shank"] < t["interface_z_m"] + 0.01
    assert 2 <= len(pts) <= 3 and len(c.recordings[0].frf.outputs) == len(pts)
    assert len(c.recordings[0].frf.inputs) == 2
    if t["nominal_variant"] == "b":
        (ins,) = m["insertions"]
        assert ins["end"] == pytest.approx(t["interface_z_m"]) and ins["contact"] == "rigid"
        assert ins["end"] - ins["start"] == pytest.approx(t["insertion_m"])
        assert ins["joined_at"] == "end"
    else:
        assert "insertions" not in m
    plain = {k: v for k, v in m.items() if k != "insertions"}
    model_from_dict(plain)                      # variant (a) is a valid model file
    if effect == "interface_none":
        assert t["nominal_variant"] == "b" and t["contact_stiffness_n_per_m2"] >= 1e15
    if effect == "interface_softening":
        assert t["levels_n"] == [0.5, 5.0, 25.0]
        assert [r.level_n for r in c.recordings] == t["levels_n"]
        assert 0.01 <= t["first_mode_shift"] <= 0.04


def test_nominal_variants_are_both_drawn():
    variants = {generate_case("interface_joint", s).truth["nominal_variant"] for s in range(6)}
    assert variants == {"a", "b"}


def _chi(model, rec, drop_inputs=False):
    """RMS of |H_model − H_rec| / σ over all lines, σ from the recorded coherence."""
    names = [p.name for p in model.points]
    H = model.frf(rec.frf.freq, points=names, directions=["x"]).values[:, :, :2]
    g2 = rec.coherence
    sigma = np.abs(rec.frf.values) * np.sqrt((1 - g2) / g2)
    return float(np.sqrt(np.mean((np.abs(H - rec.frf.values) / sigma) ** 2)))


@pytest.mark.parametrize("seed", [0, 1])
def test_stack_null_case_nominal_agrees_with_the_truth_at_the_noise_level(seed):
    c = _case("interface_none", seed)
    model = _load(c.model)
    chi = _chi(model, c.recordings[0])
    # noise alone gives chi ≈ 0.95-1 (the coherence's σ is up to 10 % generous); what may remain:
    # the spindle face (rigid-clamp shift ≤ 1.5e-4), the contact at k' ≥ 1e16 and the 3 mm mesh
    # (together ≲ 2e-4 in mode 3: chi 0.96-0.99 measured on development seeds 0-5). The same
    # nominal on a 5 mm mesh (mode 3 ≈ 5e-4 high) gave chi up to 1.15, and up to 1.35 with a
    # spindle face 3x softer; leaving out the inserted shank gives chi > 40.
    assert chi < 1.25, chi
    # leaving the inserted shank out of the nominal model is far from the truth (the check can fail)
    plain = model_from_dict({k: v for k, v in c.model.items() if k != "insertions"})
    assert _chi(plain, c.recordings[0]) > 10


def test_interface_joint_is_visible_against_the_nominal():
    c = next(c for c in (generate_case("interface_joint", s) for s in range(10))
             if c.truth["nominal_variant"] == "b")
    model = _load(c.model)
    f_nom = model.modes(1).freq_hz[0]
    assert c.truth["natural_frequencies_hz"][0] < 0.99 * f_nom      # the compliant contact lowers mode 1


def _first_peak(rec, f1):
    """Frequency [Hz] and half-power damping ratio of the tip receptance's first peak."""
    f = rec.frf.freq
    h = np.abs(rec.frf.values[:, 0, 0])
    w = (f > 0.85 * f1) & (f < 1.03 * f1)
    fw, hw = f[w], h[w]
    i = int(np.argmax(hw))
    sl = slice(max(i - 3, 0), i + 4)
    c = np.polyfit(fw[sl] - fw[i], hw[sl], 2)       # parabola through 7 lines (noise 1-2 %)
    fp = fw[i] - c[1] / (2 * c[0])
    above = fw[hw >= np.polyval(c, fp - fw[i]) / np.sqrt(2)]
    return fp, (above.max() - above.min()) / (2 * fp)


@pytest.mark.parametrize("seed", [0, 1])
def test_amplitude_case_recorded_first_peak_moves_down_and_damping_rises_with_level(seed):
    c = _case("interface_softening", seed)
    f1 = c.truth["natural_frequencies_hz"][0]
    peaks = [_first_peak(r, f1) for r in c.recordings]
    f = np.array([p[0] for p in peaks])
    zeta = np.array([p[1] for p in peaks])
    df = c.truth["resolution_hz"]
    # 0.5 -> 5 -> 25 N: each step moves the peak down by more than a third of a line
    assert np.all(np.diff(f) < -df / 3), f
    # the total shift is the one the generator aimed at (1-4 %), seen in the noisy recording
    assert 0.01 <= 1 - f[-1] / f[0] <= 0.04
    assert f[-1] / f[0] == pytest.approx(c.truth["first_peak_hz_per_level"][-1] / c.truth["first_peak_hz_per_level"][0],
                                         abs=df / f[0])
    assert zeta[-1] > 1.2 * zeta[0], zeta


def _result(effect, named, top3=(), position=None, placed=None, truth=None):
    return CaseResult(case=f"{effect}-0", effect=effect, named=named, names=(named,), top3=top3,
                      improvement=2.0, mismatch_before=0.2, mismatch_after=0.1, seconds=1.0,
                      truth=truth or {}, position=position, placed=placed)


def test_scoring_expected_families_and_placement():
    assert expected_families("interface_joint") == ("joint_compliance", "joint_damping")
    assert expected_families("interface_none") == ("none",)
    assert expected_families("interface_softening") == ("softening_joint",)
    assert expected_families("gain") == ("gain",)
    t = {"interface_z_m": 0.09, "insertion_m": 0.03}
    assert truth_position("interface_joint", t) == 0.09
    assert truth_position("interface_none", t) is None
    assert truth_position("joint_compliance", {"insertion_m": 0.04}) == 0.0
    assert truth_position("gain", {}) is None
    assert placement_tolerance(t) == 0.005 and placement_tolerance({"insertion_m": 0.08}) == pytest.approx(0.008)
    assert _result("interface_joint", "joint_damping").first
    assert not _result("interface_joint", "fluted_diameter", top3=("fluted_diameter", "joint_compliance")).first
    assert _result("interface_joint", "fluted_diameter", top3=("fluted_diameter", "joint_compliance")).in_top3
    assert _result("interface_none", "none").first and not _result("interface_none", "gain").first


def test_per_effect_rows_report_placement_and_false_alarms():
    t = {"interface_z_m": 0.09, "insertion_m": 0.03}
    cases = [_result("interface_joint", "joint_compliance", position=0.089, placed=True, truth=t),
             _result("interface_joint", "joint_compliance", position=0.0, placed=False, truth=t),
             _result("interface_none", "none"), _result("interface_none", "fluted_diameter"),
             _result("gain", "gain")]
    rows = {r["effect"]: r for r in BenchResult(cases, 1.0).per_effect()}
    assert rows["interface_joint"]["named_first_pct"] == 100.0 and rows["interface_joint"]["placed_pct"] == 50.0
    assert rows["interface_none"]["false_alarm_pct"] == 50.0 and "placed_pct" not in rows["interface_none"]
    assert "placed_pct" not in rows["gain"]
    r, cols, m = BenchResult(cases, 1.0).confusion()
    assert r == ["interface_joint", "interface_none", "gain"]
    assert cols[:4] == ["joint_compliance", "joint_damping", "none", "gain"]
    assert m[0, cols.index("joint_compliance")] == 2 and m[1, cols.index("fluted_diameter")] == 1
