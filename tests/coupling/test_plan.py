"""Measurement planning (issue 13 item 4): Fisher information ranks tap points; the recommended points
lower the k_θ, c_θ error of the Table 4.1 joint against the default ones at the same noise."""

import json
import sys
from pathlib import Path

import numpy as np
import pytest
from test_coupling_planar import CR, CX, KR, KX, build_case

from jointdb.cli import main
from jointdb.coupling._oe_core import SpringDamperModel, coupled_blocks, fit
from jointdb.coupling._plan import plan_measurements
from jointdb.frf import Dof

CANDIDATES = [("B", "1x"), ("B", "201x"), ("B", "202x"), ("B", "2x"), ("A", "3x"), ("A", "103x")]
DEFAULT = [(0, 0), (0, 3)]  # tip direct 1x/1x and tip/contact 1x/2x: what identify_planar_joint uses
TRUE = np.array([KX, CX, KR, CR])


@pytest.fixture(scope="module")
def case():
    A, B, _ = build_case()
    bl = coupled_blocks({"A": A, "B": B}, "A", ["3x", "3ry"], "B", ["2x", "2ry"], CANDIDATES, CANDIDATES)
    m = SpringDamperModel((Dof(3, "x"), Dof(3, "ry")))
    th = m.start(np.array([KX, KR]), np.array([CX, CR]))
    return bl, m, th


def simulate(bl, m, th, pairs, seeds):
    g = m.evaluate(th, bl, False)[0]  # the assembly over all candidates with the true joint
    ent = np.zeros(g.shape[1:], bool)
    for o, i in pairs:
        ent[o, i] = True
    err = []
    for seed in seeds:
        rng = np.random.default_rng(seed)
        noisy = g * (1 + 0.01 * (rng.standard_normal(g.shape) + 1j * rng.standard_normal(g.shape)) / np.sqrt(2))
        start = m.start(np.array([KX * 1.1, KR * 0.8]), np.array([CX * 1.2, CR * 0.6]))
        err.append(fit(m, bl, noisy, np.abs(noisy), start, ent).values / TRUE - 1)
    return np.sqrt(np.mean(np.square(err), axis=0))


def test_recommended_points_lower_the_rotational_errors(case):
    bl, m, th = case
    targets = ["k 3ry", "c 3ry"]
    plan = plan_measurements(m, th, bl, n_measurements=2, targets=targets)
    best = plan.rows[0]
    default = plan_measurements(m, th, bl, n_measurements=2, targets=targets, must_include=DEFAULT, top=1).rows[0]
    assert best["criterion"] < 0.5 * default["criterion"]
    label = {f"{bl.outputs[o]}/{bl.inputs[i]}": (o, i) for o in range(6) for i in range(6)}
    seeds = range(500, 530)
    rms_default = simulate(bl, m, th, DEFAULT, seeds)
    rms_best = simulate(bl, m, th, [label[s] for s in best["measurements"]], seeds)
    # same noise, same number of FRFs: k_θ and c_θ errors drop (predicted ×0.44 and ×0.32)
    assert rms_best[2] < 0.7 * rms_default[2] and rms_best[3] < 0.6 * rms_default[3], (rms_best, rms_default)
    # the Fisher prediction is the error the output-error fit reaches (30 seeds: ±13 % sampling error of an RMS)
    for rms, row in ((rms_default, default), (rms_best, best)):
        predicted = np.array([row["std_rel"][n] for n in m.names])
        assert np.all(np.abs(rms / predicted - 1) < 0.4), (rms, predicted)


def test_averages_scale_with_the_target(case):
    bl, m, th = case
    p1 = plan_measurements(m, th, bl, targets=["c 3ry"], target=0.01, must_include=DEFAULT, top=1).rows[0]
    p2 = plan_measurements(m, th, bl, targets=["c 3ry"], target=0.001, must_include=DEFAULT, top=1).rows[0]
    sd = p1["std_rel"]["c 3ry"]
    assert p2["averages"] == int(np.ceil((sd / 0.001) ** 2)) and p1["averages"] == int(np.ceil((sd / 0.01) ** 2))


def test_plan_cli_on_the_bundled_campaign(monkeypatch, capsys):
    camp = Path(__file__).resolve().parents[2] / "fixtures" / "campaigns" / "th-steel-30nm" / "campaign.json"
    monkeypatch.setattr(sys, "argv", ["jointdb", "plan", str(camp), "--json"])
    try:
        main()
    except SystemExit as exc:
        assert not exc.code
    rep = json.loads(capsys.readouterr().out)
    assert rep["targets"] == ["k 3ry", "c 3ry"]
    assert rep["current"]["measurements"] and rep["ranked"]
    assert rep["ranked"][0]["criterion"] <= rep["current"]["criterion"]
