"""The evaluator's memo of predictions (ModelEvaluator.predict_u): a repeated point gives the identical
array without a new model evaluation, a new point or another candidate is evaluated, and copies of an
evaluator that weight other lines (the jackknife's) share it."""

import copy

import numpy as np

from jointdb.diagnose import Measurement
from jointdb.diagnose._data import prepare
from jointdb.diagnose._fit import MEMO_SIZE, ModelEvaluator
from jointdb.diagnose.physics import Context, candidates_for
from jointdb.fe import BeamModel, Clamp, ModalDamping, NamedPoint, PointMass, Segment


def _setup():
    shaft, tip = (Segment(0.2, 0.02, material="steel"),), (NamedPoint("tip", 0.0, node=1),)
    model = BeamModel(shaft, tip, (Clamp(0.2), ModalDamping(0.01)))
    truth = BeamModel(shaft, tip, (Clamp(0.2), ModalDamping(0.01), PointMass(0.0, 0.02)))
    rec = truth.frf(np.arange(50.0, 3000.0, 5.0), points=["tip"]).select(["1x"], ["1x"])
    modes = model.modes(8).freq_hz
    obs = prepare(model, [Measurement(rec)], None, (None, None), model_freqs=modes)
    ctx = Context(model=model, points=("tip",), n_levels=1, levels=obs.levels, modes_hz=modes)
    cands = [c for c in candidates_for(ctx) if c.family == "sensor_mass"]
    return model, ModelEvaluator(obs), cands


def test_a_repeated_point_is_not_evaluated_again_and_is_the_same_array():
    model, ev, cands = _setup()
    cand = cands[0]
    calls = []
    frf = ev.frf
    ev.frf = lambda m: calls.append(1) or frf(m)
    u = np.full(len(cand.params), 0.1)
    H = ev.predict_u(model, cand, u)
    assert np.array_equal(H, ev.predict(model, cand, {q.name: q.from_u(x) for q, x in zip(cand.params, u)}))
    n = len(calls)
    again = ev.predict_u(model, cand, u.copy())
    assert again is H and len(calls) == n and not H.flags.writeable
    other = ev.predict_u(model, cand, u + 1e-12)                     # another point: evaluated
    assert len(calls) == n + 1 and other is not H
    sub = copy.copy(ev)                                               # a jackknife copy shares the memo
    sub.w = np.zeros_like(ev.w)
    assert sub.predict_u(model, cand, u) is H and len(calls) == n + 1
    if len(cands) > 1:                                                # another candidate at the same u
        ev.predict_u(model, cands[1], u[: len(cands[1].params)])
        assert len(calls) == n + 2


def test_the_memo_keeps_the_last_points_only():
    model, ev, cands = _setup()
    cand = cands[0]
    first = ev.predict_u(model, cand, np.zeros(len(cand.params)))
    for k in range(MEMO_SIZE):
        ev.predict_u(model, cand, np.full(len(cand.params), 1e-3 * (k + 1)))
    assert len(ev._memo) == MEMO_SIZE
    again = ev.predict_u(model, cand, np.zeros(len(cand.params)))
    assert again is not first and np.array_equal(again, first)


def test_the_memo_keeps_at_most_its_byte_budget(monkeypatch):
    import jointdb.diagnose._fit as fit

    model, ev, cands = _setup()
    cand = cands[0]
    one = ev.predict_u(model, cand, np.zeros(len(cand.params))).nbytes
    monkeypatch.setattr(fit, "MEMO_BYTES", 3 * one)                   # room for three predictions
    sub = copy.copy(ev)                                               # a copy counts into the same budget
    for k in range(6):
        (sub if k % 2 else ev).predict_u(model, cand, np.full(len(cand.params), 1e-3 * (k + 1)))
    assert len(ev._memo) == 3 and ev._memo_bytes[0] == 3 * one
