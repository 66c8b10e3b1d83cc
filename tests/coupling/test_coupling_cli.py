"""`jointdb identify` / `jointdb couple` on the fixture campaign; bad campaign files fail cleanly."""

import filecmp
import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from jointdb.io import read_frf_hdf5, read_frf_uff58, write_uff58

ROOT = Path(__file__).resolve().parents[2]
FIXTURE = ROOT / "fixtures" / "campaigns" / "th-steel-30nm"


@pytest.fixture
def campaign(tmp_path):
    d = tmp_path / "camp"
    shutil.copytree(FIXTURE, d)
    return d


def edit(campaign_dir, change):
    p = campaign_dir / "campaign.json"
    data = json.loads(p.read_text())
    change(data)
    p.write_text(json.dumps(data))
    return p


def test_identify_store_couple_back(run_cli, campaign, tmp_path):
    truth = json.loads((campaign / "truth.json").read_text())["joint"]
    out = tmp_path / "joint.h5"
    code, stdout, err = run_cli("identify", campaign / "campaign.json", "--out", out,
                            "--report", tmp_path / "rep.json", "--plots", tmp_path / "figs", "--json")
    assert code == 0, err
    rep = json.loads(stdout)
    fit = {row["dof"]: row for row in rep["constant_fit"]}
    assert abs(fit["3x"]["k"] / truth["kx"] - 1) < 0.02
    assert abs(fit["3x"]["c"] / truth["cx"] - 1) < 0.05
    assert rep["validation"]["identified_joint_error_mean"] < 0.1
    assert rep["validation"]["rigid_joint_error_mean"] > 0.5
    assert json.loads((tmp_path / "rep.json").read_text())["joint_model"] == "planar"
    assert {p.name for p in (tmp_path / "figs").iterdir()} == {"joint_kc.png", "assembly_fit.png", "validation.png"}
    joint = read_frf_hdf5(out)
    assert [str(d) for d in joint.inputs] == ["3x", "3ry"]
    # couple back through the stored joint: reproduces the (noisy) measurement, unlike a rigid joint
    code, stdout, err = run_cli("couple", campaign / "campaign.json", "--joint", out,
                            "--out", tmp_path / "g.uff", "--json")
    assert code == 0, err
    dev = json.loads(stdout)["mean_relative_deviation_from_measurement"]
    code, stdout, _ = run_cli("couple", campaign / "campaign.json", "--json")
    dev_rigid = json.loads(stdout)["mean_relative_deviation_from_measurement"]
    assert dev < 0.06 < 0.5 < dev_rigid
    g = read_frf_uff58(tmp_path / "g.uff")
    meas = read_frf_uff58(campaign / "assembly.uff", "receptance").select(["1x"], ["1x"])
    assert np.median(np.abs(g.values - meas.values) / np.abs(meas.values)) < 0.03


BAD = [
    ("missing file", lambda d: d["substructures"]["tool"].update(model="nope.json"),
     "substructures.tool.model: file 'nope.json' not found"),
    ("unknown substructure", lambda d: d["interface"].update(a="holdr"), "interface.a: unknown substructure 'holdr'"),
    ("unknown field", lambda d: d.update(measurment=["x.uff"]), "measurment: unknown field"),
    ("bad joint model", lambda d: d.update(joint_model="magic"), "joint_model: must be one of"),
    ("bad dof", lambda d: d["interface"].update(b_dofs=["2x", "2q"]), "interface.b_dofs"),
    ("missing dof in file", lambda d: d["substructures"]["holder"].update(dofs=["3x", "3ry", "9x"]),
     "holder.uff has no DOF(s) 9x"),
    ("no rotations", lambda d: d["interface"].update(a_dofs=["3x", "3rx"]),
     "substructure A has no FRF between 3x and 3rx"),
    ("no tip", lambda d: d["planar"].pop("b_tip"), "planar.b_tip"),
]


@pytest.mark.parametrize("label,change,message", BAD, ids=[b[0] for b in BAD])
def test_bad_campaign_fails_clearly_and_writes_nothing(run_cli, campaign, tmp_path, label, change, message):
    path = edit(campaign, change)
    out, figs = tmp_path / "joint.h5", tmp_path / "figs"
    code, stdout, err = run_cli("identify", path, "--out", out, "--plots", figs)
    assert code == 2
    assert message in err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert not out.exists() and not figs.exists()


def test_mismatched_grid_fails_clearly(run_cli, campaign, tmp_path):
    v = read_frf_uff58(campaign / "validation.uff")
    write_uff58(campaign / "validation.uff", v.band(fmax=2000.0))
    code, _, err = run_cli("identify", campaign / "campaign.json", "--out", tmp_path / "j.h5")
    assert code == 2 and "validation.measurements" in err and "same" in err or "grid" in err
    assert not (tmp_path / "j.h5").exists()
    h = read_frf_uff58(campaign / "holder.uff")
    write_uff58(campaign / "holder.uff", h.band(fmax=3000.0))
    code, _, err = run_cli("identify", campaign / "campaign.json", "--out", tmp_path / "j.h5")
    assert code == 2 and "substructures.holder.uff58: holder.uff has 299 lines" in err


def test_dead_channel_fails_clearly(run_cli, campaign, tmp_path):
    m = read_frf_uff58(campaign / "assembly.uff")
    write_uff58(campaign / "assembly.uff", m.replace(values=np.zeros_like(m.values)))
    code, _, err = run_cli("identify", campaign / "campaign.json", "--out", tmp_path / "j.h5")
    assert code == 2, err
    assert "measured H(1x, 1x) is zero at every line" in err and "Traceback" not in err
    assert not (tmp_path / "j.h5").exists()


def test_fixture_generator_is_byte_reproducible(tmp_path, load_script):
    mc = load_script("fixtures/make_campaigns.py")
    assert mc.main(["--out", str(tmp_path)]) == 0
    for name in mc.DEFAULT_CAMPAIGNS:
        committed = sorted(p.name for p in (ROOT / "fixtures" / "campaigns" / name).iterdir())
        fresh = sorted(p.name for p in (tmp_path / name).iterdir())
        assert committed == fresh
        match, mismatch, errors = filecmp.cmpfiles(ROOT / "fixtures" / "campaigns" / name, tmp_path / name,
                                                   committed, shallow=False)
        assert mismatch == [] and errors == []
    # a campaign is a function of (joint, conditions, seed): another seed changes only the noisy files
    j = mc.joint_for_conditions(30.0, "steel")
    mc.make_planar_campaign(tmp_path / "other", j, {"torque_nm": 30.0, "materials": ["steel", "steel"]}, seed=12,
                            name="th-steel-30nm")
    same = filecmp.cmp(tmp_path / "other" / "holder.uff", tmp_path / "th-steel-30nm" / "holder.uff", shallow=False)
    differs = not filecmp.cmp(tmp_path / "other" / "assembly.uff", tmp_path / "th-steel-30nm" / "assembly.uff",
                              shallow=False)
    assert same and differs


def _write_campaign(d, data):
    (d / "campaign.json").write_text(json.dumps(data))
    return d / "campaign.json"


def test_n_point_campaign_through_the_cli(run_cli, tmp_path):
    from coupling_cases import TABLE_5_1_K, plate_frfs, plates

    freq = np.arange(20.0, 2000.0, 20.0)
    case = plates(freq)
    fa, fb, g = plate_frfs(freq, case)
    write_uff58(tmp_path / "a.uff", fa, binary=True)
    write_uff58(tmp_path / "b.uff", fb, binary=True)
    write_uff58(tmp_path / "g.uff", g, binary=True)
    path = _write_campaign(tmp_path, {
        "format": "jointdb-campaign/1", "name": "plates", "joint_model": "n-point",
        "substructures": {"A": {"uff58": "a.uff"}, "B": {"uff58": "b.uff"}},
        "interface": {"a": "A", "a_dofs": [f"{n}z" for n in case["a_bolts"]],
                      "b": "B", "b_dofs": [f"{n}z" for n in case["b_bolts"]]},
        "measurements": ["g.uff"], "n_point": {"internal": [f"{n}z" for n in case["internal"]]},
    })
    code, stdout, err = run_cli("identify", path, "--out", tmp_path / "j.h5", "--json")
    assert code == 0, err
    rep = json.loads(stdout)
    assert np.allclose([row["k"] for row in rep["constant_fit"]], TABLE_5_1_K, rtol=1e-6)
    code, stdout, err = run_cli("couple", path, "--joint", tmp_path / "j.h5", "--json")
    assert code == 0, err
    assert json.loads(stdout)["mean_relative_deviation_from_measurement"] < 1e-6


def test_matrix_campaign_through_the_cli(run_cli, tmp_path):
    from coupling_cases import blocks

    freq = np.arange(150.0, 3000.0, 30.0)
    b = blocks(freq)
    write_uff58(tmp_path / "a.uff", b["subs"]["A"], binary=True)
    write_uff58(tmp_path / "b.uff", b["subs"]["B"], binary=True)
    labels = [d for _, d in b["m15"]]
    write_uff58(tmp_path / "g.uff", b["G"].select(labels, labels), binary=True)
    path = _write_campaign(tmp_path, {
        "format": "jointdb-campaign/1", "name": "blocks", "joint_model": "matrix",
        "substructures": {"A": {"uff58": "a.uff"}, "B": {"uff58": "b.uff"}},
        "interface": {"a": "A", "a_dofs": [str(d) for d in b["a_dofs"]], "b": "B",
                      "b_dofs": [str(d) for d in b["b_dofs"]]},
        "measurements": ["g.uff"], "matrix": {"measured": [[n, str(d)] for n, d in b["m15"]]},
    })
    code, stdout, err = run_cli("identify", path, "--out", tmp_path / "j.h5", "--json",
                            "--plots", tmp_path / "figs")
    assert code == 0, err
    rep = json.loads(stdout)
    assert rep["joint_model"] == "matrix" and rep["residual_median"] < 1e-8
    joint = read_frf_hdf5(tmp_path / "j.h5")
    zt = np.linalg.inv(b["joint_true"].values)
    zi = np.linalg.inv(joint.values)
    assert np.median(np.linalg.norm(zi - zt, axis=(1, 2)) / np.linalg.norm(zt, axis=(1, 2))) < 1e-8
    code, stdout, err = run_cli("couple", path, "--joint", tmp_path / "j.h5", "--json")
    assert code == 0, err
    assert json.loads(stdout)["mean_relative_deviation_from_measurement"] < 1e-6
