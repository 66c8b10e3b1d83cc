"""``jointdb predict``: files, JSON report of the chosen joints, and one clear line for bad stack files."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
from typer.testing import CliRunner

from jointdb.cli import app
from jointdb.coupling import spring_damper_joint
from jointdb.io import read_frf_csv
from jointdb.store import Conditions, Repository

ROOT = Path(__file__).resolve().parents[2]
STACK = ROOT / "fixtures" / "stacks" / "endmill-modelled-spindle.json"


def _doc() -> dict:
    return json.loads(STACK.read_text())


def test_predict_writes_the_tip_frf_and_the_comparison_plot(tmp_path):
    out, plot = tmp_path / "tip.csv", tmp_path / "tip.png"
    r = CliRunner().invoke(app, ["predict", str(STACK), "--out", str(out), "--plot", str(plot),
                                 "--fmax", "3000", "--df", "20", "--json"])
    assert r.exit_code == 0, r.output
    report = json.loads(r.stdout)
    assert [j["kind"] for j in report["joints"]] == ["explicit", "explicit"]
    tip = read_frf_csv(out)
    assert [str(d) for d in tip.outputs] == ["1x", "1y"] and tip.freq[-1] == 3000.0
    assert report["prediction"][0]["peak_hz"] == float(tip.freq[np.argmax(np.abs(tip.entry("1x", "1x")))])
    assert plot.stat().st_size > 10_000


def test_predict_reports_the_chosen_version_and_distance(tmp_path):
    db = tmp_path / "j.sqlite"
    f = np.linspace(10.0, 6000.0, 300)
    with Repository(db) as repo:
        for name, torque in (("th-a", 50.0), ("th-b", 100.0)):
            repo.catalogue(name, "tool-holder", spring_damper_joint(f, [3e7, 5e5], [300, 3], ["3x", "3ry"]),
                           Conditions(("tungsten-carbide", "steel"), torque_nm=torque), "spring-damper-planar")
    doc = _doc()
    doc["interfaces"]["tool-holder"] = {"query": {"joint_type": "tool-holder", "torque_nm": 90}}
    doc["frequency"] = {"min": 20, "max": 3000, "step": 20}
    stack = tmp_path / "stack.json"
    stack.write_text(json.dumps(doc))
    r = CliRunner().invoke(app, ["predict", str(stack), "--db", str(db), "--json"])
    assert r.exit_code == 0, r.output
    th = json.loads(r.stdout)["joints"][0]
    assert th["joint"] == "th-b@1" and th["kind"] == "query" and th["distance"] > 0
    assert "torque_nm=" in th["per_condition"]
    assert "tool-holder: nearest: th-b@1 (weight 1.000, distance" in r.stderr


def test_bad_stack_file_gives_one_line_naming_the_field(tmp_path):
    doc = _doc()
    doc["holder"]["segments"][0]["outer_diameter"] = -0.03
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(doc))
    p = subprocess.run([sys.executable, "-m", "jointdb", "predict", str(bad)], capture_output=True, text=True)
    assert p.returncode == 2
    assert p.stderr.strip() == "error: bad.json: holder.segments[0].outer_diameter: must be > 0 (got -0.03)"
    assert "Traceback" not in p.stderr and p.stdout == ""
