"""Diagnosis of joints *inside* a tool/holder stack, on the benchmark's two-concentric-beam truth.

The truth (jointdb.diagnose_bench, shares no code with jointdb.fe/diagnose) is a
carbide tool in a steel holder bore on a lossy contact layer over the insertion,
the holder on its own spindle-face stiffness; the nominal model is what a user
writes (holder segments clamped at the spindle face, the tool from the holder
face, the inserted shank left out or bonded). Development seeds (< 1000) only:
the reported rates come from `jointdb diagnose-bench` on seeds >= 1000.
"""

import functools

import numpy as np
import pytest

from jointdb.diagnose import MIN_IMPROVEMENT
from jointdb.diagnose_bench import diagnose_case, generate_case
from jointdb.fe import model_to_dict

JOINTS = ("joint_compliance", "joint_damping")
@functools.cache
def _diagnosed(effect, seed):
    """(case, Diagnosis), computed once per session."""
    case = generate_case(effect, seed)
    return case, diagnose_case(case)[1]


def _primary(d):
    c = d.best.candidate
    return c.parts[0] if hasattr(c, "parts") else c


def _placed(case, d):
    tol = max(0.005, 0.1 * case.truth["insertion_m"])
    return d.position is not None and abs(d.position - case.truth["interface_z_m"]) <= tol


@pytest.mark.parametrize("seed", [0, 1])
def test_joint_inside_the_stack_is_named_and_placed_at_the_tool_holder_interface(seed):
    case, d = _diagnosed("interface_joint", seed)
    assert d.explained, d.verdict
    assert _primary(d).family in JOINTS, [f.name for f in d.ranking[:3]]
    assert _placed(case, d), (d.position, case.truth["interface_z_m"])
    assert d.mismatch_before / d.mismatch_after >= 3.0
    assert f"z = {case.truth['interface_z_m'] * 1e3:.4g} mm" in d.verdict
    # the augmented model file holds the joint at that place
    doc = model_to_dict(d.augmented[0])
    where = [j["position"] for j in doc.get("joints", [])] + \
            [i["end"] if i["joined_at"] == "end" else i["start"] for i in doc.get("insertions", [])
             if i["contact"] != "rigid"]
    assert any(abs(z - case.truth["interface_z_m"]) < 1e-9 for z in where), doc


def test_amplitude_dependent_contact_is_named_placed_and_its_trends_match_the_data():
    case, d = _diagnosed("interface_softening", 0)
    assert d.levels_data is not None and d.levels_data.differs
    assert d.explained and _primary(d).family == "softening_joint", [f.name for f in d.ranking[:3]]
    assert _placed(case, d)
    rows = d.level_table
    assert len(rows) == 3
    stiff = [r.get("k_contact_n_per_m2", r.get("k_x_n_per_m")) for r in rows]
    loss = [r["loss_factor"] for r in rows]
    assert stiff[0] > stiff[1] > stiff[2] and loss[0] < loss[1] < loss[2]
    # the augmented model's per-level modes (same local modal fit) move like the recordings':
    # same sign and within 20 % in size, for the first mode's frequency and damping trends
    data, model = d.levels_data.tracks[0], d.levels_model.tracks[0]
    assert np.sign(model.freq_change) == np.sign(data.freq_change) == -1
    assert model.freq_change == pytest.approx(data.freq_change, rel=0.2)
    assert model.zeta_ratio > 1 and data.zeta_ratio > 1
    assert model.zeta_ratio - 1 == pytest.approx(data.zeta_ratio - 1, rel=0.2)


def test_stack_null_case_adds_nothing():
    case, d = _diagnosed("interface_none", 0)
    assert not d.explained and d.best is None and d.augmented == ()


@pytest.mark.parametrize("effect, seed", [("interface_joint", 0), ("interface_joint", 1),
                                          ("interface_softening", 0), ("interface_none", 0)])
def test_explained_never_goes_with_an_improvement_below_the_threshold(effect, seed):
    case, d = _diagnosed(effect, seed)
    if d.explained:
        assert d.mismatch_before / d.mismatch_after >= MIN_IMPROVEMENT
    else:
        assert d.mismatch_after == d.mismatch_before and "Nothing is added" in d.verdict or \
            "no physics is added" in d.verdict


@pytest.mark.parametrize("effect, seed", [("interface_joint", 0), ("interface_joint", 1), ("interface_softening", 0)])
def test_what_is_named_has_its_key_parameters_identified(effect, seed):
    """Nothing is named whose key parameter has σ > 0.5× its value (of an either-group, one suffices);
    values of an equivalent model say so."""
    from jointdb.diagnose._identify import IDENTIFIED, unidentified

    case, d = _diagnosed(effect, seed)
    assert d.explained, d.verdict
    assert unidentified(d.best) == {}
    params = d.best.candidate.params
    for q in params:
        rel = q.relative_sigma(d.best.values[q.name], d.best.sigmas.get(q.name))
        if q.key and not q.either:
            assert rel <= IDENTIFIED, (q.name, d.best.values[q.name], d.best.sigmas.get(q.name))
    either = [q for q in params if q.key and q.either]
    if either:
        assert min(q.relative_sigma(d.best.values[q.name], d.best.sigmas.get(q.name)) for q in either) <= IDENTIFIED
    for q in params:
        if q.equivalent:
            assert f"equivalent {q.name}" in d.verdict
