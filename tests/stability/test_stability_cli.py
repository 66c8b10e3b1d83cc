"""The `jointdb lobes` and `jointdb modal-fit` commands, end to end on real files."""

import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from jointdb.cli import app
from jointdb.io import write_frf_hdf5, write_uff58
from jointdb.modal import ModalModel

REAL_FILE = Path(__file__).resolve().parents[1] / "data" / "measured-accelerance-3refs.uff"
runner = CliRunner()


@pytest.fixture(scope="module")
def tip_files(tmp_path_factory):
    d = tmp_path_factory.mktemp("tip")
    k = 0.03993 * (2 * np.pi * 922) ** 2
    model = ModalModel.from_modal_parameters([922], [0.011], [k], "1x")
    frf = model.synthesize(np.arange(600, 1300, 0.1))
    write_frf_hdf5(d / "tip.h5", frf)
    write_uff58(d / "tip.uff", frf.to("accelerance"), binary=True)
    return d, k


def run(args):
    result = runner.invoke(app, args)
    return result


def test_lobes_zoa_json_from_uff_gives_the_benchmark_floor(tip_files):
    d, k = tip_files
    r = run(["lobes", str(d / "tip.uff"), "--op", "milling", "--method", "zoa", "--teeth", "2", "--kt", "6e8",
             "--kr", "2e8", "--rpm-min", "5000", "--rpm-max", "25000", "--n-speeds", "800", "--json"])
    assert r.exit_code == 0, r.output
    data = json.loads(r.stdout[r.stdout.index("{"):])
    depths = np.array([row["depth_m"] for row in data["rows"]], dtype=float)
    assert np.nanmin(depths) == pytest.approx(2 * k * 0.011 * 1.011 / 1e8, rel=5e-3)
    assert {row["kind"] for row in data["rows"]} == {"hopf"}


def test_lobes_sd_from_hdf5_fits_modes_and_writes_a_plot(tip_files, tmp_path):
    d, _ = tip_files
    png = tmp_path / "lobes.png"
    r = run(["lobes", str(d / "tip.h5"), "--op", "milling", "--method", "sd", "--teeth", "2", "--kt", "6e8", "--kr", "2e8",
             "--immersion", "0.1", "--rpm-min", "14000", "--rpm-max", "22000", "--n-speeds", "5", "--modes", "1",
             "--intervals", "20", "--plot", str(png), "--json"])
    assert r.exit_code == 0, r.output
    data = json.loads(r.stdout[r.stdout.index("{"):])
    assert data["method"] == "milling-sd"
    assert "flip" in {row["kind"] for row in data["rows"]}
    assert png.exists() and png.stat().st_size > 5000


def test_lobes_turning_table(tip_files):
    d, k = tip_files
    r = run(["lobes", str(d / "tip.h5"), "--op", "turning", "--kf", "1e9", "--n-speeds", "20"])
    assert r.exit_code == 0, r.output
    assert "speeds_added_by_refinement" in r.stdout and "min_depth [mm]" in r.stdout  # a summary by default
    r = run(["lobes", str(d / "tip.h5"), "--op", "turning", "--kf", "1e9", "--n-speeds", "20", "--table"])
    assert r.exit_code == 0, r.output
    assert "spindle_speed [rpm]" in r.stdout and "depth [mm]" in r.stdout and "hopf" in r.stdout


def test_lobes_user_errors_are_one_line(tip_files, tmp_path):
    d, _ = tip_files
    r = run(["lobes", str(d / "tip.h5"), "--op", "turning"])
    assert r.exit_code != 0 and "--kf" in str(r.exception)
    bad = tmp_path / "tip.txt"
    bad.write_text("x")
    r = run(["lobes", str(bad), "--op", "milling", "--kt", "1", "--kr", "1"])
    assert r.exit_code != 0 and "unknown FRF file type" in str(r.exception)


@pytest.mark.skipif(not REAL_FILE.exists(), reason="shared real data file not present")
def test_modal_fit_on_the_real_file_reports_quality(tmp_path):
    r = run(["modal-fit", str(REAL_FILE), "--band", "5", "1000", "--modes", "6", "--max-order", "40",
             "--plot", str(tmp_path), "--json"])
    assert r.exit_code == 0, r.output
    data = json.loads(r.stdout[r.stdout.index("{"):])
    assert len(data["modes"]) == 6
    assert data["quality"]["nmse_total"] < 0.02 and data["quality"]["frac_min"] > 0.98
    assert (tmp_path / "modal-fit-stabilisation.png").exists() and (tmp_path / "modal-fit-overlay.png").exists()
