"""The joint-choice term's feature position (issue 22, round 3 session 11): a chosen joint's frequency axis shifted.

Known answers: linear interpolation is exact on a receptance linear in frequency; a joint with a resonance read at
``f (1 + ε)`` has it at ``f₀ / (1 + ε)``; a joint constant in frequency is unchanged by any shift, so the term alone
gives a band of zero width, while a joint with a feature under the stack's mode gives a band.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from jointdb.coupling import spring_damper_joint
from jointdb.stack import predict_tool_tip, stack_from_dict
from jointdb.stack._band import frequency_shifted, tip_band

ROOT = Path(__file__).resolve().parents[2]
STACK = ROOT / "fixtures" / "stacks" / "endmill-modelled-spindle.json"
K, C = np.array([3e7, 6e5]), np.array([300.0, 3.0])  # the fixture stack's tool–holder joint (x, θ)


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


def test_a_joint_without_features_gives_no_band_and_a_feature_under_the_mode_does():
    spec = _spec()
    f = np.arange(20.0, 6000.1, 5.0)
    flat = spring_damper_joint(f, K, 0.0 * C, ["3x", "3ry"])  # real and constant in frequency
    flat = flat.replace(values=np.broadcast_to(np.linalg.inv(np.diag(K * (1 + 0.02j))), flat.values.shape).copy())
    b = tip_band(spec, {"tool-holder": flat}, freq=f, n=50, seed=2, feature_shift={"tool-holder": 0.03})
    peaks = np.abs(b.tips["x"]).max(axis=1)
    assert np.ptp(peaks) <= 1e-12 * peaks.max()
    # the same joint softened by 40 % over a band of ±4 % around the stack's mode: where the mode sits matters
    tip = np.abs(predict_tool_tip(spec, {"tool-holder": flat}, f).tip.values[:, 0, 0])
    f_mode = f[np.argmax(tip)]
    dip = 1.0 - 0.4 * np.exp(-0.5 * ((f - f_mode) / (0.04 * f_mode)) ** 2)
    z = np.linalg.inv(flat.values) * np.where(np.arange(2) == 1, 1.0, dip[:, None])[:, :, None]
    featured = flat.replace(values=np.linalg.inv(z))
    b = tip_band(spec, {"tool-holder": featured}, freq=f, n=200, seed=2, feature_shift={"tool-holder": 0.03})
    peaks = np.abs(b.tips["x"]).max(axis=1)
    nominal = np.abs(predict_tool_tip(spec, {"tool-holder": featured}, f).tip.values[:, 0, 0]).max()
    assert np.ptp(peaks) > 0.01 * nominal
    assert b.interfaces == ("tool-holder",)


def test_the_usecase_shifts_only_joints_with_a_joint_choice_error(monkeypatch):
    import jointdb.usecases._stack_band as sb

    monkeypatch.setattr(sb, "FEATURE_SHIFT", 0.0)
    assert sb.feature_shifts({"tool-holder": object()}) == {}
    monkeypatch.setattr(sb, "FEATURE_SHIFT", 0.02)
    assert sb.feature_shifts({"tool-holder": object()}) == {"tool-holder": 0.02}
    assert sb.feature_shifts({}) == {}
