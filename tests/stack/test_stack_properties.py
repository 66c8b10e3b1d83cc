"""Physical properties of predicted tool-tip FRFs (hypothesis): passivity, rigid limit."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from jointdb.stack import predict_tool_tip, stack_from_dict

STACK = Path(__file__).resolve().parents[2] / "fixtures" / "stacks" / "endmill-modelled-spindle.json"
FREQ = np.linspace(50.0, 6000.0, 80)


def _spec(gauge, kt, kr, ct, cr, eta, holder_spindle=None):
    doc = json.loads(STACK.read_text())
    if holder_spindle is not None:
        doc["interfaces"]["holder-spindle"] = holder_spindle
    doc["gauge_length"] = gauge
    doc["tool"]["loss_factor"] = doc["holder"]["loss_factor"] = eta
    doc["interfaces"]["tool-holder"] = {"k": [kt, kr], "c": [ct, cr]}
    return stack_from_dict(doc)


@settings(max_examples=15, deadline=None)
@given(
    gauge=st.floats(0.041, 0.08),  # the 40 mm bore holds at most 39 mm of the 80 mm tool
    kt=st.floats(1e6, 1e9), kr=st.floats(1e4, 1e7),
    ct=st.floats(0.0, 2000.0), cr=st.floats(0.0, 20.0),
    eta=st.floats(0.0, 0.02),
)
def test_tip_receptance_of_a_passive_stack_is_passive(gauge, kt, kr, ct, cr, eta):
    pred = predict_tool_tip(_spec(gauge, kt, kr, ct, cr, eta), freq=FREQ)
    h = pred.tip.entry("1x", "1x")
    assert np.all(h.imag <= 1e-9 * np.abs(h)), "a passive driving-point receptance has Im H <= 0 (docs/theory.md §0)"


def test_very_stiff_joints_approach_the_rigid_prediction():
    errors = []
    for k in (1e10, 1e12, 1e14):
        stiff = {"k": [k, k / 50.0], "c": [0.0, 0.0]}
        pred = predict_tool_tip(_spec(0.05, k, k / 50.0, 0.0, 0.0, 0.004, stiff), freq=FREQ)
        errors.append(np.max(np.abs(pred.tip.values - pred.rigid.values)) / np.max(np.abs(pred.rigid.values)))
    # the joint compliance 1/k enters linearly: 100 x stiffer, 100 x closer
    assert 50 < errors[0] / errors[1] < 200 and 50 < errors[1] / errors[2] < 200 and errors[2] < 1e-4
