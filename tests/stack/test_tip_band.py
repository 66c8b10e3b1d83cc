"""Uncertainty carried to the tool tip and the lobes (issue 13 item 3): sampled joints, bands, CLI."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from jointdb.cli import app
from jointdb.coupling import Interface, couple, spring_damper_joint
from jointdb.coupling._oe_core import coupled_blocks
from jointdb.coupling._propagate import (
    ensemble_coupled,
    sample_theta,
    spring_damper_samples,
    spring_pairs_stiffness,
)
from jointdb.stability import MillingCut, milling_lobes_zoa
from jointdb.stability._band import milling_lobes_band
from jointdb.store import Conditions, Provenance, Repository

ROOT = Path(__file__).resolve().parents[2]
STACK = ROOT / "fixtures" / "stacks" / "endmill-modelled-spindle.json"
sys.path.insert(0, str(ROOT / "tests" / "coupling"))


def record(k=(3e7, 5e5), c=(300.0, 3.0), rel=(0.01, 0.01, 0.10, 0.20)):
    theta = np.log([k[0], c[0], k[1], c[1]])
    return {"format": "jointdb-joint-uncertainty/1", "model": "spring-damper", "names": ["k 3x", "c 3x", "k 3ry",
            "c 3ry"], "theta": theta.tolist(), "covariance": np.diag(np.square(rel)).tolist(), "theta_is_log": True,
            "dofs": ["3x", "3ry"], "order": 0, "residual_rms": 1.0}


def test_samples_follow_the_covariance_and_couple_like_one_by_one():
    rec = record()
    th = sample_theta(rec, 20000, seed=1)
    assert np.allclose(np.std(th, axis=0), [0.01, 0.01, 0.10, 0.20], rtol=0.03)
    from test_coupling_planar import build_case

    freq = np.linspace(5.0, 3000.0, 50)
    A, B, _ = build_case(freq)
    bl = coupled_blocks({"A": A, "B": B}, "A", ["3x", "3ry"], "B", ["2x", "2ry"], [("B", "1x")], [("B", "1x")])
    hj = spring_damper_samples(rec, freq, 3, seed=2)
    g = ensemble_coupled(bl, spring_pairs_stiffness(hj))
    ks = np.exp(sample_theta(rec, 3, seed=2))
    for s in range(3):
        joint = spring_damper_joint(freq, ks[s, 0::2], ks[s, 1::2], ["3x", "3ry"])
        ref = couple({"A": A, "B": B}, [Interface("A", ["3x", "3ry"], "B", ["2x", "2ry"], joint)], [("B", "1x")])
        assert np.allclose(g[s], ref.values, rtol=1e-9, atol=0)


@pytest.fixture(scope="module")
def catalogued_with_covariance(tmp_path_factory):
    d = tmp_path_factory.mktemp("band")
    db = d / "j.sqlite"
    f = np.linspace(10.0, 6000.0, 300)
    with Repository(db) as repo:
        repo.catalogue("th-u", "tool-holder", spring_damper_joint(f, [3e7, 5e5], [300, 3], ["3x", "3ry"]),
                       Conditions(("tungsten-carbide", "steel"), torque_nm=80.0), "spring-damper-planar",
                       Provenance(method="output-error-planar", parameters={"uncertainty": record()}))
        repo.catalogue("th-v", "tool-holder", spring_damper_joint(f, [2e7, 3e5], [300, 3], ["3x", "3ry"]),
                       Conditions(("tungsten-carbide", "steel"), torque_nm=40.0), "spring-damper-planar")
    doc = json.loads(STACK.read_text())
    doc["interfaces"]["tool-holder"] = {"query": {"joint_type": "tool-holder", "torque_nm": 80}}
    doc["frequency"] = {"min": 20, "max": 3000, "step": 10}
    stack = d / "stack.json"
    stack.write_text(json.dumps(doc))
    return d, db, stack


def test_predict_json_and_plot_carry_the_band(catalogued_with_covariance):
    d, db, stack = catalogued_with_covariance
    plot = d / "tip.png"
    r = CliRunner().invoke(app, ["predict", str(stack), "--db", str(db), "--json", "--plot", str(plot)])
    assert r.exit_code == 0, r.output
    rep = json.loads(r.stdout)
    band = rep["band"]
    assert band["samples"] == 200 and band["interfaces"] == ["prediction path", "tool-holder"]
    nominal = {p["direction"]: p["peak_m_per_n"] for p in rep["prediction"]}
    for p in band["peaks"]:
        assert p["peak_m_per_n_p05"] < nominal[p["direction"]] < p["peak_m_per_n_p95"]
        # 10 % on k_θ and 20 % on c_θ must show at the tip: a band, not a line
        assert p["peak_m_per_n_p95"] / p["peak_m_per_n_p05"] > 1.01
    mag = band["magnitude_m_per_n"]["x"]
    assert len(mag["p05"]) == len(band["frequency_hz"]) and np.all(np.array(mag["p05"]) <= np.array(mag["p95"]))
    assert "band (200 samples of the tool-holder joint, prediction path): tip peak x" in r.stderr
    # two catalogued joints are too few for a leave-one-out estimate of the joint choice: said, not hidden
    assert "no joint-choice error" in r.stderr
    assert plot.stat().st_size > 10_000
    # how much the choice of joint matters: the next candidate (a softer joint) moves the tip peak
    alt = [row for row in rep["joint_choice_sensitivity"] if row["direction"] == "x"]
    assert alt and alt[0]["alternative"] == "th-v@1" and abs(alt[0]["peak_change"]) > 0.01
    assert "with the candidate th-v@1 alone" in r.stderr


def test_lobe_band_brackets_the_nominal_critical_depth(catalogued_with_covariance):
    from jointdb import usecases
    from jointdb.stack._band import tip_band

    _, db, stack = catalogued_with_covariance
    spec = usecases.load_stack(stack)
    result = usecases.predict_stack(spec, str(db))
    res = result.joints["tool-holder"]
    b = tip_band(spec, {"tool-holder": res.frf}, {"tool-holder": res.uncertainty}, result.prediction.tip.freq, n=60)
    cut = MillingCut(4, 7.96e8, 1.69e8, 0.5, True)
    speeds = np.linspace(5000, 20000, 60)
    lb = milling_lobes_band(b.tip_frfs("x"), b.tip_frfs("y"), cut, speeds)
    nominal = milling_lobes_zoa(result.prediction.tip, cut, spindle_speed_rpm=speeds)
    assert lb.critical_depth_m[0] < nominal.min_depth_m < lb.critical_depth_m[2]
    both = np.isfinite(lb.depth_m[0]) & np.isfinite(lb.depth_m[2]) & np.isfinite(nominal.depth_m)
    assert both.mean() > 0.8
    assert np.all(lb.depth_m[0][both] <= lb.depth_m[2][both])
    inside = (lb.depth_m[0] <= nominal.depth_m) & (nominal.depth_m <= lb.depth_m[2])
    assert inside[both].mean() > 0.8
