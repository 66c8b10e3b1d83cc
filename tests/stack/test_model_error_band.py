"""The band's substructure-model term (issue 22 item 1): the error a campaign's validation assembly shows.

Known answers: a validation assembly equal to its prediction has no error; one 5 % off at every dominant peak
has 5 %; a joint carrying 5 % puts a 5–95 % half-width of sinh(1.645 ln 1.05) = 8.0 % on the tip peak. End to end:
the fixture campaign with a validation assembly is catalogued and its error reaches the band of a stack using it.
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from jointdb.campaign._oe import entry_peaks
from jointdb.campaign._run import peak_model_error
from jointdb.stack import JointChoice, stack_from_dict
from jointdb.usecases import predict_with_joints, resolve_joints
from jointdb.usecases._stack_band import band_terms, model_error

ROOT = Path(__file__).resolve().parents[2]
CAMPAIGN = ROOT / "fixtures" / "campaigns" / "th-steel-30nm" / "campaign.json"
STACK = ROOT / "fixtures" / "stacks" / "endmill-modelled-spindle.json"


@pytest.fixture(scope="module")
def catalogued(tmp_path_factory):
    from jointdb.store import Repository
    from jointdb.usecases._catalogue import catalogue_campaign

    repo = Repository(tmp_path_factory.mktemp("val") / "j.sqlite")
    out = catalogue_campaign(repo, CAMPAIGN, author="test")
    yield repo, out
    repo.close()


def test_validation_equal_to_its_prediction_has_no_error_and_5_percent_has_5(catalogued):
    pred = catalogued[1].identified.validation["predicted"]
    assert peak_model_error(entry_peaks(pred, pred)) == 0.0
    for factor in (1.05, 1 / 1.05):  # measured 5 % above or below the prediction at every line
        meas = pred.replace(values=pred.values * factor)
        assert peak_model_error(entry_peaks(pred, meas)) == pytest.approx(0.05, rel=1e-9)
    # mixed: one peak 5 % high, one 5 % low -> still 5 %; a 2 % and a 10 % peak -> their RMS in log units
    peaks = [{"amplitude_ratio": 1.05}, {"amplitude_ratio": 1 / 1.05}]
    assert peak_model_error(peaks) == pytest.approx(0.05, rel=1e-12)
    rms = np.sqrt((np.log(1.02) ** 2 + np.log(1.10) ** 2) / 2)
    assert peak_model_error([{"amplitude_ratio": 1.02}, {"amplitude_ratio": 1.10}]) == pytest.approx(np.expm1(rms))
    assert np.isnan(peak_model_error([]))


def test_the_catalogue_records_the_validation_peak_error(catalogued):
    _, out = catalogued
    e = out.version.quality["validation_peak_error"]
    assert e == pytest.approx(peak_model_error(out.identified.validation["peaks"]), rel=1e-12)
    assert 0 < e < 0.5  # a finer model measured with 1 % noise: not exact, not wild


def _stack_result(joints_patch=None, repo=None, interfaces=None):
    spec = stack_from_dict(json.loads(STACK.read_text()))
    if interfaces:
        spec = spec.replace(interfaces={**spec.interfaces, **interfaces})
    joints = resolve_joints(spec, repo)
    for name, val in (joints_patch or {}).items():
        joints[name] = replace(joints[name], validation_errors=val)
    return predict_with_joints(spec, joints, np.arange(20.0, 5000.1, 10.0))  # the campaign's joint: 20-5000 Hz


def test_a_known_5_percent_model_error_gives_its_band_and_absent_is_zero_stated():
    plain = band_terms(_stack_result(), n=100)
    assert "validation assembly" in plain.zero["substructure model"] and plain.half_width["substructure model"] == {}
    exact = band_terms(_stack_result({"tool-holder": (("th@1", 1.0, 0.0),)}), n=100)
    assert "show no error" in exact.zero["substructure model"]  # a validation assembly met exactly: 0, said so
    five = _stack_result({"tool-holder": (("th@1", 1.0, 0.05),)})
    assert model_error(five.joints)[0] == pytest.approx(np.log(1.05))
    terms = band_terms(five, n=400)
    expected = np.sinh(1.645 * np.log(1.05))  # 8.0 %: the 5-95 % of exp(σ ξ) around its median
    # 400 samples: each 5 %/95 % quantile of a normal has a standard error of 0.11 σ -> half-width within ±10 %
    for d in ("x", "y"):
        assert terms.half_width["substructure model"][d] == pytest.approx(expected, rel=0.1)
    assert "substructure model" not in terms.zero
    assert any("validation assemblies of th@1 (peak error 5.0%)" in n for n in terms.notes)
    row = {t["term"]: t for t in terms.to_json()["terms"]}["substructure model"]
    assert row["zero_because"] is None and row["peak_half_width"]["x"] > 0.05


def test_interpolated_and_two_interfaces_combine_as_documented():
    # weights of the versions that have a validation assembly only; interfaces add in quadrature (log units)
    r = _stack_result({"tool-holder": (("a@1", 0.25, 0.10), ("b@1", 0.75, None)),
                       "holder-spindle": (("c@1", 0.5, 0.02), ("d@1", 0.5, 0.04))})
    s, parts = model_error(r.joints)
    hs = (np.log(1.02) ** 2 + np.log(1.04) ** 2) / 2
    assert s == pytest.approx(np.sqrt(np.log(1.10) ** 2 + hs))
    assert len(parts) == 2 and "a@1" in parts[0] and "b@1" not in parts[0]


def test_a_catalogued_joint_with_a_validation_assembly_carries_it_to_the_band(catalogued):
    repo, out = catalogued
    r = _stack_result(repo=repo, interfaces={"tool-holder": JointChoice("catalogued", name=out.version.name,
                                                                        version=out.version.version)})
    th = r.joints["tool-holder"]
    e = out.version.quality["validation_peak_error"]
    assert th.validation_errors == ((f"{out.version.name}@{out.version.version}", 1.0, e),)
    assert th.row()["validation_peak_error"][0]["error"] == e
    terms = band_terms(r, n=200)
    assert terms.half_width["substructure model"]["x"] > 0 and "substructure model" not in terms.zero
