"""`optimize` against brute force (predict + lobes per candidate), its constraints, and the CLI."""

import json
import math
import os
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import pytest

from optimize_helpers import fast_equals_brute_force

from jointdb.usecases._optimize import best_cut, enumerate_candidates, load_problem
from jointdb.usecases._optimize_eval import evaluate_candidates

ROOT = Path(__file__).resolve().parents[2]
SPEC = ROOT / "fixtures" / "optimize" / "optimize-spec.json"


def test_candidates_are_the_catalogued_conditions_in_range(catalogue):
    repo, _ = catalogue
    problem = load_problem(SPEC)
    cands = enumerate_candidates(problem, repo)
    # the bundled tool-holder torques are 40/80/120 N·m, the HSK-A63 drawbar forces 12/18/24 kN; 4 overhangs
    assert sorted({c.torque_nm for c in cands}) == [40.0, 80.0, 120.0]
    assert sorted({c.drawbar_n for c in cands}) == [12000.0, 18000.0, 24000.0]
    assert sorted({c.overhang_m for c in cands}) == [0.055, 0.06, 0.065, 0.07]
    assert len(cands) == 36


def test_fast_ranking_equals_brute_force_to_the_last_digit(catalogue):
    repo, _ = catalogue
    problem = load_problem(SPEC)
    cands = enumerate_candidates(problem, repo)[::3]  # a small grid: 12 candidates
    fast = fast_equals_brute_force(problem, cands, repo)


def test_constraints_bind_where_they_should(catalogue):
    repo, _ = catalogue
    problem = load_problem(SPEC)
    (res,) = evaluate_candidates(problem, enumerate_candidates(problem, repo)[:1], repo)
    b = res.best
    d = 0.012
    rate = b["depth_m"] * 0.5 * d * 1e-4 * 4 * b["spindle_speed_rpm"] / 60
    assert math.isclose(b["removal_rate_m3_s"], rate, rel_tol=1e-12)
    assert math.isclose(b["power_w"], problem.cut.kt * rate, rel_tol=1e-12)
    # a tiny spindle power makes power bind; its depth is P / (K_t a_e f_z N n/60)
    spec = problem.spec.model_copy(update={"machine": problem.spec.machine.model_copy(update={"power_w": 100.0,
                                                                                              "torque_nm": None})})
    weak = best_cut(replace(problem, spec=spec), res.lobes)
    assert weak["binding"] == "power"
    assert math.isclose(weak["power_w"], 100.0, rel_tol=1e-9)
    # a short flute binds when stability allows more
    spec = problem.spec.model_copy(update={"tool": problem.spec.tool.model_copy(update={"flute_length_m": 1e-4})})
    short = best_cut(replace(problem, spec=spec), res.lobes)
    assert short["binding"] == "flute length" and short["depth_m"] == 1e-4


def test_optimize_cli_recommends_a_stack_that_the_time_domain_confirms(catalogue, tmp_path):
    _, db = catalogue
    env = dict(os.environ, PYTHONPATH=str(ROOT), OPENBLAS_NUM_THREADS="1")
    r = subprocess.run([sys.executable, "-m", "jointdb", "optimize", str(SPEC), "--db", str(db), "--json",
                        "--out", str(tmp_path / "opt"), "--scheduler", "in-process"], capture_output=True, text=True, cwd=ROOT, env=env)
    assert r.returncode == 0, r.stderr
    doc = json.loads(r.stdout)
    best = doc["ranked"][0]
    assert best["removal_rate_m3_s"] > 0 and best["joint_tool-holder"] and best["joint_holder-spindle"]
    rec, above = doc["checks"]
    assert not rec["chatter"] and above["chatter"]
    for name in ("ranking.csv", "best-lobes.png", "rate-vs-overhang.png", "pareto-rate-vs-margin.png", "result.json"):
        assert (tmp_path / "opt" / name).stat().st_size > 0


def test_the_best_five_are_sd_confirmed_and_nothing_unconfirmed_outranks_them(catalogue):
    from jointdb.usecases import optimize_stack

    repo, _ = catalogue
    out = optimize_stack(load_problem(SPEC), repo, simulate=False, scheduler="in-process")
    top = out.ranked[:5]
    assert all("sd_limit_m" in r.best for r in top)
    assert all(r.best["depth_m"] <= r.best["sd_limit_m"] * (1 - r.best["margin"]) + 1e-15 for r in top)
    floor = top[-1].best["removal_rate_m3_s"]
    assert all(r.best["removal_rate_m3_s"] <= floor for r in out.ranked[5:])
    assert out.ranked[0].tip is not None
