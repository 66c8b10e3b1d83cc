"""Two bending planes: an asymmetric spindle gives different x and y tips; a spindle whose planes are coupled
(anisotropic bearings on rotated axes) gives the cross terms, and they transform as the rotation says."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from jointdb.frf import FRF, Dof
from jointdb.stack import JointChoice, MeasuredSpindle, predict_tool_tip, spindle_model, stack_from_dict

ROOT = Path(__file__).resolve().parents[2]
DEMO = json.loads((ROOT / "jointdb" / "data" / "catalogue" / "demo-stack.json").read_text())
JOINTS = {"tool-holder": JointChoice("explicit", k=(3e7, 4.5e5), c=(230.0, 1.7)),
          "holder-spindle": JointChoice("explicit", k=(1.5e8, 2e6), c=(1500.0, 15.0))}
FREQ = np.arange(100.0, 5000.0, 10.0)


def _spec():
    return stack_from_dict(DEMO).replace(interfaces=JOINTS)


def _spindle_frf(spec):
    model = spindle_model(spec)
    return model.frf(FREQ, ["nose"], directions=("x", "y", "rx", "ry"))


def test_asymmetric_spindle_gives_two_different_planes_without_cross_terms():
    pred = predict_tool_tip(_spec(), freq=FREQ)
    hx, hy = pred.tip.entry("1x", "1x"), pred.tip.entry("1y", "1y")
    fx, fy = FREQ[np.argmax(np.abs(hx))], FREQ[np.argmax(np.abs(hy))]
    assert fy < fx  # the y bearings are 25 % softer
    assert not np.any(pred.tip.values[:, 0, 1]) and not any("equal to the x plane" in n for n in pred.notes)


def test_x_only_spindle_keeps_working_with_y_equal_to_x_and_says_so():
    spec = _spec()
    frf = _spindle_frf(spec)
    keep = [d for d in frf.outputs if d.direction in ("x", "ry")]
    xonly = FRF(FREQ, frf.block(keep, keep), keep, keep, "receptance")
    pred = predict_tool_tip(spec.replace(spindle=MeasuredSpindle("s.uff", 5, xonly)), freq=FREQ)
    np.testing.assert_array_equal(pred.tip.entry("1x", "1x"), pred.tip.entry("1y", "1y"))
    assert any("y plane taken equal to the x plane" in n for n in pred.notes)


@pytest.mark.parametrize("angle_deg", [30.0, 60.0])
def test_rotated_anisotropic_spindle_gives_cross_terms_that_rotate_with_it(angle_deg):
    spec = _spec()
    frf = _spindle_frf(spec)  # principal axes u = x, v = y
    ref = predict_tool_tip(spec.replace(spindle=MeasuredSpindle("s.uff", 5, frf)), freq=FREQ)
    # the same spindle turned by φ about z: H' = R H Rᵀ over (x, y, rx, ry) (translations and rotations turn alike)
    c, s = np.cos(np.radians(angle_deg)), np.sin(np.radians(angle_deg))
    order = [Dof(5, d) for d in ("x", "y", "rx", "ry")]
    r2 = np.array([[c, -s], [s, c]])
    R = np.zeros((4, 4))
    R[:2, :2] = R[2:, 2:] = r2
    turned = FRF(FREQ, R @ frf.block(order, order) @ R.T, order, order, "receptance")
    pred = predict_tool_tip(spec.replace(spindle=MeasuredSpindle("s.uff", 5, turned)), freq=FREQ)
    assert any("coupled" in n for n in pred.notes)
    want = r2 @ ref.tip.values @ r2.T  # the tool and holder are axisymmetric: the tip turns with the spindle
    scale = np.abs(ref.tip.values).max()
    np.testing.assert_allclose(pred.tip.values, want, atol=1e-9 * scale)
    assert np.abs(pred.tip.values[:, 0, 1]).max() > 0.05 * scale  # real cross terms
    np.testing.assert_allclose(pred.tip.values[:, 0, 1], pred.tip.values[:, 1, 0], atol=1e-9 * scale)


def test_fluted_area_ratio_gives_the_fluted_section_its_true_mass_and_round_trips():
    from jointdb.stack import stack_to_dict, tool_model

    doc = json.loads(json.dumps(DEMO))
    plain = stack_from_dict(doc)
    doc["tool"]["fluted_area_ratio"] = 0.6
    heavy = stack_from_dict(doc)
    assert stack_from_dict(stack_to_dict(heavy)).tool.fluted_area_ratio == 0.6
    assert "fluted_area_ratio" not in stack_to_dict(plain)["tool"]
    m0, m1 = tool_model(plain).assemble(), tool_model(heavy).assemble()
    np.testing.assert_array_equal(m0.K, m1.K)  # the Kops–Vo bending stiffness is kept
    # mass of the 30 mm fluted section: 0.6 of the full Ø12 circle instead of 0.656² of it
    ux = [i for i, d in enumerate(m0.dof_labels) if d.direction == "x"]
    extra = float(np.sum(m1.M[np.ix_(ux, ux)]) - np.sum(m0.M[np.ix_(ux, ux)]))
    area = np.pi * 0.012**2 / 4
    from jointdb.fe import get_material

    want = get_material("carbide").rho * area * (0.6 - 0.656**2) * 0.030
    assert extra == pytest.approx(want, rel=1e-9)
    doc["tool"]["fluted_area_ratio"] = 1.5
    with pytest.raises(Exception, match="fluted_area_ratio"):
        stack_from_dict(doc)


def test_band_samples_carry_the_cross_terms_and_equal_one_by_one_predictions():
    """Joint-choice samples through a plane-coupling spindle: each sample's 2×2 tip (cross terms included)
    equals predict_tool_tip with that sample's joint; with no spread the band collapses onto the prediction."""
    from jointdb.stack._band import choice_perturbed, tip_band

    spec = _spec()
    frf = _spindle_frf(spec)
    c, s = np.cos(np.radians(30.0)), np.sin(np.radians(30.0))
    order = [Dof(5, d) for d in ("x", "y", "rx", "ry")]
    R = np.zeros((4, 4))
    R[:2, :2] = R[2:, 2:] = [[c, -s], [s, c]]
    spec = spec.replace(spindle=MeasuredSpindle("s.uff", 5, FRF(FREQ, R @ frf.block(order, order) @ R.T, order,
                                                                 order, "receptance")))
    nominal = predict_tool_tip(spec, freq=FREQ)
    jdofs = (Dof(3, "x"), Dof(3, "ry"))
    w = 2 * np.pi * FREQ
    hj = np.zeros((FREQ.size, 2, 2), complex)
    hj[:, 0, 0], hj[:, 1, 1] = 1 / (3e7 + 1j * w * 230.0), 1 / (4.5e5 + 1j * w * 1.7)
    joint = FRF(FREQ, hj, jdofs, jdofs, "receptance")
    rel = np.zeros((1, FREQ.size, 2, 2), complex)
    rel[0, :, 0, 0], rel[0, :, 1, 1] = 0.3, -0.2 + 0.1j  # a stiffness and a damping error pattern
    b0 = tip_band(spec, {"tool-holder": joint}, None, FREQ, n=4, seed=5, choice={"tool-holder": (rel, np.zeros(1))})
    np.testing.assert_allclose(b0.cross[0], nominal.tip.values, rtol=1e-9, atol=1e-12)
    b = tip_band(spec, {"tool-holder": joint}, None, FREQ, n=3, seed=5, choice={"tool-holder": (rel, np.ones(1))})
    assert b.cross is not None and np.abs(b.cross[:, :, 0, 1]).max() > 0
    rng = np.random.default_rng([5, 104729])  # the draws tip_band makes, in its order
    samples = choice_perturbed(np.broadcast_to(hj, (3,) + hj.shape), rel, np.ones(1), rng)
    for k in range(3):
        one = predict_tool_tip(spec, {"tool-holder": FRF(FREQ, samples[k], jdofs, jdofs, "receptance")}, FREQ)
        np.testing.assert_allclose(b.cross[k], one.tip.values, rtol=1e-8, atol=1e-12)
