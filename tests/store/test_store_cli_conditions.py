"""Issue 14, silent wrong numbers in `catalogue`: the conditions a joint file records are
kept, a contradicting option is refused without --force, unknown materials are refused
with the known list, and an identical re-catalogue writes nothing (and says so)."""

from __future__ import annotations

import json

import pytest
from store_helpers import spring_joint
from test_store_cli import run, run_json

from jointdb.errors import InputError, NotFoundError

@pytest.fixture
def joint_file(tmp_path):
    io = pytest.importorskip("jointdb.io")
    path = tmp_path / "joint.h5"
    io.write_frf_hdf5(path, spring_joint(), {
        "kind": "joint", "joint_model": "planar", "joint_type": "tool-holder",
        "conditions": {"materials": ["steel", "steel"], "torque_nm": 30.0},
    })
    return path


def test_recorded_conditions_are_kept_and_options_fill_in(joint_file, tmp_path):
    db = tmp_path / "j.sqlite"
    out = run_json("catalogue", joint_file, "--name", "T1", "--geometry", "shank_diameter_m=0.012", "--db", db)
    assert out["torque_nm"] == 30.0 and out["materials"] == "steel + steel"
    assert json.loads(out["geometry"]) == {"shank_diameter_m": 0.012}


@pytest.mark.parametrize("option, needle", [
    (("--torque", "40"), "torque_nm = 30 but --torque gives 40"),
    (("--material", "carbide"), "materials = steel+steel but --material gives tungsten-carbide"),
])
def test_contradicting_option_refused_without_force(joint_file, tmp_path, option, needle):
    db = tmp_path / "j.sqlite"
    r = run("catalogue", joint_file, "--name", "T1", *option, "--db", db, ok=False)
    assert isinstance(r.exception, InputError)
    assert needle in str(r.exception) and "--force" in str(r.exception)
    assert not db.exists()  # refused before the database is created
    out = run_json("catalogue", joint_file, "--name", "T1", *option, "--force", "--db", db)
    assert out["torque_nm"] == (40.0 if option[0] == "--torque" else 30.0)


def test_the_old_flag_spelling_is_gone(joint_file, tmp_path):
    r = run("catalogue", joint_file, "--name", "T1", "--override-conditions", "--db", tmp_path / "j.sqlite",
            ok=False)
    assert r.exit_code == 2


@pytest.mark.parametrize("where", ["catalogue", "query"])
def test_unknown_material_refused_with_known_list(joint_file, tmp_path, where):
    db = tmp_path / "j.sqlite"
    run("catalogue", joint_file, "--name", "T1", "--db", db)
    if where == "catalogue":
        args = ("catalogue", joint_file, "--name", "T2", "--material", "unobtainium", "--force")
    else:
        args = ("query", "--type", "tool-holder", "--material", "unobtainium")
    r = run(*args, "--db", db, ok=False)
    assert isinstance(r.exception, InputError)
    assert "unknown material 'unobtainium'; known: aluminium" in str(r.exception)
    assert "JOINTDB_MATERIALS" in str(r.exception)


def test_extension_mechanism_still_accepts_a_new_material(joint_file, tmp_path, monkeypatch):
    monkeypatch.setenv("JOINTDB_MATERIALS", "unobtainium")
    out = run_json("catalogue", joint_file, "--name", "T2", "--material", "unobtainium", "--force",
                   "--db", tmp_path / "j.sqlite")
    assert out["materials"] == "unobtainium"


def test_identical_recatalogue_writes_nothing_unless_asked(joint_file, tmp_path):
    db = tmp_path / "j.sqlite"
    assert run_json("catalogue", joint_file, "--name", "T1", "--db", db)["version"] == 1
    r = run("catalogue", joint_file, "--name", "T1", "--label", "released", "--db", db)
    assert "T1: identical to v1" in r.stderr and "nothing written" in r.stderr
    assert "--label not applied" in r.stderr
    hist = run_json("joints", "history", "T1", "--db", db)
    assert [h["version"] for h in hist if "version" in h] == [1]
    assert isinstance(run("joints", "show", "T1", "--label", "released", "--db", db, ok=False).exception, NotFoundError)
    # other conditions are not identical: a new version
    assert run_json("catalogue", joint_file, "--name", "T1", "--geometry", "d_m=0.012", "--db", db)["version"] == 2
    # asked explicitly: a new version even though identical to v2
    assert run_json("catalogue", joint_file, "--name", "T1", "--geometry", "d_m=0.012", "--allow-identical",
                    "--db", db)["version"] == 3


def test_campaign_with_unknown_material_is_refused_before_identifying(tmp_path):
    import shutil
    from pathlib import Path

    src = Path(__file__).resolve().parents[2] / "fixtures" / "campaigns" / "th-steel-30nm"
    shutil.copytree(src, tmp_path / "c")
    path = tmp_path / "c" / "campaign.json"
    data = json.loads(path.read_text())
    data["conditions"]["materials"] = ["steel", "unobtainium"]
    path.write_text(json.dumps(data))
    r = run("identify", path, "--out", tmp_path / "j.h5", ok=False)
    assert isinstance(r.exception, InputError)
    assert "conditions.materials[1]" in str(r.exception) and "known: aluminium" in str(r.exception)
    assert not (tmp_path / "j.h5").exists()
