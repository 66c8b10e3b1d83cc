"""The main job end to end (catalogue → query → predict → lobes) on a temporary SQLite database, and what its
outputs show: the tip plot and refined lobes, ``joints show`` and ``query`` on the database it filled (one run of
the job for the whole file)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from jointdb.usecases._demo import run_main_job
from jointdb.io import read_frf_csv, read_frf_uff58
from jointdb.store import Repository


@pytest.fixture(scope="module")
def journey(tmp_path_factory):
    """One run of the main job (default settings) on a database of its own, shared by this file's tests:
    ``(output folder, database file, result, the lines it said)``."""
    tmp = tmp_path_factory.mktemp("journey")
    lines: list[str] = []
    db = tmp / "journey.sqlite"
    result = run_main_job(tmp / "out", f"sqlite:///{db}", say=lines.append)
    return tmp / "out", db, result, lines


def test_main_job_runs_end_to_end_and_writes_its_outputs(journey):
    out, db, result, lines = journey
    url = f"sqlite:///{db}"

    expected = {"catalogue.csv", "joint-choice.json", "joint-choice.png", "stack.json", "tip.uff", "tip.csv",
                "tip-vs-rigid.png", "lobes.csv", "lobes.png", "summary.json"}
    assert expected <= {p.name for p in out.iterdir()}
    assert all(p.stat().st_size > 0 for p in result.files)
    assert not (out / "joints.sqlite").exists()  # the given database was used

    # 1. six campaigns catalogued, each identified close to its true joint (0.2 % noise, Savitzky–Golay
    #    smoothing, coarser models than the "measurement": the rotational term is the sensitive one)
    assert len(result.catalogued) == 12
    for row in result.catalogued:
        assert abs(row["k_x_error"]) < 0.01 and abs(row["k_theta_error"]) < 0.06, row
    with Repository(url) as repo:
        assert len(repo.list_joints("tool-holder")) == 6
        assert len(repo.list_joints("holder-spindle")) == 6

    # 2. the query had a real choice and the report names version and distance
    th = next(j for j in result.joints if j["interface"] == "tool-holder")
    assert th["kind"] == "query" and "@" in th["joint"]
    dists = [c[2] for c in th["candidates"]]
    assert len(dists) == 3 and dists == sorted(dists) and dists[0] > 0
    assert th["distance"] == pytest.approx(dists[0])
    assert any("tool-holder: chose " + th["joint"] in line and "distance" in line for line in lines)
    assert th["joint"].startswith("th-er32-carbide-")  # same interface materials as the request
    # the holder–spindle interface is catalogued too: same taper (HSK-A63), nearest drawbar force (20 kN → 18 kN)
    hs = next(j for j in result.joints if j["interface"] == "holder-spindle")
    assert hs["kind"] == "query" and hs["joint"] == "hs-hsk-a63-18kn@1" and hs["distance"] > 0
    assert not hs["extrapolating"]
    assert any("holder-spindle: chose hs-hsk-a63-18kn@1 at distance" in line for line in lines)

    # 3. the written tip FRF is the prediction, in both formats
    uff, csv = read_frf_uff58(out / "tip.uff"), read_frf_csv(out / "tip.csv")
    assert uff.n_freq == csv.n_freq and np.allclose(uff.values, csv.values, rtol=1e-6)
    peak = result.prediction[0]
    k = int(np.argmax(np.abs(csv.entry("1x", "1x"))))
    assert csv.freq[k] == pytest.approx(peak["peak_hz"])
    # two bending planes: the demo spindle's bearings are 25 % softer in y, so the y tip differs from x
    hx, hy = csv.entry("1x", "1x"), csv.entry("1y", "1y")
    assert np.max(np.abs(hx - hy)) > 0.02 * np.max(np.abs(hx))
    assert [r["direction"] for r in result.prediction] == ["x", "y"]

    # 4. lobes: a finite floor, and the summary says what was done
    assert 0 < result.lobes["min_depth_m"] < result.lobes["best_depth_m"]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["lobes"]["min_depth_m"] == pytest.approx(result.lobes["min_depth_m"])
    assert "INTERPOLATED" in next(iter(summary["interpolated_cross_check"]["joints"].values()))
    assert set(summary["interfaces"]) == {"tool-holder", "holder-spindle"}
    assert all("@" in v["joint"] and v["distance"] > 0 for v in summary["interfaces"].values())
    assert [line[:5] for line in lines if line.startswith("[")] == ["[1/4]", "[2/4]", "[3/4]", "[4/4]"]


def test_journey_tip_plot_legend_and_refined_lobes(journey):
    out, db, result, _ = journey
    assert (out / "tip-vs-rigid.png").exists() and (out / "lobes.png").exists()
    import csv

    with (out / "lobes.csv").open(encoding="utf-8") as fh:
        n = sum(1 for _ in csv.DictReader(fh))
    assert n > 400  # 400 base speeds plus the refinement near minima and pockets


def test_joints_show_prints_constant_k_c(journey, cli):
    out, db, result, _ = journey
    row = next(r for r in result.catalogued if r["joint"].startswith("th-er32-carbide-120nm"))
    truth = json.loads(next((p for p in _campaign_dirs() if p.name == "th-er32-carbide-120nm")).joinpath(
        "truth.json").read_text(encoding="utf-8"))
    r = cli("joints", "show", "th-er32-carbide-120nm", "--db", db)
    assert r.returncode == 0, r.stderr
    assert "constant k, c per DOF: median of Re(1/h)" in r.stdout
    lines = {ln.split("|")[1].strip(): [c.strip() for c in ln.split("|")[2:-1]]
             for ln in r.stdout.splitlines() if ln.startswith("| 3")}
    header = next(ln for ln in r.stdout.splitlines() if ln.startswith("| dof |"))
    cols = [c.strip() for c in header.split("|")[2:-1]]
    k_x = float(lines["3x"][cols.index("k [N/m]")])
    k_t = float(lines["3ry"][cols.index("k [N·m/rad]")])
    # the synthetic campaign's true joint; identification is within 1 % of it (catalogue: row["k_x_error"])
    assert k_x == pytest.approx(truth["k"][0], rel=0.02) and k_t == pytest.approx(truth["k"][1], rel=0.02)
    assert abs(row["k_x_error"]) < 0.02
    rj = cli("joints", "show", "th-er32-carbide-120nm", "--db", db, "--json")
    kc = json.loads(rj.stdout)["constant_kc"]
    assert [d["dof"] for d in kc["dofs"]] == ["3x", "3ry"] and kc["dofs"][0]["k_unit"] == "N/m"
    assert kc["dofs"][0]["k"] == pytest.approx(k_x, rel=1e-3)  # 4 digits shown


def _campaign_dirs():
    from importlib import resources

    return [p for p in resources.files("jointdb").joinpath("data", "catalogue", "campaigns").iterdir() if p.is_dir()]


def test_query_out_equals_json_rows(journey, tmp_path, cli):
    out, db, _, _ = journey
    args = ["query", "--type", "tool-holder", "--material", "carbide+steel", "--torque", "100", "-k", "3", "--db", db]
    rj = cli(*args, "--json")
    ro = cli(*args, "--out", tmp_path / "m.json")
    assert rj.returncode == 0 and ro.returncode == 0, ro.stderr
    assert json.loads((tmp_path / "m.json").read_text(encoding="utf-8"))["rows"] == json.loads(rj.stdout)
