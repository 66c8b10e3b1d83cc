"""CLI: ``jointdb modes``, ``jointdb frf`` (the console entry point in-process, the ``cli`` fixture) and ``jointdb demo``
(run as a subprocess outside the source tree, like a user)."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

FIXTURES = Path(__file__).resolve().parents[2] / "fixtures" / "models"
MODEL = FIXTURES / "end-mill-in-holder.json"


def run(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "jointdb", *map(str, args)], capture_output=True, text=True, cwd=cwd)


def test_modes_json_matches_the_library(cli):
    from jointdb.fe import load_model

    out = cli("modes", MODEL, "--n", "4", "--json")
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    expected = load_model(MODEL).modes(4).freq_hz
    np.testing.assert_allclose([m["freq_hz"] for m in data["modes"]], expected, rtol=1e-12)
    assert [m["mode"] for m in data["modes"]] == [1, 2, 3, 4]
    assert data["kind"] == "planar" and data["theory"] == "timoshenko" and data["n_rigid"] == 0


def test_modes_table_for_people(cli):
    out = cli("modes", FIXTURES / "carbide-end-mill-12mm.json", "--n", "3")
    assert out.returncode == 0, out.stderr
    assert "rigid body" in out.stdout and "bending" in out.stdout


def test_frf_writes_csv_and_bode_plot(tmp_path, cli):
    csv, png = tmp_path / "tip.csv", tmp_path / "tip.png"
    out = cli("frf", MODEL, "--points", "tip,gauge", "--fmax", "4000", "--df", "10", "--out", csv, "--plot", png, "--json")
    assert out.returncode == 0, out.stderr
    summary = json.loads(out.stdout)
    assert summary["lines"] == 401 and summary["dofs"] == "1x 1ry 2x 2ry"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    from jointdb.fe import load_model
    from jointdb.io import read_frf_csv

    frf = read_frf_csv(csv)
    direct = load_model(MODEL).frf(np.arange(0, 4001, 10.0), points=["tip", "gauge"])
    assert frf.outputs == direct.outputs
    np.testing.assert_allclose(frf.values, direct.values, rtol=1e-9, atol=1e-9 * np.abs(direct.values).max())


@pytest.mark.parametrize("suffix", [".uff", ".h5"])
def test_frf_writes_uff58_and_hdf5(tmp_path, suffix, cli):
    path = tmp_path / f"tip{suffix}"
    out = cli("frf", FIXTURES / "carbide-end-mill-12mm.json", "--points", "tip", "--directions", "x",
              "--fmax", "20000", "--n-lines", "200", "--quantity", "accelerance", "--method", "modal", "--out", path,
              "--binary")
    assert out.returncode == 0, out.stderr
    assert "start at" in out.stderr  # free-free: the 0 Hz line is dropped, and it says so
    from jointdb.io import read_frf_hdf5, read_frf_uff58

    frf = read_frf_uff58(path) if suffix == ".uff" else read_frf_hdf5(path)
    assert frf.quantity.value == "accelerance" and [str(d) for d in frf.outputs] == ["1x"]
    assert frf.n_freq == 199 and frf.freq[0] > 0


@pytest.mark.parametrize(
    "args, message",
    [
        (["modes", "missing.json"], "does not exist"),
        (["modes", "{bad}", "--n", "0"], "--n must be >= 1"),
        (["frf", "{bad}", "--fmin", "0"], "rigid-body modes"),
        (["frf", "{model}", "--points", "nose"], "unknown point 'nose'"),
        (["frf", "{model}", "--out", "x.txt"], "unknown FRF file type"),
        (["frf", "{model}", "--df", "1", "--n-lines", "5"], "either --df or --n-lines"),
        (["modes", "{broken}"], "segments[1].outer_diameter: must be > 0"),
    ],
)
def test_user_errors_exit_nonzero_with_one_line_and_no_traceback(tmp_path, args, message, cli, monkeypatch):
    broken = json.loads(MODEL.read_text())
    broken["segments"][1]["outer_diameter"] = -0.012
    (tmp_path / "broken.json").write_text(json.dumps(broken))
    subs = {"{bad}": str(FIXTURES / "carbide-end-mill-12mm.json"), "{model}": str(MODEL),
            "{broken}": str(tmp_path / "broken.json")}
    monkeypatch.chdir(tmp_path)
    out = cli(*[subs.get(a, a) for a in args])
    assert out.returncode != 0
    assert "Traceback" not in out.stderr
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], out.stderr


def test_demo_runs_end_to_end_outside_the_source_tree(tmp_path):
    out_dir = tmp_path / "demo out"
    out = run("demo", "--out", out_dir, cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    model_dir = out_dir / "tool-model"
    for name in ("tip-frf.uff", "tip-frf.csv", "tip-frf-bode.png", "modes.json", "end-mill-in-holder.json"):
        assert (model_dir / name).is_file(), name
    for name in ("catalogue.csv", "tip.uff", "tip-vs-rigid.png", "lobes.csv", "lobes.png", "summary.json"):
        assert (out_dir / name).is_file(), name
    assert "[1] model" in out.stderr and "[5] wrote" in out.stderr
    assert "[1/4]" in out.stderr and "[4/4]" in out.stderr
    listed = out.stdout.strip().splitlines()
    assert str(out_dir / "lobes.png") in listed and str(model_dir / "modes.json") in listed
    from jointdb.io import read_frf_uff58

    frf = read_frf_uff58(model_dir / "tip-frf.uff")
    modes = json.loads((model_dir / "modes.json").read_text())["modes"]
    # the tip FRF peaks at the first mode
    h = np.abs(frf.entry("1x", "1x"))
    assert abs(frf.freq[np.argmax(h)] - modes[0]["freq_hz"]) < 5.0


def test_bode_and_nyquist_helpers_write_pngs(tmp_path):
    from jointdb.errors import InputError
    from jointdb.fe import load_model
    from jointdb.plots import save_bode, save_nyquist

    model = load_model(MODEL)
    freq = np.linspace(100, 5000, 200)
    frf = model.frf(freq, points=["tip"])
    modal = model.frf(freq, points=["tip"], method="modal", n_modes=2)
    bode = save_bode(tmp_path / "b.png", frf, pairs=[("1x", "1x"), ("1ry", "1x")], labels=["direct", "2 modes"],
                     others=[modal])
    nyq = save_nyquist(tmp_path / "n.png", frf)
    for path in (bode, nyq):
        assert path.read_bytes()[:4] == b"\x89PNG"
    with pytest.raises(InputError, match="must end in .png"):
        save_bode(tmp_path / "b.pdf", frf)
