"""CLI: ``jointdb campaign init`` → ``campaign check`` → ``identify`` → ``catalogue`` from a folder of UFF58 and
model files with no hand-written JSON, field-named errors of ``campaign check``, and ``jointdb rotations``."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
TH = ROOT / "fixtures" / "campaigns" / "th-steel-30nm"
CAT = ROOT / "jointdb" / "data" / "catalogue"


def run(*args, cwd=None):
    """``jointdb ARGS`` in a process of its own: the first test's whole session from a folder; the others run
    their commands in-process (the ``cli`` fixture of tests/conftest.py)."""
    return subprocess.run([sys.executable, "-m", "jointdb", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, stdin=subprocess.DEVNULL)


def test_init_check_identify_catalogue_from_a_folder_of_measurements_and_models(tmp_path):
    folder = tmp_path / "th-steel-30nm-bench"
    folder.mkdir()
    for name in ("assembly.uff", "holder.uff", "tool.json"):  # the user's files: measured, A with rotations, B
        shutil.copy(TH / name, folder / name)
    db = tmp_path / "joints.sqlite"

    init = run("campaign", "init", folder, "--type", "tool-holder", "--material", "steel", "--material", "carbide",
               "--torque", "30", "--smoothing", "21", "--fit-band", "100,4000")
    assert init.returncode == 0, init.stderr
    camp = folder / "campaign.json"
    assert init.stdout.strip() == str(camp)
    doc = json.loads(camp.read_text())
    # what was inferred from the files
    assert doc["measurements"] == ["assembly.uff"]
    assert doc["substructures"]["holder"] == {"uff58": "holder.uff", "dofs": ["3x", "3ry"]}
    assert doc["substructures"]["tool"] == {"model": "tool.json"}
    assert doc["interface"] == {"a": "holder", "a_dofs": ["3x", "3ry"], "b": "tool", "b_dofs": ["2x", "2ry"]}
    assert doc["planar"] == {"b_tip": 1} and doc["name"] == folder.name
    assert doc["conditions"] == {"materials": ["steel", "tungsten-carbide"], "torque_nm": 30.0}
    assert doc["options"] == {"smoothing": 21, "fit_band": [100.0, 4000.0]}

    check = run("campaign", "check", camp)
    assert check.returncode == 0, check.stderr
    assert "OK" in check.stderr and "H(1x, 2x)" in check.stderr

    joint = tmp_path / "joint.h5"
    ident = run("identify", camp, "--out", joint, "--json")
    assert ident.returncode == 0, ident.stderr
    cat = run("catalogue", camp, "--name", "bench-th-30", "--db", db, "--json")
    assert cat.returncode == 0, cat.stderr

    from jointdb.store import Repository

    truth = json.loads((TH / "truth.json").read_text())["joint"]
    with Repository(f"sqlite:///{db}") as repo:
        jv = repo.get("bench-th-30")
        assert jv.joint_type == "tool-holder" and jv.conditions.torque_nm == 30.0
        h = repo.load_frf(jv)
    # the catalogued joint is the true one (1 % noise, coarser models: the identification tests' tolerance)
    k = 1.0 / h.values[:, 0, 0].real
    band = (h.freq > 200) & (h.freq < 2000)
    assert np.median(k[band]) == pytest.approx(truth["kx"], rel=0.05)


def test_init_finds_a_modelled_spindle_as_substructure_a_for_a_holder_spindle_campaign(tmp_path, cli):
    folder = tmp_path / "hsk"
    folder.mkdir()
    shutil.copy(CAT / "campaigns" / "hs-hsk-a63-18kn" / "assembly.uff", folder / "g.uff")
    shutil.copy(CAT / "models" / "spindle-alone.json", folder / "spindle.json")
    shutil.copy(CAT / "models" / "hs-test-arbor-in-er32.json", folder / "arbor.json")
    init = cli("campaign", "init", folder, "--type", "holder-spindle", "--material", "steel", "--material", "steel",
               "--preload", "18000", "--geometry", "taper_diameter_m=0.063", "--extra", "taper=HSK-A63")
    assert init.returncode == 0, init.stderr
    doc = json.loads((folder / "campaign.json").read_text())
    assert doc["interface"] == {"a": "spindle", "a_dofs": ["5x", "5ry"], "b": "arbor", "b_dofs": ["4x", "4ry"]}
    assert doc["conditions"]["extra"] == {"taper": "HSK-A63"} and doc["conditions"]["preload_n"] == 18000.0
    check = cli("campaign", "check", folder / "campaign.json")
    assert check.returncode == 0, check.stderr


def test_init_without_the_joint_type_names_the_flag_and_writes_nothing(tmp_path, cli):
    folder = tmp_path / "f"
    folder.mkdir()
    for name in ("assembly.uff", "holder.uff", "tool.json"):
        shutil.copy(TH / name, folder / name)
    out = cli("campaign", "init", folder)
    assert out.returncode != 0 and "--type" in out.stderr and "Traceback" not in out.stderr
    out = cli("campaign", "init", folder, "--type", "tool-holder", "--smoothing", "20")
    assert out.returncode != 0 and "--smoothing" in out.stderr
    assert not (folder / "campaign.json").exists()
    (folder / "tool.json").unlink()
    out = cli("campaign", "init", folder, "--type", "tool-holder")
    assert out.returncode != 0 and "substructure B" in out.stderr and "Traceback" not in out.stderr


def test_check_names_the_field_that_is_wrong(tmp_path, cli):
    folder = tmp_path / "f"
    folder.mkdir()
    for name in ("assembly.uff", "holder.uff", "tool.json"):
        shutil.copy(TH / name, folder / name)
    assert cli("campaign", "init", folder, "--type", "tool-holder").returncode == 0
    camp = folder / "campaign.json"
    doc = json.loads(camp.read_text())
    doc["interface"]["b_dofs"] = ["7x", "7ry"]
    camp.write_text(json.dumps(doc))
    out = cli("campaign", "check", camp)
    assert out.returncode != 0 and "Traceback" not in out.stderr
    assert "interface.b_dofs" in out.stderr and "7x" in out.stderr
    doc["interface"]["b_dofs"] = ["2x", "2ry"]
    doc["planar"]["b_tip"] = 9
    camp.write_text(json.dumps(doc))
    out = cli("campaign", "check", camp)
    assert out.returncode != 0 and "measurements" in out.stderr and "b_tip" in out.stderr


def _rotation_rig(tmp_path):
    """A clamped holder-like beam A (contact point node 3 at its free end), a free cylinder E fixed to it, and
    A+E as one beam model: the "measured" G at E's two points, and A's true contact receptance."""
    from jointdb.fe import BeamModel, Clamp, HystereticDamping, NamedPoint, Segment, model_to_dict

    damp = (HystereticDamping(0.01),)
    a = BeamModel((Segment(0.10, 0.05),), points=(NamedPoint("c", 0.10, 3), NamedPoint("inner1", 0.09, 4),
                                                 NamedPoint("inner3", 0.07, 6)),
                  ingredients=(Clamp(0.0), *damp), max_element_length=0.005)
    e = BeamModel((Segment(0.08, 0.03),), points=(NamedPoint("base", 0.0, 10), NamedPoint("p1", 0.04, 11),
                                                 NamedPoint("p2", 0.08, 12)),
                  ingredients=damp, max_element_length=0.005)
    ae = BeamModel((Segment(0.10, 0.05), Segment(0.08, 0.03)),
                   points=(NamedPoint("p1", 0.14, 11), NamedPoint("p2", 0.18, 12)),
                   ingredients=(Clamp(0.0), *damp), max_element_length=0.005)
    freq = np.arange(20.0, 4000.0, 20.0)
    from jointdb.io import write_frf_hdf5

    write_frf_hdf5(tmp_path / "ext.h5", ae.frf(freq, ["p1", "p2"], directions=("x",)))
    (tmp_path / "ext.json").write_text(json.dumps(model_to_dict(e)))
    write_frf_hdf5(tmp_path / "fd.h5", a.frf(freq, ["c", "inner1", "inner3"], directions=("x",)))
    return a.frf(freq, ["c"])


def test_rotations_by_extension_recover_the_contact_receptance_and_report_noise_amplification(tmp_path, cli):
    from jointdb.usecases import read_frf_file

    truth = _rotation_rig(tmp_path)
    out = cli("rotations", tmp_path / "ext.h5", "--extension", tmp_path / "ext.json", "--joint-point", "base",
              "--points", "p1,p2", "--node", "3", "--out", tmp_path / "a.h5", "--json", "--trials", "8")
    assert out.returncode == 0, out.stderr
    got = read_frf_file(tmp_path / "a.h5")
    assert [str(d) for d in got.outputs] == ["3x", "3ry"]
    # same mesh for the "measurement" and the extension model: exact up to the conditioning of E (~1e3)
    np.testing.assert_allclose(got.values, truth.values, rtol=1e-6, atol=1e-9 * np.abs(truth.values).max())
    report = json.loads(out.stdout)
    amp = {r["entry"]: r for r in report["amplification"]}
    assert set(amp) == {"h", "n", "p"} and all(r["amplification_median"] > 0 for r in amp.values())
    assert report["condition_median"] > 1


def test_rotations_by_finite_difference_amplify_noise_more_when_the_points_are_closer(tmp_path, cli):
    _rotation_rig(tmp_path)
    amps = {}
    for inner, spacing in ((4, 0.01), (6, 0.03)):
        out = cli("rotations", tmp_path / "fd.h5", "--method", "finite-difference", "--node", "3", "--inner", inner,
                  "--spacing", spacing, "--out", tmp_path / f"fd{inner}.csv", "--json", "--trials", "8")
        assert out.returncode == 0, out.stderr
        amps[spacing] = {r["entry"]: r["amplification_median"] for r in json.loads(out.stdout)["amplification"]}
    # n = (h33 - h43)/s: the closer the points, the smaller the difference of two noisy numbers
    assert amps[0.01]["n"] > 2 * amps[0.03]["n"] > 2
    missing = cli("rotations", tmp_path / "fd.h5", "--method", "finite-difference", "--node", "3",
                  "--out", tmp_path / "x.csv")
    assert missing.returncode != 0 and "--inner" in missing.stderr and "Traceback" not in missing.stderr


def test_rotations_fill_reciprocity_completes_a_uff58_file_with_one_cross_entry(tmp_path, cli):
    """G11, G21, G22 measured (no G12): refused with a hint, then completed by --fill reciprocity; the result
    equals that of the full matrix."""
    from jointdb.frf import FRF
    from jointdb.io import read_frf_hdf5, write_uff58
    from jointdb.usecases import read_frf_file

    _rotation_rig(tmp_path)
    full = read_frf_hdf5(tmp_path / "ext.h5")
    parts = []
    for k, (o, i) in enumerate(((0, 0), (1, 0), (1, 1))):
        one = FRF(full.freq, full.values[:, o:o + 1, i:i + 1], [full.outputs[o]], [full.inputs[i]], full.quantity)
        write_uff58(tmp_path / f"part{k}.uff", one, binary=False, units_dataset=k == 0)
        parts.append((tmp_path / f"part{k}.uff").read_text())
    (tmp_path / "ext.uff").write_text("".join(parts))
    args = ("rotations", tmp_path / "ext.uff", "--extension", tmp_path / "ext.json", "--joint-point", "base",
            "--points", "p1,p2", "--node", "3", "--trials", "4")
    refused = cli(*args, "--out", tmp_path / "r.h5")
    assert refused.returncode != 0 and "--fill reciprocity" in refused.stderr and "Traceback" not in refused.stderr
    done = cli(*args, "--out", tmp_path / "a.h5", "--fill", "reciprocity")
    assert done.returncode == 0, done.stderr
    ref = cli("rotations", tmp_path / "ext.h5", "--extension", tmp_path / "ext.json", "--joint-point", "base",
              "--points", "p1,p2", "--node", "3", "--trials", "4", "--out", tmp_path / "b.h5")
    assert ref.returncode == 0, ref.stderr
    got, want = read_frf_file(tmp_path / "a.h5"), read_frf_file(tmp_path / "b.h5")
    # ASCII UFF58 keeps ~1e-10 of each value; the extension equations amplify it by their condition (~1e3)
    np.testing.assert_allclose(got.values, want.values, rtol=1e-6, atol=1e-9 * np.abs(want.values).max())
