"""The main job end to end (catalogue → query → predict → lobes) on a temporary SQLite database."""

from __future__ import annotations

import json

import numpy as np
import pytest

from jointdb.usecases._demo import run_main_job
from jointdb.io import read_frf_csv, read_frf_uff58
from jointdb.store import Repository


def test_main_job_runs_end_to_end_and_writes_its_outputs(tmp_path):
    lines: list[str] = []
    out = tmp_path / "out"
    url = f"sqlite:///{tmp_path / 'journey.sqlite'}"
    result = run_main_job(out, url, say=lines.append, n_speeds=60)

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
