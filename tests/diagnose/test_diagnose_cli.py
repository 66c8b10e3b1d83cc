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
    assert res.returncode == 3 and "no such file" in res.stderr   # not found, like every missing file


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


def _nan_in_first_value(src, dst, text="NaN"):
    """Copy a UFF58 file written by write_uff58 with the first value of its first FRF record set to NaN
    (as a text field, the way some acquisition software exports a dropped line)."""
    lines = src.read_text().split("\n")
    k = next(i for i, line in enumerate(lines) if line.strip().startswith("13    0    0    0")) + 2
    lines[k] = f"{text:>20s}" + lines[k][20:]
    dst.write_text("\n".join(lines))


def test_diagnose_command_names_a_nonfinite_line_or_masks_it(files):
    d, case = files
    _nan_in_first_value(d / "tap.uff", d / "tap-nan.uff")
    f0 = case.recordings[0].frf.freq[0]
    res = subprocess.run(JOINTDB + ["diagnose", str(d / "model.json"), str(d / "tap-nan.uff")],
                         capture_output=True, text=True)
    assert res.returncode == 2 and res.stderr.strip().count("\n") == 0, res.stderr
    assert f"tap-nan.uff: FRF 1x/1x: 1 non-finite value (NaN) at line 1 ({f0:g} Hz)" in res.stderr
    assert "--mask-nonfinite" in res.stderr
    res = subprocess.run(JOINTDB + ["diagnose", str(d / "model.json"), str(d / "tap-nan.uff"), "--mask-nonfinite",
                                    "--no-combinations", "--json"], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    assert f"note: tap-nan.uff: 1 non-finite value(s) masked (zero weight): FRF 1x/1x at line 1 ({f0:g} Hz)" \
        in res.stderr
    out = json.loads(res.stdout[res.stdout.index("{"):])
    assert out["input_notes"] and out["best"]["family"].startswith("sensor_mass")


def test_diagnose_command_an_inf_stored_as_the_largest_double_is_refused(files, tmp_path):
    """pyuff writes an Inf as 1.797e308 (and a NaN as 0): the reader takes that file, diagnose must not."""
    import numpy as np
    import pyuff

    d, case = files
    sets = pyuff.UFF(str(d / "tap.uff")).read_sets()
    k = next(i for i, s in enumerate(sets) if s.get("type") == 58)
    sets[k]["data"] = np.array(sets[k]["data"], dtype=complex)
    sets[k]["data"][9] = np.inf
    pyuff.UFF(str(tmp_path / "inf.uff")).write_sets(sets, mode="overwrite")
    res = subprocess.run(JOINTDB + ["diagnose", str(d / "model.json"), str(tmp_path / "inf.uff")],
                         capture_output=True, text=True)
    assert res.returncode == 2 and res.stderr.strip().count("\n") == 0, res.stderr
    f9 = case.recordings[0].frf.freq[9]
    assert f"inf.uff: FRF 1x/1x: 1 non-finite value (±1.8e308, an Inf as some UFF writers store it) at line 10 " \
           f"({f9:g} Hz)" in res.stderr


def test_diagnose_command_writes_a_backbone_for_several_levels(tmp_path):
    case = generate_case("softening_joint", 1)
    (tmp_path / "model.json").write_text(json.dumps(case.model))
    recs = []
    for i, r in enumerate(case.recordings):
        write_uff58(tmp_path / f"level{i + 1}.uff", r.frf)
        recs.append(str(tmp_path / f"level{i + 1}.uff"))
    levels = ",".join(f"{r.level_n:g}" for r in case.recordings)
    res = CliRunner().invoke(app, ["diagnose", str(tmp_path / "model.json"), *recs, "--levels", levels,
                                   "--plots", str(tmp_path / "figs"), "--no-combinations"])
    assert res.exit_code == 0, res.output
    assert "backbone.png" in [p.name for p in (tmp_path / "figs").iterdir()]
    assert (tmp_path / "figs" / "backbone.png").stat().st_size > 10_000
    assert "recorded modes per excitation level" in res.stdout and "changes with level" in res.stdout


def test_diagnose_command_names_a_literal_inf_as_inf(files):
    d, case = files
    _nan_in_first_value(d / "tap.uff", d / "tap-inf.uff", text="inf")
    f0 = case.recordings[0].frf.freq[0]
    res = subprocess.run(JOINTDB + ["diagnose", str(d / "model.json"), str(d / "tap-inf.uff")],
                         capture_output=True, text=True)
    assert res.returncode == 2 and res.stderr.strip().count("\n") == 0, res.stderr
    assert f"tap-inf.uff: FRF 1x/1x: 1 non-finite value (Inf) at line 1 ({f0:g} Hz)" in res.stderr


def test_diagnose_help_defines_explained_and_lists_exit_codes():
    res = subprocess.run(JOINTDB + ["diagnose", "--help"], capture_output=True, text=True)
    text = " ".join(res.stdout.split())
    assert res.returncode == 0
    assert '"Explained" (explained: true in --json) means' in text and "1.5x" in text and "identified" in text
    assert "Exit codes: 0 diagnosis done" in text and "2 bad input" in text and "3 a file not found" in text
