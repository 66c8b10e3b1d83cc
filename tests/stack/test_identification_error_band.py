"""The band's substructure-model term from a campaign's own identification assembly (issue 22 item 1).

A tool–holder campaign's identification assembly is a stack of the kind predicted (tool in holder on spindle,
at the tool tip); when the catalogued joint does not give it back at its dominant peaks (constant k, c kept
although it misfits, or a per-line joint with masked lines at the peak), that in-sample error is an error of the
predicted quantity. Known answers: the error of given peak ratios; the catalogue records it for a campaign;
the band's term uses it on the tool–holder interface only, and a validation assembly wins over it.
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from jointdb.campaign._run import peak_model_error
from jointdb.stack import stack_from_dict
from jointdb.usecases import predict_with_joints, resolve_joints
from jointdb.usecases._catalogue import identification_peak_error
import jointdb.usecases._stack_band as stack_band
from jointdb.usecases._stack_band import IDENTIFICATION_CALIBRATION as KAPPA
from jointdb.usecases._stack_band import band_terms, model_error

ROOT = Path(__file__).resolve().parents[2]
CAMPAIGN = ROOT / "fixtures" / "campaigns" / "th-steel-30nm" / "campaign.json"
STACK = ROOT / "fixtures" / "stacks" / "endmill-modelled-spindle.json"


def test_identification_peak_error_of_known_ratios_and_of_rows_that_are_not_ratios():
    assert identification_peak_error({"peaks": [{"amplitude_ratio": 1.05}, {"amplitude_ratio": 1 / 1.05}]}) \
        == pytest.approx(0.05, rel=1e-12)
    assert identification_peak_error({"peaks": [{"amplitude_ratio": 1.0}]}) == 0.0
    for bad in (None, [], {"peaks": []}, {"peaks": "x"}, {"peaks": [{"amplitude_ratio": "1"}]},
                {"peaks": [{"amplitude_ratio": float("nan")}]}, {"peaks": [{"amplitude_ratio": -1.0}]},
                {"peaks": [{"amplitude_ratio": True}]}, {"peaks": [1.0]}):
        assert identification_peak_error(bad) is None


def test_the_catalogue_records_the_identification_peak_error_of_a_campaign(tmp_path):
    from jointdb.store import Repository
    from jointdb.usecases._catalogue import catalogue_campaign

    with Repository(tmp_path / "j.sqlite") as repo:
        out = catalogue_campaign(repo, CAMPAIGN, author="test")
        e = out.version.quality["identification_peak_error"]
        assert e == pytest.approx(peak_model_error(out.identified.quality["peaks"]), rel=1e-12)
        assert 0 <= e < 0.25  # the re-coupled identification assembly at 1 % noise: within the verdict's 25 %


def _joints(tool_holder=(), holder_spindle=()):
    spec = stack_from_dict(json.loads(STACK.read_text()))
    joints = resolve_joints(spec, None)
    for name, rows in (("tool-holder", tool_holder), ("holder-spindle", holder_spindle)):
        if rows:
            joints[name] = replace(joints[name], validation_errors=tuple((j, w, v) for j, w, v, _ in rows),
                                   identification_errors=tuple((j, w, i) for j, w, _, i in rows))
    return spec, joints


def test_the_term_uses_the_tool_holder_identification_error_and_a_validation_wins():
    _, j = _joints(tool_holder=(("th@1", 1.0, None, 0.05),))
    s, parts = model_error(j)
    assert s == pytest.approx(KAPPA * np.log(1.05)) and "identification assemblies of th@1" in parts[0]
    # a holder–spindle joint's identification error does not count (the tool–holder campaigns absorb it)
    _, j = _joints(holder_spindle=(("hs@1", 1.0, None, 0.10),))
    assert model_error(j) == (0.0, [])
    # a validation assembly of the same version replaces its in-sample error; interpolation weights as documented
    _, j = _joints(tool_holder=(("a@1", 0.25, 0.02, 0.10), ("b@1", 0.75, None, 0.04)))
    s, parts = model_error(j)
    assert s == pytest.approx(np.sqrt(0.25 * np.log(1.02) ** 2 + 0.75 * (KAPPA * np.log(1.04)) ** 2))
    assert "validation assemblies and identification assemblies" in parts[0]


def test_the_calibration_factor_scales_identification_errors_only(monkeypatch):
    monkeypatch.setattr(stack_band, "IDENTIFICATION_CALIBRATION", 0.5)
    _, j = _joints(tool_holder=(("th@1", 1.0, None, 0.10),))
    s, parts = model_error(j)
    assert s == pytest.approx(0.5 * np.log(1.10), rel=1e-12) and "taken as 4.9%, identification errors × 0.5" in parts[0]
    _, j = _joints(tool_holder=(("th@1", 1.0, 0.10, 0.30),))  # a validation assembly: its error as it is
    s, parts = model_error(j)
    assert s == pytest.approx(np.log(1.10), rel=1e-12) and "×" not in parts[0]
    _, j = _joints(tool_holder=(("a@1", 0.5, 0.10, None), ("b@1", 0.5, None, 0.10)))
    assert model_error(j)[0] == pytest.approx(np.sqrt(0.5 * np.log(1.10) ** 2 + 0.5 * (0.5 * np.log(1.10)) ** 2))


def test_a_known_identification_error_reaches_the_tip_band():
    spec, j = _joints(tool_holder=(("th@1", 1.0, None, 0.05),))
    terms = band_terms(predict_with_joints(spec, j, np.arange(20.0, 5000.1, 10.0)), n=400)
    expected = np.sinh(1.645 * KAPPA * np.log(1.05))  # 8.0 %: the 5-95 % of exp(σ ξ) around its median
    # 400 samples: each 5 %/95 % quantile of a normal has a standard error of 0.11 σ -> half-width within ±10 %
    for d in ("x", "y"):
        assert terms.half_width["substructure model"][d] == pytest.approx(expected, rel=0.1)


def test_a_peak_error_that_is_not_a_number_in_range_is_left_out_and_said_so():
    # quality values can come from an uploaded file: -1 would make σ infinite, -2 NaN, 1e300 absurd
    for bad in (-1.0, -2.0, 1e300, float("nan"), 10.5):
        _, j = _joints(tool_holder=(("th@1", 1.0, None, bad),))
        s, parts = model_error(j)
        assert s == 0.0 and any("th@1 left out" in p for p in parts)
        _, j = _joints(tool_holder=(("a@1", 0.5, bad, None), ("b@1", 0.5, None, 0.05)))
        s, parts = model_error(j)
        assert s == pytest.approx(KAPPA * np.log(1.05)) and np.isfinite(s)  # the usable version alone (weights renormalised)
    # ratios so far from 1 that the error overflows give no error, not inf
    assert identification_peak_error({"peaks": [{"amplitude_ratio": 5e-324}]}) is None
