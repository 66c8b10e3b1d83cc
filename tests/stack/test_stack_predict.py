"""Tool-tip prediction (docs/theory.md §4) against single FE models of the whole stack."""

from __future__ import annotations

import copy
import json
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg

from jointdb.coupling import Interface, couple
from jointdb.errors import InputError
from jointdb.fe import BeamModel, HystereticDamping, NamedPoint, Support, model_from_dict
from jointdb.frf import FRF, Dof
from jointdb.stack import (
    MeasuredSpindle,
    holder_model,
    predict_tool_tip,
    spindle_model,
    stack_from_dict,
    stack_parts,
    tool_model,
)

STACKS = Path(__file__).resolve().parents[2] / "fixtures" / "stacks"
FREQ = np.linspace(20.0, 6000.0, 150)


def _doc() -> dict:
    return json.loads((STACKS / "endmill-modelled-spindle.json").read_text())


def _dofs_at(model: BeamModel, position: float) -> list[int]:
    mesh = model.mesh()
    node = mesh.node_at(position)
    return [mesh.dof(node, "x"), mesh.dof(node, "ry")]


def _monolithic_tip(spec, joints: dict[str, tuple[tuple[float, float], tuple[float, float]] | None]) -> np.ndarray:
    """Tip x/x receptance of the whole stack from one assembled matrix system.

    The parts' matrices are placed block-diagonally; a flexible joint adds
    springs/dampers ``k [[1, −1], [−1, 1]]`` between the paired DOFs; a rigid
    joint merges the paired DOFs (transformation ``u = T q``). One direct solve
    per line: no receptance coupling involved.
    """
    models = [tool_model(spec), holder_model(spec), spindle_model(spec)]
    mats = [m.assemble() for m in models]
    sizes = [m.K.shape[0] for m in mats]
    off = np.concatenate([[0], np.cumsum(sizes)])
    K = scipy.linalg.block_diag(*[m.K for m in mats]).astype(complex)
    K += 1j * scipy.linalg.block_diag(*[m.K_loss for m in mats])
    C = scipy.linalg.block_diag(*[m.C for m in mats])
    M = scipy.linalg.block_diag(*[m.M for m in mats])
    fixed = np.concatenate([m.fixed for m in mats])
    tool, holder, spindle = models
    pairs = {
        "tool-holder": (
            [off[0] + i for i in _dofs_at(tool, spec.gauge_length)],
            [off[1] + i for i in _dofs_at(holder, 0.0)],
        ),
        "holder-spindle": (
            [off[1] + i for i in _dofs_at(holder, spec.holder.length)],
            [off[2] + i for i in _dofs_at(spindle, spindle.point("nose").position)],
        ),
    }
    n = K.shape[0]
    T = np.eye(n)
    drop = []
    for name, (a, b) in pairs.items():
        if joints[name] is None:  # rigid: q_b := q_a
            for ia, ib in zip(a, b):
                T[ib, :] = 0.0
                T[ib, ia] = 1.0
                drop.append(ib)
        else:
            (kx, kr), (cx, cr) = joints[name]
            for ia, ib, k, c in zip(a, b, (kx, kr), (cx, cr)):
                for (i, j), s in (((ia, ia), 1), ((ib, ib), 1), ((ia, ib), -1), ((ib, ia), -1)):
                    K[i, j] += s * k
                    C[i, j] += s * c
    keep = [j for j in range(n) if j not in drop and not fixed[j]]
    T = T[:, keep]
    Kr, Cr, Mr = T.T @ K @ T, T.T @ C @ T, T.T @ M @ T
    tip = keep.index(_dofs_at(tool, 0.0)[0] + off[0])
    w = 2 * np.pi * FREQ
    D = Kr[None] + 1j * w[:, None, None] * Cr[None] - (w**2)[:, None, None] * Mr[None]
    rhs = np.zeros((FREQ.size, len(keep), 1), dtype=complex)
    rhs[:, tip, 0] = 1.0
    return np.linalg.solve(D, rhs)[:, tip, 0]


def test_prediction_with_joints_equals_one_fe_model_of_the_whole_stack():
    spec = stack_from_dict(_doc())
    pred = predict_tool_tip(spec, freq=FREQ)
    ref = _monolithic_tip(spec, {"tool-holder": ((3e7, 6e5), (300, 3)), "holder-spindle": ((2e8, 3e6), (800, 10))})
    got = pred.tip.entry("1x", "1x")
    assert np.max(np.abs(got - ref)) / np.max(np.abs(ref)) < 1e-9
    # the joints matter: the rigid prediction is far away
    assert np.max(np.abs(pred.rigid.entry("1x", "1x") - ref)) / np.max(np.abs(ref)) > 0.3
    # axisymmetric: y equals x, and the note says so
    np.testing.assert_allclose(pred.tip.entry("1y", "1y"), got, rtol=1e-13)
    assert any("y plane" in n for n in pred.notes)


def test_rigid_prediction_equals_one_beam_model_of_the_whole_stack():
    doc = _doc()
    doc["interfaces"] = {"tool-holder": "rigid", "holder-spindle": "rigid"}
    doc["tool"]["loss_factor"] = doc["holder"]["loss_factor"] = 0.01
    doc["spindle"]["model"]["max_element_length"] = 0.005  # one mesh size, as the single model below has
    spec = stack_from_dict(doc)
    pred = predict_tool_tip(spec, freq=FREQ)
    # one BeamModel: tool overhang + composite holder + spindle, supports shifted
    tool, holder = tool_model(spec), holder_model(spec)
    sp = model_from_dict(doc["spindle"]["model"])
    shift = tool.length + holder.length
    supports = tuple(
        Support(s.position + shift, s.stiffness, s.damping) for s in sp.ingredients if isinstance(s, Support)
    )
    whole = BeamModel(
        tool.segments + holder.segments + sp.segments,
        points=(NamedPoint("tip", 0.0, 1),),
        ingredients=supports + (HystereticDamping(0.01),),
    )
    ref = whole.frf(FREQ, ["tip"]).entry("1x", "1x")
    got = pred.tip.entry("1x", "1x")
    assert np.max(np.abs(got - ref)) / np.max(np.abs(ref)) < 1e-9
    np.testing.assert_allclose(pred.rigid.values, pred.tip.values, rtol=1e-13)


def test_chain_agrees_with_general_lm_fbs_coupling():
    spec = stack_from_dict(_doc())
    pred = predict_tool_tip(spec, freq=FREQ)
    parts = stack_parts(spec, FREQ)
    from jointdb.coupling import spring_damper_joint

    th = spring_damper_joint(FREQ, [3e7, 6e5], [300, 3], ["2x", "2ry"])
    hs = spring_damper_joint(FREQ, [2e8, 3e6], [800, 10], ["4x", "4ry"])
    g = couple(
        parts,
        [
            Interface("tool", ["2x", "2ry"], "holder", ["3x", "3ry"], th),
            Interface("holder", ["4x", "4ry"], "spindle", ["5x", "5ry"], hs),
        ],
        outputs=[("tool", "1x")],
    )
    np.testing.assert_allclose(pred.tip.entry("1x", "1x"), g.entry("1x", "1x"), rtol=1e-9)


def test_measured_spindle_frf_gives_the_same_prediction_as_its_model_and_reads_the_y_plane():
    doc = _doc()
    spec = stack_from_dict(doc)
    model_pred = predict_tool_tip(spec, freq=FREQ)
    s_frf = spindle_model(spec).frf(FREQ, ["nose"]).replace(
        outputs=("7x", "7ry"), inputs=("7x", "7ry")
    )
    doc["spindle"] = {"file": "spindle.uff", "node": 7}
    measured = stack_from_dict(doc)
    measured = measured.replace(spindle=MeasuredSpindle("spindle.uff", 7, s_frf))
    pred = predict_tool_tip(measured, freq=FREQ)
    np.testing.assert_allclose(pred.tip.values, model_pred.tip.values, rtol=1e-12)
    # a stiffer y plane (y, rx with rx = −dθ/dz convention) gives a different, stiffer y prediction
    v = np.zeros((FREQ.size, 4, 4), dtype=complex)
    v[:, :2, :2] = s_frf.values
    T = np.diag([1.0, -1.0])
    v[:, 2:, 2:] = 0.5 * (T @ s_frf.values @ T)  # y plane: half as compliant
    both = FRF(FREQ, v, ("7x", "7ry", "7y", "7rx"), ("7x", "7ry", "7y", "7rx"))
    pred2 = predict_tool_tip(measured.replace(spindle=MeasuredSpindle("spindle.uff", 7, both)), freq=FREQ)
    np.testing.assert_allclose(pred2.tip.entry("1x", "1x"), model_pred.tip.entry("1x", "1x"), rtol=1e-12)
    assert not np.allclose(pred2.tip.entry("1y", "1y"), pred2.tip.entry("1x", "1x"))
    assert not pred2.notes


def test_resolved_joint_frf_is_used_like_explicit_values():
    doc = _doc()
    doc["interfaces"]["tool-holder"] = "th-demo@2"
    spec = stack_from_dict(doc)
    with pytest.raises(InputError, match="interfaces.tool-holder: th-demo@2 must be resolved"):
        predict_tool_tip(spec, freq=FREQ)
    # a joint FRF on a wider, coarser grid, at some other node, is resampled and used
    fj = np.linspace(10.0, 7000.0, 3000)
    w = 2 * np.pi * fj
    jv = np.zeros((fj.size, 2, 2), dtype=complex)
    jv[:, 0, 0] = 1 / (3e7 + 1j * w * 300)
    jv[:, 1, 1] = 1 / (6e5 + 1j * w * 3)
    joint = FRF(fj, jv, ("9x", "9ry"), ("9x", "9ry"))
    pred = predict_tool_tip(spec, {"tool-holder": joint}, freq=FREQ)
    ref = predict_tool_tip(stack_from_dict(_doc()), freq=FREQ)
    assert pred.interfaces["tool-holder"] == "th-demo@2"
    err = np.max(np.abs(pred.tip.values - ref.tip.values)) / np.max(np.abs(ref.tip.values))
    assert err < 1e-3  # linear interpolation of a smooth joint FRF
    with pytest.raises(InputError, match=r"covers 10–7000 Hz but the prediction needs"):
        predict_tool_tip(spec, {"tool-holder": joint}, freq=np.linspace(20, 8000, 50))
    no_rot = FRF(fj, jv[:, :1, :1], ("9x",), ("9x",))
    with pytest.raises(InputError, match="needs x and ry"):
        predict_tool_tip(spec, {"tool-holder": no_rot}, freq=FREQ)


def test_prediction_refuses_a_zero_hz_line():
    spec = stack_from_dict(_doc())
    with pytest.raises(InputError, match="> 0 Hz"):
        predict_tool_tip(spec, freq=[0.0, 10.0])


def test_fluted_section_uses_the_kops_vo_equivalent_diameter():
    spec = stack_from_dict(_doc())
    tool = tool_model(spec)
    assert tool.segments[0].outer_diameter == pytest.approx(0.656 * 0.012)
    assert tool.segments[1].outer_diameter == pytest.approx(0.012)
    assert tool.length == pytest.approx(spec.gauge_length)
    holder = holder_model(spec)
    # 30 mm of shank inside the 40 mm bore: composite, then the empty bore, then the solid base
    assert [round(s.length, 6) for s in holder.segments] == [0.03, 0.01, 0.03]
    assert holder.segments[1].inner_diameter == pytest.approx(0.012)
    comp = holder.segments[0].mat
    steel, wc = holder.segments[2].mat, tool.segments[1].mat
    i_full, i_h, i_t = (np.pi * d**4 / 64 for d in (0.032, 0.032, 0.012))
    i_h -= i_t
    assert comp.E * i_full == pytest.approx(steel.E * i_h + wc.E * i_t)
    d = copy.deepcopy(_doc())
    d["tool"]["fluted_ratio"] = 1.0
    assert tool_model(stack_from_dict(d)).segments[0].outer_diameter == pytest.approx(0.012)
    assert Dof(1, "x") in predict_tool_tip(spec, freq=FREQ[:3]).tip.outputs
