"""Plot details of issue 14: phase lines break at wraps, k(ω) scaled by percentiles (spikes clipped to
the edge), the tip-vs-rigid legend names the joint versions and weights, joints show prints k, c."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from types import SimpleNamespace

import numpy as np
import pytest

from jointdb.plots import phase_deg, robust_limits


def test_phase_breaks_at_wraps():
    f = np.linspace(0, 100, 1001)
    h = np.exp(-1j * 2 * np.pi * f / 25)  # a delay: the phase wraps four times
    ff, p = phase_deg(f, h)
    assert np.isnan(p).sum() == 4 and ff.size == f.size + 4
    finite = ~np.isnan(p)
    runs = np.split(p, np.flatnonzero(~finite))
    assert all(np.all(np.abs(np.diff(r[~np.isnan(r)])) < 10) for r in runs)  # no vertical bar inside a run
    assert np.array_equal(p[finite], np.degrees(np.angle(h)))  # the values themselves are unchanged


def test_robust_limits_ignore_single_spikes():
    y = np.full(500, 3.0e7) + np.linspace(-1e6, 1e6, 500)
    y[250] = 5e9  # one noisy line, 170x the level
    lo, hi = robust_limits(y)
    assert hi < 3.3e7 and lo > 2.7e7


def test_kc_plot_keeps_the_scale_of_the_bulk(tmp_path):
    from jointdb.frf import FRF
    from jointdb.plots import save_kc_plot

    f = np.linspace(50, 5000, 200)
    z = 3e7 + 1j * 2 * np.pi * f * 200.0
    z[100] = 1e10  # a spike in k(ω)
    frf = FRF(f, (1 / z)[:, None, None], ["3x"], ["3x"])
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    captured = {}
    real_close = plt.close

    def keep(fig=None):
        captured["fig"] = fig

    plt.close = keep
    try:
        save_kc_plot(tmp_path / "kc.png", frf)
    finally:
        plt.close = real_close
    ax_k = captured["fig"].axes[0]
    assert ax_k.get_ylim()[1] < 4e7  # the spike is drawn at the edge, not setting the scale
    assert any("off scale" in t.get_text() for t in ax_k.get_legend().get_texts())
    real_close(captured["fig"])


def test_tip_legend_names_versions_and_weights():
    from jointdb.plots import joints_legend

    res = {
        "tool-holder": SimpleNamespace(kind="interpolated", name="th-a", version=1,
                                       description="INTERPOLATED tool-holder joint from th-a v1 (w=0.550), "
                                                   "th-b v2 (w=0.450)"),
        "holder-spindle": SimpleNamespace(kind="query", name="hs-1", version=3, description=""),
        "spindle": SimpleNamespace(kind="rigid", name=None, version=None, description="rigid"),
    }
    text = joints_legend(res)
    assert text == "tool-holder: interpolated th-a v1 (w=0.550), th-b v2 (w=0.450); holder-spindle: hs-1 v3"


@pytest.fixture(scope="module")
def demo_db(tmp_path_factory):
    from jointdb.usecases._demo import run_main_job

    out = tmp_path_factory.mktemp("journey")
    result = run_main_job(out, say=lambda s: None)
    return out, result


def test_journey_tip_plot_legend_and_refined_lobes(demo_db):
    out, result = demo_db
    assert (out / "tip-vs-rigid.png").exists() and (out / "lobes.png").exists()
    import csv

    with (out / "lobes.csv").open(encoding="utf-8") as fh:
        n = sum(1 for _ in csv.DictReader(fh))
    assert n > 400  # 400 base speeds plus the refinement near minima and pockets


def test_joints_show_prints_constant_k_c(demo_db):
    out, result = demo_db
    row = next(r for r in result.catalogued if r["joint"].startswith("th-er32-carbide-120nm"))
    truth = json.loads(next((p for p in _campaign_dirs() if p.name == "th-er32-carbide-120nm")).joinpath(
        "truth.json").read_text(encoding="utf-8"))
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    r = subprocess.run([sys.executable, "-m", "jointdb", "joints", "show", "th-er32-carbide-120nm", "--db",
                        str(out / "joints.sqlite")], capture_output=True, text=True, env=env, timeout=120)
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
    rj = subprocess.run([sys.executable, "-m", "jointdb", "joints", "show", "th-er32-carbide-120nm", "--db",
                         str(out / "joints.sqlite"), "--json"], capture_output=True, text=True, env=env, timeout=120)
    kc = json.loads(rj.stdout)["constant_kc"]
    assert [d["dof"] for d in kc["dofs"]] == ["3x", "3ry"] and kc["dofs"][0]["k_unit"] == "N/m"
    assert kc["dofs"][0]["k"] == pytest.approx(k_x, rel=1e-3)  # 4 digits shown


def _campaign_dirs():
    from importlib import resources

    return [p for p in resources.files("jointdb").joinpath("data", "catalogue", "campaigns").iterdir() if p.is_dir()]


def test_query_out_equals_json_rows(demo_db, tmp_path):
    out, _ = demo_db
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    args = [sys.executable, "-m", "jointdb", "query", "--type", "tool-holder", "--material", "carbide+steel",
            "--torque", "100", "-k", "3", "--db", str(out / "joints.sqlite")]
    rj = subprocess.run([*args, "--json"], capture_output=True, text=True, env=env, timeout=120)
    ro = subprocess.run([*args, "--out", str(tmp_path / "m.json")], capture_output=True, text=True, env=env, timeout=120)
    assert rj.returncode == 0 and ro.returncode == 0, ro.stderr
    assert json.loads((tmp_path / "m.json").read_text(encoding="utf-8"))["rows"] == json.loads(rj.stdout)
