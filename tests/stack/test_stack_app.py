"""Stacks with joints from the database: resolution report, pinned versions, campaigns."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from jointdb import usecases
from jointdb.coupling import spring_damper_joint
from jointdb.errors import InputError, NotFoundError
from jointdb.stack import predict_tool_tip, stack_from_dict
from jointdb.store import Conditions, Provenance, Repository

ROOT = Path(__file__).resolve().parents[2]
STACK = ROOT / "fixtures" / "stacks" / "endmill-modelled-spindle.json"
CATALOGUE = ROOT / "jointdb" / "data" / "catalogue"
FREQ = np.linspace(20.0, 4000.0, 120)
JOINT_FREQ = FREQ  # stored on the prediction grid: no resampling, so the comparison is exact


def _joint(k, c):
    return spring_damper_joint(JOINT_FREQ, k, c, ["3x", "3ry"])


@pytest.fixture()
def repo(tmp_path):
    r = Repository(f"sqlite:///{tmp_path / 'j.sqlite'}")
    prov = Provenance(method="synthetic")
    for name, torque, k, c in (
        ("th-40", 40.0, (1.5e7, 2.0e5), (300.0, 2.5)),
        ("th-80", 80.0, (2.5e7, 3.5e5), (250.0, 2.0)),
        ("th-120", 120.0, (3.0e7, 4.5e5), (220.0, 1.8)),
    ):
        r.catalogue(name, "tool-holder", _joint(k, c), Conditions(("tungsten-carbide", "steel"), torque_nm=torque),
                    "spring-damper-planar", prov)
    # a second, corrected version of th-80
    r.catalogue("th-80", "tool-holder", _joint((2.6e7, 3.6e5), (240.0, 1.9)),
                Conditions(("tungsten-carbide", "steel"), torque_nm=80.0), "spring-damper-planar", prov)
    yield r
    r.close()


def _doc(tool_holder) -> dict:
    doc = json.loads(STACK.read_text())
    doc["interfaces"]["tool-holder"] = tool_holder
    return doc


def _explicit(k, c):
    return predict_tool_tip(stack_from_dict(_doc({"k": list(k), "c": list(c)})), freq=FREQ).tip


def test_nearest_joint_is_reported_and_used(repo):
    spec = stack_from_dict(_doc({"query": {"joint_type": "tool-holder", "materials": ["carbide", "steel"],
                                           "torque_nm": 90}}))
    result = usecases.predict_stack(spec, repo, FREQ)
    res = result.joints["tool-holder"]
    expected = repo.nearest("tool-holder", Conditions(("tungsten-carbide", "steel"), torque_nm=90.0), k=3)
    assert (res.kind, res.name, res.version) == ("query", "th-80", 2)  # the current version of the nearest joint
    assert res.distance == pytest.approx(expected[0].distance)
    assert res.distance > 0 and not res.extrapolating
    assert [c[:2] for c in res.candidates] == [(m.version.name, m.version.version) for m in expected]
    assert res.candidates[0][2] <= res.candidates[1][2] <= res.candidates[2][2]
    assert result.joints["holder-spindle"].kind == "explicit"
    # the prediction is exactly the one with that joint's constants
    np.testing.assert_allclose(result.prediction.tip.values, _explicit((2.6e7, 3.6e5), (240.0, 1.9)).values,
                               rtol=1e-10)


def test_extrapolation_is_flagged(repo):
    spec = stack_from_dict(_doc({"query": {"joint_type": "tool-holder", "torque_nm": 200}}))
    res = usecases.resolve_joints(spec, repo)["tool-holder"]
    assert res.name == "th-120" and res.extrapolating and "torque_nm" in res.outside_range
    assert res.warnings  # the store's warning is captured into the report, not printed


def test_pinned_version_is_used_even_when_newer_exists(repo):
    result = usecases.predict_stack(stack_from_dict(_doc("th-80@1")), repo, FREQ)
    res = result.joints["tool-holder"]
    assert (res.kind, res.name, res.version, res.distance) == ("catalogued", "th-80", 1, 0.0)
    np.testing.assert_allclose(result.prediction.tip.values, _explicit((2.5e7, 3.5e5), (250.0, 2.0)).values,
                               rtol=1e-10)
    with pytest.raises(NotFoundError):
        usecases.predict_stack(stack_from_dict(_doc("th-80@7")), repo, FREQ)
    repo.label("th-80", 1, "released")
    res = usecases.resolve_joints(stack_from_dict(_doc("th-80@released")), repo)["tool-holder"]
    assert (res.name, res.version) == ("th-80", 1)


def test_interpolated_joint_is_labelled(repo):
    spec = stack_from_dict(_doc({"query": {"joint_type": "tool-holder", "torque_nm": 100, "neighbours": 2,
                                           "interpolate": True}}))
    res = usecases.resolve_joints(spec, repo)["tool-holder"]
    assert res.kind == "interpolated" and "INTERPOLATED" in res.description
    assert len(res.candidates) == 2


def test_load_stack_names_the_file_and_field(tmp_path):
    doc = _doc("rigid")
    doc["tool"]["segments"][0]["length"] = 0
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(doc))
    with pytest.raises(InputError, match=r"^bad\.json: tool\.segments\[0\]\.length: must be > 0"):
        usecases.load_stack(bad)
    (tmp_path / "broken.json").write_text("{ not json")
    with pytest.raises(InputError, match=r"broken\.json: not valid JSON \(line 1"):
        usecases.load_stack(tmp_path / "broken.json")
    with pytest.raises(NotFoundError):
        usecases.load_stack(tmp_path / "missing.json")


def test_measured_spindle_file_is_loaded_relative_to_the_stack(tmp_path):
    from jointdb.io import write_frf_hdf5
    from jointdb.stack import spindle_model

    spec = stack_from_dict(_doc("rigid"))
    write_frf_hdf5(tmp_path / "spindle.h5", spindle_model(spec).frf(FREQ, ["nose"]))
    doc = _doc("rigid")
    doc["spindle"] = {"file": "spindle.h5", "node": 5}
    (tmp_path / "s.json").write_text(json.dumps(doc))
    loaded = usecases.load_stack(tmp_path / "s.json")
    a = predict_tool_tip(loaded, freq=FREQ)
    b = predict_tool_tip(spec, freq=FREQ)
    np.testing.assert_allclose(a.tip.values, b.tip.values, rtol=1e-12)


def test_campaign_identification_recovers_the_true_joint_and_catalogues_once(tmp_path):
    path = CATALOGUE / "campaigns" / "th-er32-carbide-080nm" / "campaign.json"
    truth = json.loads((path.parent / "truth.json").read_text())
    with Repository(f"sqlite:///{tmp_path / 'c.sqlite'}") as repo:
        first = usecases.catalogue_campaign(repo, path)
        row = first.row()
        # 0.2 % noise, finer-mesh "measurement", coarser models: named tolerances
        assert row["k_x_n_per_m"] == pytest.approx(truth["k"][0], rel=0.01)
        assert row["k_theta_nm_per_rad"] == pytest.approx(truth["k"][1], rel=0.03)
        assert row["c_x_ns_per_m"] == pytest.approx(truth["c"][0], rel=0.05)
        assert first.version.version == 1 and not first.reused
        assert first.version.model_kind == "spring-damper-planar"
        files = first.version.provenance.input_files
        assert {"campaign.json", "assembly.uff", "../../models/test-tool-carbide.json"} <= set(files)
        again = usecases.catalogue_campaign(repo, path)
        assert again.reused and again.version.version == 1


def test_spindle_model_file_is_loaded_relative_to_the_stack():
    path = ROOT / "fixtures" / "stacks" / "endmill-catalogued-joint.json"
    spec = usecases.load_stack(path)
    assert isinstance(spec.spindle.model, dict) and spec.spindle.model["segments"]
    with pytest.raises(InputError, match="interfaces.tool-holder: nearest tool-holder .* must be resolved"):
        predict_tool_tip(spec, freq=FREQ)
    pred = predict_tool_tip(spec, {"tool-holder": _joint((2.5e7, 3.5e5), (250.0, 2.0))}, freq=FREQ)
    assert pred.interfaces["tool-holder"] == "resolved joint FRF"
