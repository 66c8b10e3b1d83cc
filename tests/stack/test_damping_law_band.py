"""The band's damping-law term (issue 22 item 1): a constant k, c joint used away from its campaign's mode.

A constant spring–damper ``Z = K + i 2πf C`` fitted at one mode (``f_ref``) fixes its loss there, not the law of
its loss; the term samples the fractional-derivative family between viscous (β = 1) and hysteretic (β = 0).
Known answers: at ``f_ref`` nothing changes; β = 0 is a hysteretic joint of loss factor ``η = 2π f_ref C / K``
on every line; a stack with this term alone lies between its viscous and its hysteretic prediction, its peak
monotone in β; the catalogue records ``f_ref``; the term is 0, with its reason, without ``f_ref``, for a per-line
joint and for an explicit joint; an interpolation mixing constant and per-line joints applies the law to the
constant joints' weight.
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from jointdb.coupling import spring_damper_joint
from jointdb.errors import InputError
from jointdb.stack import predict_tool_tip, stack_from_dict
from jointdb.stack._band import damping_law, tip_band
from jointdb.usecases import predict_with_joints, resolve_joints
from jointdb.usecases._catalogue import identification_peak_hz
from jointdb.usecases._stack_band import absent_terms, band_terms, damping_laws

ROOT = Path(__file__).resolve().parents[2]
STACK = ROOT / "fixtures" / "stacks" / "endmill-modelled-spindle.json"
CAMPAIGN = ROOT / "fixtures" / "campaigns" / "th-steel-30nm" / "campaign.json"
K, C = np.array([3e7, 6e5]), np.array([300.0, 3.0])  # the fixture stack's tool–holder joint (x, θ)


def _planes(f, n=1):
    h = spring_damper_joint(f, K, C, ["3x", "3ry"]).values
    return np.broadcast_to(h, (n,) + h.shape)


def test_at_the_reference_frequency_the_law_changes_nothing():
    f = np.array([500.0, 1234.5, 4000.0])
    out = damping_law(_planes(f, 3), f, 1234.5, np.array([0.0, 0.4, 1.0]))
    z_in, z_out = np.linalg.inv(_planes(f, 3)), np.linalg.inv(out)
    assert np.allclose(z_out[:, 1], z_in[:, 1], rtol=1e-12, atol=0)  # every β, the f_ref line
    assert np.allclose(z_out[2], z_in[2], rtol=1e-12, atol=0)  # β = 1 (viscous, as catalogued), every line


def test_beta_zero_is_a_hysteretic_joint_with_the_loss_it_has_at_the_reference():
    f = np.linspace(50.0, 6000.0, 120)
    f_ref = 1800.0
    z = np.linalg.inv(damping_law(_planes(f), f, f_ref, np.array([0.0]))[0])
    eta = 2 * np.pi * f_ref * C / K  # loss factor per DOF
    for i in range(2):
        assert np.allclose(z[:, i, i].real, K[i], rtol=1e-10)
        assert np.allclose(z[:, i, i].imag / z[:, i, i].real, eta[i], rtol=1e-10)  # the same η on every line
    assert np.allclose(z[:, 0, 1], 0, atol=1e-6 * K[1])
    # half-way: Im Z ∝ f^0.5 through the same point at f_ref
    zh = np.linalg.inv(damping_law(_planes(f), f, f_ref, np.array([0.5]))[0])
    assert np.allclose(zh[:, 0, 0].imag, 2 * np.pi * f_ref * C[0] * np.sqrt(f / f_ref), rtol=1e-10)
    # share: a mix of constant (weight 0.3) and per-line joints keeps 70 % of Im Z as it is
    zs = np.linalg.inv(damping_law(_planes(f), f, f_ref, np.array([0.0]), share=0.3)[0])
    expect = 2 * np.pi * f * C[0] * (0.3 * f_ref / f + 0.7)
    assert np.allclose(zs[:, 0, 0].imag, expect, rtol=1e-10)


def test_the_law_refuses_what_is_not_a_law():
    f = np.array([100.0, 200.0])
    for args in ((0.0, np.array([0.5])), (np.nan, np.array([0.5])), (100.0, np.array([1.5])),
                 (100.0, np.array([0.5, 0.5]))):
        with pytest.raises(InputError, match="damping law"):
            damping_law(_planes(f), f, *args)
    with pytest.raises(InputError, match="share"):
        damping_law(_planes(f), f, 100.0, np.array([0.5]), share=1.5)


def _spec():
    return stack_from_dict(json.loads(STACK.read_text()))


def _peak(spec, frfs, f):
    return np.abs(predict_tool_tip(spec, frfs, f).tip.values[:, 0, 0]).max()


def test_the_term_alone_brackets_the_viscous_and_the_hysteretic_stack_and_is_monotone_in_beta():
    spec = _spec()
    f = np.arange(20.0, 6000.1, 5.0)
    frfs = {"tool-holder": spring_damper_joint(f, K, C, ["3x", "3ry"])}  # the stack's own joint, as an FRF
    tip = np.abs(predict_tool_tip(spec, frfs, f).tip.values[:, 0, 0])
    f_mode = f[np.argmax(tip)]
    f_ref = f_mode / 2.5  # a campaign whose mode lay at 40 % of this stack's
    th = frfs["tool-holder"]

    def peak_at(beta):
        lawed = th.replace(values=damping_law(th.values[None], th.freq, f_ref, np.array([beta]))[0])
        return _peak(spec, {**frfs, "tool-holder": lawed}, f)

    peaks = np.array([peak_at(b) for b in np.linspace(0.0, 1.0, 11)])
    viscous, hysteretic = peaks[-1], peaks[0]
    assert viscous == pytest.approx(tip.max(), rel=1e-9)  # β = 1: the catalogued joint
    assert hysteretic > viscous * 1.01  # less loss above f_ref: a higher peak
    assert np.all(np.diff(peaks) < 0)  # monotone in β
    b = tip_band(spec, frfs, freq=f, n=200, seed=3, damping={"tool-holder": (f_ref, 1.0)})
    assert b.interfaces == ("damping law",)
    sampled = np.abs(b.tips["x"]).max(axis=1)
    assert sampled.min() >= viscous * (1 - 1e-9) and sampled.max() <= hysteretic * (1 + 1e-9)
    span = hysteretic - viscous  # 200 uniform β: the ends are reached to 5 % of the span (each miss p = 0.95^200)
    assert sampled.min() <= viscous + 0.05 * span and sampled.max() >= hysteretic - 0.05 * span
    assert np.array_equal(b.tips["x"], b.tips["y"])  # both planes take the same draw (an axisymmetric stack)


def test_the_catalogue_records_the_frequency_of_the_dominant_identification_peak(tmp_path):
    from jointdb.store import Repository
    from jointdb.usecases._catalogue import catalogue_campaign

    rows = [{"entry": "1rx/1rx", "f_measured_hz": 300.0, "amplitude_measured": 1e-3},
            {"entry": "1x/1x", "f_measured_hz": 900.0, "amplitude_measured": 2e-6},
            {"entry": "1x/1x", "f_measured_hz": 2100.0, "amplitude_measured": 5e-6}]
    assert identification_peak_hz({"peaks": rows}) == 2100.0  # translational first: a rotation is in other units
    assert identification_peak_hz({"peaks": rows[:1]}) == 300.0
    for bad in (None, {}, {"peaks": []}, {"peaks": [{"f_measured_hz": -1.0, "amplitude_measured": 1.0}]},
                {"peaks": [{"f_measured_hz": True, "amplitude_measured": 1.0}]}, {"peaks": [3]}):
        assert identification_peak_hz(bad) is None
    with Repository(tmp_path / "j.sqlite") as repo:
        out = catalogue_campaign(repo, CAMPAIGN, author="test")
        peaks = out.identified.quality["peaks"]
        top = max((p for p in peaks if p["entry"].split("/")[0][-1] in "xyz" and "r" not in p["entry"].split("/")[0]),
                  key=lambda p: p["amplitude_measured"])
        assert out.version.quality["identification_peak_hz"] == top["f_measured_hz"]
        j = resolve_joints(_spec().replace(interfaces={**_spec().interfaces, "tool-holder": _pinned(out)}), repo)
        (name, w, f_ref, constant), = j["tool-holder"].damping_references
        assert (name, w, f_ref) == (f"{out.version.name}@{out.version.version}", 1.0, top["f_measured_hz"])
        # the fixture campaign keeps constant k, c exactly when its fit covariance describes the catalogued joint
        unc = (out.version.provenance.parameters or {}).get("uncertainty") or {}
        assert constant == (bool(unc) and unc.get("describes_catalogued_joint", True) is not False)


def _pinned(out):
    from jointdb.stack import JointChoice

    return JointChoice("catalogued", name=out.version.name, version=out.version.version)


def _with_refs(refs):
    """The fixture prediction with its tool–holder joint resolved as if from catalogued versions ``refs``."""
    spec = _spec()
    joints = resolve_joints(spec, None)
    joints["tool-holder"] = replace(joints["tool-holder"], kind="catalogued", damping_references=tuple(refs))
    return predict_with_joints(spec, joints, np.arange(20.0, 5000.1, 10.0))


def test_the_term_is_zero_with_its_reason_and_weighted_over_an_interpolation():
    plain = predict_with_joints(_spec(), resolve_joints(_spec(), None), np.arange(20.0, 5000.1, 10.0))
    why = absent_terms(plain)["damping law"]
    assert "explicit k, c written in the stack" in why  # the fixture's joints are written in the stack: no f_ref known
    r = _with_refs([("th@1", 1.0, None, True)])
    assert "records no identification frequency" in absent_terms(r)["damping law"]
    r = _with_refs([("th@1", 0.6, 900.0, False), ("th@2", 0.4, 1200.0, False)])
    assert "per-line joint (th@1, th@2)" in absent_terms(r)["damping law"]
    terms = band_terms(r, n=50)
    assert terms.half_width["damping law"] == {} and "damping law" in terms.zero
    # an interpolation mixing constant and per-line joints: not sampled (the constant part's loss cannot be taken
    # apart from the interpolated Z), said why
    r = _with_refs([("a@1", 0.25, 800.0, True), ("b@1", 0.5, 1800.0, True), ("c@1", 0.25, 3000.0, False)])
    laws, why = damping_laws(r.joints)
    assert "tool-holder" not in laws and "constant k, c (a@1, b@1) and per-line (c@1)" in why["tool-holder"]
    # the passivity guard's constant fallback: not sampled, and not called a per-line joint
    fell = replace(r.joints["tool-holder"], constant_fallback=True, damping_references=(("a@1", 1.0, 800.0, True),))
    laws, why = damping_laws({**r.joints, "tool-holder": fell})
    assert "tool-holder" not in laws and "passivity guard" in why["tool-holder"]
    # an interpolation of constant joints: f_ref their weighted geometric mean
    r = _with_refs([("a@1", 0.25, 800.0, True), ("b@1", 0.75, 1800.0, True)])
    laws, why = damping_laws(r.joints)
    f_ref, share = laws["tool-holder"]
    assert f_ref == pytest.approx(np.exp(0.25 * np.log(800.0) + 0.75 * np.log(1800.0)), rel=1e-12)
    assert share == 1.0 and "holder-spindle" in why
    terms = band_terms(r, n=50)
    assert "damping law" not in terms.zero and terms.half_width["damping law"]["x"] > 0
    assert any("damping law sampled between viscous and hysteretic about f_ref" in n for n in terms.notes)
    rows = {t["term"]: t for t in terms.to_json()["terms"]}
    assert rows["damping law"]["zero_because"] is None and rows["damping law"]["peak_half_width"]["x"] > 0


def test_only_a_constant_spring_damper_is_given_the_law():
    """A spring–damper of order 0 whose covariance describes the catalogued FRF gets the law; a fitted
    frequency law (order > 0), a joint body (K + iD − ω²M: hysteretic already), a full matrix, a record kept as
    information beside a per-line joint, or no record do not."""
    from types import SimpleNamespace

    from jointdb.usecases._stack import _is_constant_kc

    def version(unc, kind="spring-damper"):
        return SimpleNamespace(model_kind=kind, provenance=SimpleNamespace(parameters={"uncertainty": unc}))

    assert _is_constant_kc(version({"model": "spring-damper", "order": 0}))
    assert _is_constant_kc(version({}))  # records written before the model was named: a constant spring-damper
    assert not _is_constant_kc(version({"model": "spring-damper", "order": 2}))
    assert not _is_constant_kc(version({"model": "joint-body"}))
    assert not _is_constant_kc(version({"model": "spring-damper"}, kind="full-matrix"))
    assert not _is_constant_kc(version({"model": "spring-damper", "describes_catalogued_joint": False}))
    assert not _is_constant_kc(version(None))
