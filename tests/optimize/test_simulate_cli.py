"""`jointdb simulate` from the command line: verdicts, JSON, plots, refused options."""

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
TIP = Path(__file__).parent / "data" / "demo-tip.uff"


def run(*args):
    env = dict(os.environ, PYTHONPATH=str(ROOT), OPENBLAS_NUM_THREADS="1")
    return subprocess.run([sys.executable, "-m", "jointdb", *args], capture_output=True, text=True, cwd=ROOT, env=env)


def test_simulate_reports_stable_and_chatter_with_plots(tmp_path):
    # 12000 rpm on the demo tip: the SD limit is 1.057 mm (tests/optimize/test_simulate.py computes it).
    r = run("simulate", str(TIP), "--rpm", "12000,12000", "--depth", "0.95e-3,1.16e-3", "--teeth", "4",
            "--kt", "7.96e8", "--kr", "1.69e8", "--immersion", "0.5", "--revolutions", "100", "--json",
            "--plots", str(tmp_path / "figs"))
    assert r.returncode == 0, r.stderr
    cuts = json.loads(r.stdout)["cuts"]
    assert [c["chatter"] for c in cuts] == [False, True]
    assert 2800 < cuts[1]["chatter_freq_hz"] < 3000
    assert cuts[1]["max_force_n"] > cuts[0]["max_force_n"] > 0
    assert len(list((tmp_path / "figs").glob("simulate-*.png"))) == 2


def test_simulate_refuses_mismatched_depths():
    r = run("simulate", str(TIP), "--rpm", "12000,13000,14000", "--depth", "1e-3,2e-3", "--kt", "7e8", "--kr", "2e8")
    assert r.returncode == 2
    assert "one depth per speed" in r.stderr
