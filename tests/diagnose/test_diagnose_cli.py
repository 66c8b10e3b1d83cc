"""The two commands end to end on files written by the generator."""

import json
import subprocess
import sys

import pytest
from typer.testing import CliRunner

from jointdb.cli import app
from jointdb.diagnose_bench import generate_case
from jointdb.fe import PointMass, load_model
from jointdb.io import write_uff58

JOINTDB = [sys.executable, "-m", "jointdb"]


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("diag")
    case = generate_case("sensor_mass", 2)
    (d / "model.json").write_text(json.dumps(case.model))
    write_uff58(d / "tap.uff", case.recordings[0].frf)
    return d, case


def test_diagnose_command_json_out_and_plots(files):
    d, case = files
    res = CliRunner().invoke(app, ["diagnose", str(d / "model.json"), str(d / "tap.uff"), "--json",
                                   "--out", str(d / "fixed.json"), "--plots", str(d / "figs")])
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout[res.stdout.index("{"):])
    assert out["explained"] is True
    assert out["best"]["family"].startswith("sensor_mass")
    assert out["mismatch_before"] / out["mismatch_after"] >= 3
    assert out["modes"] and out["modes"][0]["shift_pct"] < 0
    fixed = load_model(d / "fixed.json")
    assert any(isinstance(i, PointMass) for i in fixed.ingredients)
    assert sorted(p.name for p in (d / "figs").iterdir()) == ["diagnose-frf.png", "diagnose-shifts.png"]


def test_diagnose_command_plain_verdict(files):
    d, case = files
    res = subprocess.run(JOINTDB + ["diagnose", str(d / "model.json"), str(d / "tap.uff"), "--no-combinations"],
                         capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    assert "Best explained by an unmodelled" in res.stdout and "sensor" in res.stdout
    assert "mismatch" in res.stdout and "→" in res.stdout


def test_diagnose_command_bad_map_is_one_line_and_exit_2(files):
    d, _ = files
    res = subprocess.run(JOINTDB + ["diagnose", str(d / "model.json"), str(d / "tap.uff"), "--map", "1=nose"],
                         capture_output=True, text=True)
    assert res.returncode == 2
    assert res.stderr.strip().count("\n") == 0 and "no point 'nose'" in res.stderr
    res = subprocess.run(JOINTDB + ["diagnose", str(d / "model.json"), str(d / "missing.uff")],
                         capture_output=True, text=True)
    assert res.returncode == 2 and "no such file" in res.stderr


def test_diagnose_bench_command_small_run():
    res = CliRunner().invoke(app, ["diagnose-bench", "--cases", "1", "--effects", "gain,none", "--seed", "5",
                                   "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout[res.stdout.index("{"):])
    rows = {r["effect"]: r for r in out["per_effect"]}
    assert rows["gain"]["named_first_pct"] == 100.0
    assert rows["none"]["false_alarm_pct"] == 0.0
    assert out["confusion"]["rows"] == ["gain", "none"]
    assert out["total_seconds"] > 0


def test_diagnose_bench_rejects_unknown_effect():
    res = subprocess.run(JOINTDB + ["diagnose-bench", "--effects", "gremlins"], capture_output=True, text=True)
    assert res.returncode == 2 and "unknown gremlins" in res.stderr
