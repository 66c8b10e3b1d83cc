"""``jointdb campaign init --spindle --holder --through-joint``: substructure A of a tool–holder campaign from
catalogued parts (docs/campaigns.md, *The chain from the command line*).

Known answer: receptance coupling of the holder (with the bonded shank stub) to the spindle through a rigid
joint equals the monolithic FE model of the same beams on the same mesh (fixtures/make_catalogue.py's
substructure A) to round-off. The chain through a catalogued joint against the truth is tests/test_campaign_walk.py.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
CAT = ROOT / "jointdb" / "data" / "catalogue"
CHAIN = ROOT / "fixtures" / "campaigns" / "th-chain-carbide-060nm"
PARTS = ["--spindle", "rig@1", "--holder", "er32@1", "--insertion", "0.035", "--shank-diameter", "0.012",
         "--shank-material", "carbide"]


def run(*args, cwd=None):
    """``jointdb ARGS`` in a process of its own (the module's set-up; the tests run the commands in-process,
    the ``cli`` fixture of tests/conftest.py)."""
    return subprocess.run([sys.executable, "-m", "jointdb", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, stdin=subprocess.DEVNULL)


@pytest.fixture(scope="module")
def _parts_db(tmp_path_factory):
    """A folder with a database holding a spindle (5 mm mesh, as the holder model's) and the demo holder, added
    once per module by `jointdb parts add` (the set-up of every test here, not its subject)."""
    d = tmp_path_factory.mktemp("parts-db")
    db = d / "j.sqlite"
    spindle = json.loads((CAT / "models" / "spindle-alone.json").read_text())
    spindle["max_element_length"] = 0.005
    (d / "spindle.json").write_text(json.dumps(spindle))
    r = run("parts", "add", "spindle", "rig", "--model", d / "spindle.json", "--point", "nose",
            "--machine", "rig", "--db", db)
    assert r.returncode == 0, r.stderr
    r = run("parts", "add", "holder", "er32", "--from-stack", CAT / "demo-stack.json", "--db", db)
    assert r.returncode == 0, r.stderr
    return d


@pytest.fixture
def setup(_parts_db, tmp_path):
    """A test's own copy of that database (file and blob store); a test folder."""
    shutil.copytree(_parts_db, tmp_path, dirs_exist_ok=True)
    db = tmp_path / "j.sqlite"
    folder = tmp_path / "th"
    folder.mkdir()
    shutil.copy(CHAIN / "assembly.uff", folder / "assembly.uff")
    shutil.copy(CAT / "models" / "test-tool-carbide.json", folder / "tool.json")
    return db, folder


def test_rigid_taper_gives_the_monolithic_holder_on_spindle(setup, load_script, cli):
    db, folder = setup
    r = cli("campaign", "init", folder, "--type", "tool-holder", "--torque", "60", "--through-joint", "rigid",
            *PARTS, "--db", db)
    assert r.returncode == 0, r.stderr
    doc = json.loads((folder / "campaign.json").read_text())
    a = doc["substructures"]["holder-on-spindle"]
    assert a["uff58"] == "holder-on-spindle.uff" and doc["interface"]["a_dofs"] == ["3x", "3ry"]
    assert {p["part"] for p in a["provenance"]["parts"]} == {"rig@1", "er32@1"}
    assert a["provenance"]["through_joint"]["joint"] == "rigid"
    from jointdb.io import read_frf_uff58
    from jointdb.stack import stack_from_dict

    got = read_frf_uff58(folder / "holder-on-spindle.uff")
    mc = load_script("fixtures/make_catalogue.py")
    spec = stack_from_dict(mc.test_stack("carbide"))  # the same holder, a Ø12 carbide shank 35 mm deep
    ref = mc.substructure_a(spec, 0.005).with_ingredient(mc.HystereticDamping(0.004))
    want = ref.frf(got.freq, ["nose"], directions=("x", "ry"))
    assert [str(d) for d in got.outputs] == ["3x", "3ry"]
    scale = np.abs(want.values).max(axis=0)
    assert np.max(np.abs(got.values - want.values) / scale) < 1e-8
    check = cli("campaign", "check", folder / "campaign.json")
    assert check.returncode == 0, check.stderr


@pytest.mark.parametrize("args, message", [
    (["--through-joint", "hs@1", *PARTS[:4]], "--insertion, --shank-diameter, --shank-material"),
    (["--through-joint", "nosuch@1", *PARTS], "nosuch"),
    (["--through-joint", "{bad json", *PARTS], "--through-joint: not valid JSON"),
    (["--through-joint", "hs-without-version", *PARTS], "NAME@VERSION"),
    (["--through-joint", "rigid", *PARTS[:-6], "--insertion", "0.035", "--shank-diameter", "0.02",
      "--shank-material", "carbide"], "bore"),
    (["--through-joint", "rigid", "--spindle", "er32@1", *PARTS[2:]], "spindle"),
    (["--through-joint", "rigid", *PARTS, "--fit-band", "4000,100"], "--fit-band"),
    (["--through-joint", "rigid", *PARTS, "--smoothing", "4"], "--smoothing"),
])
def test_refusals_name_the_option_and_write_nothing(setup, args, message, cli):
    db, folder = setup
    before = sorted(p.name for p in folder.iterdir())
    r = cli("campaign", "init", folder, "--type", "tool-holder", "--torque", "60", *args, "--db", db)
    assert r.returncode != 0 and message in r.stderr, r.stderr
    assert "Traceback" not in r.stderr
    assert sorted(p.name for p in folder.iterdir()) == before


def _a_file(run, folder: Path, db: Path, *args) -> tuple[np.ndarray, dict]:
    """Run init with ``args`` in a fresh copy of ``folder``; substructure A's receptance and provenance."""
    from jointdb.io import read_frf_uff58

    k = 0  # the first free name: counting the folder's entries is not, the database's -wal/-shm files come and go
    while (target := folder.parent / f"{folder.name}-{k}").exists():
        k += 1
    shutil.copytree(folder, target)
    r = run("campaign", "init", target, "--type", "tool-holder", "--torque", "60", *args, "--db", db)
    assert r.returncode == 0, r.stderr
    doc = json.loads((target / "campaign.json").read_text())
    return read_frf_uff58(target / "holder-on-spindle.uff").values, doc["substructures"]["holder-on-spindle"]


def test_a_measured_spindle_part_gives_the_same_a_as_its_model(setup, tmp_path, cli):
    """The spindle as a measured nose FRF set (here: its model's, written as a file) instead of a beam model."""
    db, folder = setup
    r = cli("frf", tmp_path / "spindle.json", "--points", "nose", "--directions", "x,ry", "--fmin", "10",
            "--fmax", "6000", "--df", "10", "--out", tmp_path / "nose.h5")
    assert r.returncode == 0, r.stderr
    r = cli("parts", "add", "spindle", "rig-measured", "--frf", tmp_path / "nose.h5", "--node", "5",
            "--machine", "rig", "--db", db)
    assert r.returncode == 0, r.stderr
    model, _ = _a_file(cli, folder, db, "--through-joint", "rigid", *PARTS)
    measured, prov = _a_file(cli, folder, db, "--through-joint", "rigid", "--spindle", "rig-measured@1", *PARTS[2:])
    assert {p["part"] for p in prov["provenance"]["parts"]} == {"rig-measured@1", "er32@1"}
    scale = np.abs(model).max(axis=0)
    assert np.max(np.abs(measured - model) / scale) < 1e-8


def test_a_queried_taper_joint_is_the_nearest_catalogued_one(setup, cli):
    """--through-joint as a JSON query: chosen as `jointdb predict` chooses, recorded with its method; on a
    catalogued condition it is that joint, so A equals A through the pinned version."""
    db, folder = setup
    for name in ("hs-hsk-a63-18kn", "hs-hsk-a63-24kn"):
        r = cli("catalogue", CAT / "campaigns" / name / "campaign.json", "--name", name, "--db", db)
        assert r.returncode == 0, r.stderr
    query = json.dumps({"joint_type": "holder-spindle", "materials": ["steel", "steel"], "preload_n": 18000,
                        "geometry": {"taper_diameter_m": 0.063}})
    pinned, _ = _a_file(cli, folder, db, "--through-joint", "hs-hsk-a63-18kn@1", *PARTS)
    queried, entry = _a_file(cli, folder, db, "--through-joint", query, *PARTS)
    tj = entry["provenance"]["through_joint"]
    assert tj["joint"] == "hs-hsk-a63-18kn@1" and tj["distance"] == pytest.approx(0.0, abs=1e-12)
    assert tj["method"] in ("nearest", "catalogued condition")
    assert [u["joint"] for u in tj["joints_used"]] == ["hs-hsk-a63-18kn@1"]
    np.testing.assert_allclose(queried, pinned, rtol=1e-12, atol=0)
    other, _ = _a_file(cli, folder, db, "--through-joint", "hs-hsk-a63-24kn@1", *PARTS)
    assert np.max(np.abs(other - pinned)) > 1e-3 * np.max(np.abs(pinned))  # the joint matters


def test_a_failed_forced_init_leaves_the_earlier_substructure_a_as_it_was(setup, cli):
    db, folder = setup
    r = cli("campaign", "init", folder, "--type", "tool-holder", "--torque", "60", "--through-joint", "rigid",
            *PARTS, "--db", db)
    assert r.returncode == 0, r.stderr
    a_before = (folder / "holder-on-spindle.uff").read_bytes()
    doc_before = (folder / "campaign.json").read_bytes()
    names = sorted(p.name for p in folder.iterdir())
    # a second, forced run that fails after A would have been rebuilt (the tool-holder type is refused late:
    # an unknown shank material), then one whose option check fails first
    for extra in (["--shank-material", "unobtainium"], ["--fit-band", "x"]):
        r = cli("campaign", "init", folder, "--type", "tool-holder", "--torque", "60", "--through-joint", "rigid",
                *PARTS, *extra, "--db", db, "--force")
        assert r.returncode != 0 and "Traceback" not in r.stderr, r.stderr
        assert sorted(p.name for p in folder.iterdir()) == names
        assert (folder / "holder-on-spindle.uff").read_bytes() == a_before
        assert (folder / "campaign.json").read_bytes() == doc_before


def test_a_tool_holder_campaign_records_the_clamped_shank_in_its_conditions(setup, cli):
    """`--insertion` and `--shank-diameter` become ``geometry.insertion_m`` / ``shank_diameter_m`` (the shank the
    joint carries, docs/stacks.md *The shank inside the holder*); a value given by `--geometry` is kept."""
    db, folder = setup
    r = cli("campaign", "init", folder, "--type", "tool-holder", "--torque", "60", "--through-joint", "rigid",
            "--geometry", "shank_diameter_m=0.0120", *PARTS, "--db", db)
    assert r.returncode == 0, r.stderr
    geometry = json.loads((folder / "campaign.json").read_text())["conditions"]["geometry"]
    assert geometry == {"shank_diameter_m": 0.012, "insertion_m": 0.035}
    assert "records the clamped shank: insertion_m=0.035" in r.stderr
    assert "shank_diameter_m=" not in r.stderr.split("records the clamped shank")[1].splitlines()[0]
