"""`optimize` from the parts catalogue: the spindle by machine, holders by family and label, a power curve
over speed — the fast path still equals brute force (predict + lobes per candidate) to the last digit."""

import copy
import json
from pathlib import Path

import numpy as np
import pytest

from optimize_helpers import fast_equals_brute_force

from jointdb.errors import InputError, NotFoundError
from jointdb.usecases._optimize import (
    available_power,
    best_cut,
    enumerate_candidates,
    problem_from_document,
)
from jointdb.usecases._optimize_eval import evaluate_candidates

ROOT = Path(__file__).resolve().parents[2]
SPEC = json.loads((ROOT / "fixtures" / "optimize" / "optimize-catalogue.json").read_text())
ER32 = {"loss_factor": 0.004, "material": "steel",
        "segments": [{"inner_diameter": 0.012, "length": 0.05, "outer_diameter": 0.034},
                     {"inner_diameter": 0.0, "length": 0.03, "outer_diameter": 0.05}]}


@pytest.fixture(scope="module")
def parts(catalogue):
    """The bundled catalogue plus two more ER32 chucks (one labelled 'released', one with a 16 mm bore)
    and a shrink-fit chuck of another family."""
    repo, _ = catalogue
    attrs = {"family": "ER32", "taper": "HSK-A63", "bore_mm": 12.0}
    long = repo.add_part("er32-long-hsk63", "holder", ER32, attributes=attrs, author="test")
    repo.label_part(long.name, long.version, "released", author="test")
    repo.add_part("er32-16mm-hsk63", "holder", ER32, attributes={**attrs, "bore_mm": 16.0}, author="test")
    repo.add_part("shrink-12mm-hsk63", "holder", ER32, attributes={**attrs, "family": "shrink-fit"}, author="test")
    return repo


def _spec(**changes):
    doc = copy.deepcopy(SPEC)
    for key, value in changes.items():
        doc[key] = value
    return doc


def test_holders_by_family_and_label_and_the_spindle_by_machine(parts):
    problem = problem_from_document(_spec(), parts, allow_files=False)
    assert [h.name for h in problem.holders] == ["er32-collet-chuck-hsk63@1", "er32-long-hsk63@1"]
    assert any("left out er32-16mm-hsk63@1: bore 16 mm" in n for n in problem.notes)
    assert {p["slot"]: p["part"] for p in problem.template.parts}["spindle"] == "demo-mill-spindle@1"
    labelled = problem_from_document(_spec(holders=[{"family": "ER32", "label": "released"}]), parts)
    assert [h.name for h in labelled.holders] == ["er32-long-hsk63@1"]
    pinned = json.loads(problem.pinned)  # what Dask workers load: every choice as name@version
    assert pinned["holders"] == [{"part": "er32-collet-chuck-hsk63@1"}, {"part": "er32-long-hsk63@1"}]
    assert pinned["machine"]["spindle"] == "demo-mill-spindle@1" and "name" not in pinned["machine"]
    assert problem_from_document(pinned, parts).holders == problem.holders
    cands = enumerate_candidates(problem, parts)
    assert len(cands) == 2 * 36 and {c.holder for c in cands} == {h.name for h in problem.holders}


def test_a_holder_that_does_not_fit_or_a_family_without_holders_is_refused(parts):
    with pytest.raises(InputError, match=r"holders\[0\]\.part: er32-16mm-hsk63@1: bore 16 mm"):
        problem_from_document(_spec(holders=[{"part": "er32-16mm-hsk63@1"}]), parts)
    with pytest.raises(NotFoundError, match="family 'HSK-T'"):
        problem_from_document(_spec(holders=[{"family": "HSK-T"}]), parts)
    with pytest.raises(NotFoundError, match="machine 'no-such-mill'"):
        problem_from_document(_spec(machine={**SPEC["machine"], "name": "no-such-mill"}), parts)


def test_fast_ranking_equals_brute_force_with_catalogue_holders_and_a_power_curve(parts):
    problem = problem_from_document(_spec(), parts, allow_files=False)
    cands = enumerate_candidates(problem, parts)[::6]  # 12 candidates, both holders
    assert {c.holder for c in cands} == {h.name for h in problem.holders}
    fast = fast_equals_brute_force(problem, cands, parts)
    # the two holders give different tips (the long chuck is another substructure)
    by_holder = {r.candidate.holder: r for r in fast}
    assert len(by_holder) == 2 and not np.allclose(*[r.tip.values for r in by_holder.values()])


def test_the_power_curve_sets_the_depth_where_it_binds(parts):
    problem = problem_from_document(_spec(), parts)
    (res,) = evaluate_candidates(problem, enumerate_candidates(problem, parts)[:1], parts)
    n = res.lobes.spindle_speed_rpm
    # by hand: the curve's points are (4000, 7.5 kW), (8000, 15 kW), (18000, 15 kW), (24000, 11 kW)
    at = {6000.0: 11250.0, 8000.0: 15000.0, 12000.0: 15000.0, 21000.0: 13000.0, 24000.0: 11000.0}
    got = available_power(problem.spec.machine, list(at))
    assert np.allclose(got, list(at.values()), rtol=1e-9)
    # a stability limit far above everything: power or torque binds; at the top speed the curve (11 kW) does
    free = best_cut(problem, res.lobes, stability_m=np.full(n.size, 1.0))
    assert free["binding"] in ("power", "torque")
    one = res.lobes.__class__(**{**res.lobes.__dict__, "spindle_speed_rpm": n[-1:], "depth_m": np.array([1.0]),
                                 "chatter_freq_hz": res.lobes.chatter_freq_hz[-1:], "lobe": res.lobes.lobe[-1:],
                                 "kind": res.lobes.kind[-1:]})
    top = best_cut(problem, one)
    assert top["binding"] == "power" and np.isclose(top["power_w"], 11000.0, rtol=1e-9)


@pytest.mark.parametrize("change, needle", [
    ({"stack": "../bundled/catalogue/demo-stack.json"}, "stack: send the stack document inline"),
    ({"machine": {**SPEC["machine"], "power_curve": [{"speed_rpm": 7000, "power_w": 1}, {"speed_rpm": 24000, "power_w": 2}]}},
     "machine: power_curve: must cover the speed range"),
    ({"tool": {**SPEC["tool"], "overhang_step_m": 1e-9}}, "tool: overhang grid: more than 1000"),
    ({"holders": [{"family": "ER32", "part": "x@1"}]}, "holders[0]: give one of name"),
    ({"holders": [{"name": "h"}] * 101}, "holders: allows at most 100 item(s)"),
    ({"machine": {**SPEC["machine"], "spindle": "../../etc/passwd"}}, "machine.spindle: is not in the expected form"),
])
def test_a_hostile_or_wrong_spec_is_refused_naming_the_field(parts, change, needle):
    with pytest.raises(InputError) as exc:
        problem_from_document(_spec(**change), parts, allow_files=False, where="body")
    assert str(exc.value).startswith("body: ") and needle in str(exc.value), str(exc.value)


def test_the_service_form_refuses_a_spindle_model_file(parts):
    stack = {**SPEC["stack"], "spindle": {"model": "/etc/spindle.json", "point": "nose"}}
    machine = {k: v for k, v in SPEC["machine"].items() if k != "name"}
    with pytest.raises(InputError, match="stack.spindle: refers to a file"):
        problem_from_document(_spec(stack=stack, machine=machine), parts, allow_files=False)


def test_margin_from_the_band_lowers_the_confirmed_best_to_the_bands_lower_edge(parts):
    from jointdb.stack import prediction_grid
    from jointdb.usecases import optimize_stack
    from jointdb.usecases._demo_band import journey_bands
    from jointdb.usecases._optimize import candidate_stack
    from jointdb.usecases._stack import predict_stack

    objective = {"kind": "removal-rate", "margin": 0.0}
    holders = [{"part": "er32-collet-chuck-hsk63@1"}]
    nominal = optimize_stack(problem_from_document(_spec(objective=objective, holders=holders), parts), parts,
                             simulate=False, scheduler="in-process")
    problem = problem_from_document(_spec(objective={**objective, "margin_from": "band"}, holders=holders), parts)
    banded = optimize_stack(problem, parts, simulate=False, scheduler="in-process")
    top = banded.ranked[:5]
    assert all(r.best["band_limit_m"] is not None and "sd_limit_m" in r.best for r in top)
    for r in top:  # the depth is the smallest of the nominal ZOA, the band's 5 % edge and SD (no margin fraction)
        b = r.best
        assert b["depth_m"] <= min(b["zoa_limit_m"], b["band_limit_m"], b["sd_limit_m"]) * (1 + 1e-12)
    floor = top[-1].best["removal_rate_m3_s"]
    assert all(r.best["removal_rate_m3_s"] <= floor for r in banded.ranked[5:])
    assert banded.ranked[0].best["removal_rate_m3_s"] < nominal.ranked[0].best["removal_rate_m3_s"]
    # the band's edge of the best, sampled again from predict_stack's own joint resolutions
    best = banded.ranked[0]
    pred = predict_stack(candidate_stack(problem, best.candidate), parts)
    _, make, _ = journey_bands(pred.spec, pred.joints, prediction_grid(pred.spec), lambda _: None)
    lobe_band = make(problem.cut, best.lobes.spindle_speed_rpm)
    i = int(np.argmin(np.abs(best.lobes.spindle_speed_rpm - best.best["spindle_speed_rpm"])))
    assert best.best["band_limit_m"] == float(lobe_band.depth_m[0, i])
    assert lobe_band.depth_m[0, i] < lobe_band.depth_m[1, i] < lobe_band.depth_m[2, i]


def test_an_interface_pinned_to_a_catalogued_joint_by_label(parts):
    parts.label("hs-hsk-a63-18kn", 1, "machine-b", author="test")
    stack = copy.deepcopy(SPEC["stack"])
    stack["interfaces"]["holder-spindle"] = "hs-hsk-a63-18kn@machine-b"
    holders = [{"part": "er32-collet-chuck-hsk63@1"}]
    problem = problem_from_document(_spec(stack=stack, holders=holders), parts, allow_files=False)
    assert json.loads(problem.pinned)["stack"]["interfaces"]["holder-spindle"] == {"joint": "hs-hsk-a63-18kn@1"}
    cands = enumerate_candidates(problem, parts)
    assert len(cands) == 4 * 3 and {c.drawbar_n for c in cands} == {18000.0}  # its one measured condition
    fast = fast_equals_brute_force(problem, cands[::2], parts)
    assert {r.joints["holder-spindle"] for r in fast} == {"hs-hsk-a63-18kn@1"}
    with pytest.raises(InputError, match="pinned joint hs-hsk-a63-18kn@1 was measured at preload_n 18000"):
        enumerate_candidates(problem_from_document(_spec(stack=stack, holders=holders, drawbar_n=[20000, 30000]),
                                                   parts), parts)
