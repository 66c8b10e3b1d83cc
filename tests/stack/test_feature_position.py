"""The band's feature-position term (issue 22, round 3 session 12): how much the tip's dominant peak depends on where
a chosen joint's features sit.

Known answers: linear interpolation is exact on a receptance linear in frequency; a joint with a resonance read at
``f (1 + ε)`` has it at ``f₀ / (1 + ε)``; a joint whose stiffness dips around ``f_c`` read at ``f (1 + ε)`` is the
same analytic joint with its dip at ``f_c / (1 + ε)`` (built here in closed form, no interpolation), so the sensitivity
the product computes must match the one computed from those closed-form joints; a joint constant in frequency has
sensitivity 0; the term combines with the substructure model's σ in quadrature.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from jointdb.coupling import spring_damper_joint
from jointdb.errors import InputError
from jointdb.stack import predict_tool_tip, stack_from_dict
from jointdb.stack._band import tip_band
from jointdb.stack._feature import frequency_shifted, peak_shift_sensitivity, read_shifted

ROOT = Path(__file__).resolve().parents[2]
STACK = ROOT / "fixtures" / "stacks" / "endmill-modelled-spindle.json"
K, C = np.array([3e7, 6e5]), np.array([300.0, 3.0])  # the fixture stack's tool–holder joint (x, θ)
F = np.arange(20.0, 6000.1, 1.0)


def test_a_receptance_linear_in_frequency_is_read_exactly_at_the_shifted_lines():
    f = np.linspace(100.0, 5000.0, 99)
    a = np.array([[1.0 + 2.0j, 0.5], [0.5, 3.0 - 1.0j]])
    b = np.array([[1e-3j, 2e-4], [2e-4, -3e-4]])
    planes = (a[None] + f[:, None, None] * b[None])[None].repeat(3, axis=0)
    eps = np.array([-0.05, 0.0, 0.03])
    out = frequency_shifted(planes, f, eps)
    for i, e in enumerate(eps):
        g = np.clip(f * (1 + e), f[0], f[-1])  # beyond the grid: its end value
        want = a[None] + g[:, None, None] * b[None]
        assert np.allclose(out[i], want, rtol=1e-12, atol=1e-12)
    assert np.array_equal(out[1], planes[1])  # no shift: the lines themselves


def test_a_resonance_moves_to_f0_over_one_plus_eps():
    f = np.arange(500.0, 2000.0, 0.5)
    f0 = 1100.0
    h = 1.0 / (f0 ** 2 - f ** 2 + 2j * 0.01 * f0 * f)  # one mode, as a joint feature
    planes = np.broadcast_to(h[None, :, None, None], (2, f.size, 1, 1))
    out = frequency_shifted(planes, f, np.array([0.02, -0.02]))
    peaks = f[np.argmax(np.abs(out[:, :, 0, 0]), axis=1)]
    assert peaks == pytest.approx(f0 / np.array([1.02, 0.98]), abs=1.0)  # two grid steps


def _spec():
    return stack_from_dict(json.loads(STACK.read_text()))


def _flat():
    """The fixture's joint, real stiffness with 2 % loss, constant in frequency."""
    j = spring_damper_joint(F, K, 0.0 * C, ["3x", "3ry"])
    return j.replace(values=np.broadcast_to(np.linalg.inv(np.diag(K * (1 + 0.02j))), j.values.shape).copy())


def _dipped(flat, f_c: float):
    """``flat`` with its translational stiffness softened by 40 % over ±4 % about ``f_c`` (closed form)."""
    dip = 1.0 - 0.4 * np.exp(-0.5 * ((F - f_c) / (0.04 * f_c)) ** 2)
    z = np.linalg.inv(flat.values) * np.where(np.arange(2) == 1, 1.0, dip[:, None])[:, :, None]
    return flat.replace(values=np.linalg.inv(z))


def test_a_joint_constant_in_frequency_has_no_feature_sensitivity():
    spec, flat = _spec(), _flat()
    nominal = predict_tool_tip(spec, {"tool-holder": flat}, F).tip
    s = peak_shift_sensitivity(spec, {"tool-holder": flat}, nominal, ["tool-holder"])
    assert set(s) == {"x", "y"} and max(s.values()) <= 1e-12
    # an interface that is not resolved is not shifted
    assert peak_shift_sensitivity(spec, {"tool-holder": flat}, nominal, ["holder-spindle"]) == {"x": 0.0, "y": 0.0}


def test_the_sensitivity_matches_closed_form_joints_with_their_features_moved():
    spec, flat = _spec(), _flat()
    f_mode = F[np.argmax(np.abs(predict_tool_tip(spec, {"tool-holder": flat}, F).tip.values[:, 0, 0]))]
    featured = _dipped(flat, f_mode)
    nominal = predict_tool_tip(spec, {"tool-holder": featured}, F).tip
    got = peak_shift_sensitivity(spec, {"tool-holder": featured}, nominal, ["tool-holder"], delta=0.03)
    peak0 = np.abs(nominal.values[:, 0, 0]).max()
    logs = [np.log(np.abs(predict_tool_tip(spec, {"tool-holder": _dipped(flat, f_mode / (1 + e))}, F)
                          .tip.values[:, 0, 0]).max() / peak0) for e in (0.03, -0.03)]
    want = float(np.sqrt(np.mean(np.square(logs))))
    assert want > 0.01  # the dip under the mode matters
    # linear interpolation of a dip ~ 0.04 f_mode wide on 1 Hz lines: relative error ≲ (1 / 0.04 f_mode)² / 8, 1e-5
    assert got["x"] == pytest.approx(want, rel=1e-3)
    assert got["y"] == pytest.approx(got["x"], rel=1e-12)  # one joint for both planes


def test_bad_shifts_are_refused_with_a_message():
    with pytest.raises(InputError, match="between 0 and 1"):
        peak_shift_sensitivity(_spec(), {}, predict_tool_tip(_spec(), {"tool-holder": _flat()}, F).tip, [], 1.5)
    with pytest.raises(InputError, match="between -1 and 1"):
        read_shifted(_flat(), float("nan"))


def test_the_term_adds_to_the_substructure_model_in_quadrature_in_one_draw():
    spec, flat = _spec(), _flat()
    both = tip_band(spec, {"tool-holder": flat}, freq=F[::10], n=300, seed=4, model_sigma=0.3, feature_sigma=0.4)
    one = tip_band(spec, {"tool-holder": flat}, freq=F[::10], n=300, seed=4, model_sigma=0.5)
    assert np.allclose(both.peak["x"], one.peak["x"], rtol=1e-12)
    assert both.interfaces == ("feature position", "substructure model")
    alone = tip_band(spec, {"tool-holder": flat}, freq=F[::10], n=4000, seed=4, feature_sigma=0.1)
    # 5–95 % of a log-normal of σ 0.1: ln(p95 / p05) = 3.29 σ. Each quantile of 4000 draws has a standard error of
    # sqrt(0.05·0.95 / 4000) / φ(1.645) ≈ 0.033 in z, so their difference ≈ 0.047 z = 0.0047 in log: 4 of them
    assert np.log(alone.peak["x"][2] / alone.peak["x"][0]) == pytest.approx(3.29 * 0.1, abs=0.019)


def test_only_a_chosen_per_line_tool_holder_joint_is_shifted(monkeypatch):
    from types import SimpleNamespace

    import jointdb.usecases._stack_band as sb

    monkeypatch.setattr(sb, "choice_perturbation", lambda r, f: r.choice)
    tip = SimpleNamespace(freq=F)
    per_line = SimpleNamespace(choice=(1,), damping_references=(("th@1", 0.6, None, False), ("th@2", 0.4, None, True)))
    constant = SimpleNamespace(choice=(1,), damping_references=(("th@1", 1.0, None, True),))
    guarded = SimpleNamespace(choice=(1,), damping_references=per_line.damping_references, constant_fallback=True)
    pinned = SimpleNamespace(choice=None, damping_references=per_line.damping_references)
    assert sb._feature_interfaces({"tool-holder": per_line}, F) == ["tool-holder"]
    assert sb._feature_interfaces({"holder-spindle": per_line}, F) == []  # FEATURE_POSITION_INTERFACES
    for r in (constant, guarded, pinned):
        assert sb._feature_interfaces({"tool-holder": r}, F) == []
        assert sb.feature_position(None, {"tool-holder": r}, tip) == (0.0, [])
