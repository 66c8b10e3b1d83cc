"""The storage commands: catalogue, joints ..., query, db ... (tables for people, --json for scripts)."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from store_helpers import reseal, spring_joint
from typer.testing import CliRunner

from jointdb.cli import app
from jointdb.errors import ConflictError, InputError, NotFoundError
from jointdb.store import head_revision, write_frf_file

runner = CliRunner()


def run(*args, ok=True):
    result = runner.invoke(app, [str(a) for a in args])
    if ok:
        assert result.exit_code == 0, (result.output, result.exception)
    return result


def run_json(*args):
    return json.loads(run(*args, "--json").stdout)


@pytest.fixture
def files(tmp_path):
    out = {}
    for torque, k in ((20, 2e6), (40, 3e6), (80, 5e6)):
        path = tmp_path / f"joint-{torque}.h5"
        write_frf_file(path, spring_joint(k=(k, 8e4)))
        out[torque] = path
    return out


@pytest.fixture
def db(backend, monkeypatch):
    monkeypatch.setenv("JOINTDB_BLOBS", str(backend.blobs))
    monkeypatch.setenv("JOINTDB_AUTHOR", "tester")
    return backend.url


def test_catalogue_query_and_joints_commands(db, files, tmp_path):
    for torque, path in files.items():
        out = run_json("catalogue", path, "--name", f"TH-{torque}", "--type", "tool-holder",
                       "--material", "carbide+steel", "--torque", torque, "--geometry", "diameter_m=0.02",
                       "--model-kind", "spring-damper-planar", "--quality", "residual=0.01", "--db", db)
        assert out["version"] == 1 and out["torque_nm"] == torque and out["author"] == "tester"
    again = run_json("catalogue", files[40], "--name", "TH-20", "--type", "tool-holder", "--material", "steel",
                     "--torque", 25, "--model-kind", "spring-damper-planar", "--label", "released", "--force", "--db", db)
    assert again["version"] == 2 and again["labels"] == "released"

    listed = run_json("joints", "list", "--db", db)
    assert [(r["name"], r["version"]) for r in listed] == [("TH-20", 2), ("TH-40", 1), ("TH-80", 1)]
    assert "TH-40" in run("joints", "list", "--db", db).stdout  # the table
    hist = run_json("joints", "history", "TH-20", "--db", db)
    assert [r["version"] for r in hist] == [1, 2]
    shown = run_json("joints", "show", "TH-20", "--version", "1", "--frf-out", tmp_path / "v1.h5", "--db", db)
    assert shown["torque_nm"] == 20
    from jointdb.io import read_frf_hdf5_full

    frf, meta = read_frf_hdf5_full(tmp_path / "v1.h5")  # the exchange file `jointdb couple --joint` reads
    assert frf.allclose(spring_joint(k=(2e6, 8e4)), rtol=0) and meta["joint_model"] == "planar"
    assert meta["catalogue"]["name"] == "TH-20" and meta["catalogue"]["version"] == 1
    assert run_json("joints", "show", "TH-20", "--label", "released", "--db", db)["version"] == 2
    d = run_json("joints", "diff", "TH-20", "1", "2", "--db", db)
    assert d["conditions"]["torque_nm"] == [20.0, 25.0] and d["max_relative_difference"] > 0.1
    assert "max_rel_diff" in run("joints", "diff", "TH-20", "1", "2", "--db", db).stdout
    assert run_json("joints", "label", "TH-20", "1", "released", "--db", db)["version"] == 1
    dep = run_json("joints", "deprecate", "TH-80", "--reason", "cracked", "--db", db)
    assert dep[0]["state"] == "deprecated"

    q = run_json("query", "--type", "tool-holder", "--torque", 35, "--material", "carbide+steel", "-k", 2,
                 "--interpolate", tmp_path / "interp.h5", "--db", db)
    assert [m["name"] for m in q["matches"]] == ["TH-40", "TH-20"]  # TH-80 is deprecated
    assert q["matches"][0]["d_torque_nm"] > 0 and q["interpolated"]["label"] == "interpolated"
    assert {n["name"] for n in q["interpolated"]["neighbours"]} == {"TH-40", "TH-20"}
    _, meta = read_frf_hdf5_full(tmp_path / "interp.h5")
    assert meta["interpolated"] is True and len(meta["neighbours"]) == 2 and meta["joint_model"] == "planar"
    table = run("query", "--type", "tool-holder", "--torque", 500, "--db", db)
    assert "outside the catalogued range" in table.stderr and "d_torque_nm" in table.stdout

    bundle = tmp_path / "lab.h5"
    exported = run_json("joints", "export", bundle, "TH-20", "TH-40", "--db", db)
    assert {k: exported[k] for k in ("bundle", "joints", "versions")} == {"bundle": str(bundle), "joints": 2,
                                                                          "versions": 3}
    other = tmp_path / "other.sqlite"
    imported = run_json("joints", "import", bundle, "--force", "--db", other, "--blobs", tmp_path / "other-blobs")
    assert imported["new_versions"] == 3
    check = run_json("db", "check", "--db", db)
    assert check["ok"] and check["versions_checked"] == 4
    assert run_json("db", "gc", "--dry-run", "--min-age", 0, "--db", db) == []
    audit = run_json("db", "audit", "--joint", "TH-20", "--db", db)
    assert [a["action"] for a in audit] == ["label", "label", "catalogue", "catalogue"]
    assert {a["actor"] for a in audit} == {"tester"}


def test_user_errors_are_refused_without_writing(db, files, tmp_path):
    base = ["catalogue", files[20], "--name", "X", "--type", "tool-holder", "--model-kind",
            "spring-damper-planar", "--db", db]
    r = run(*base, "--torque", "-5", ok=False)
    assert isinstance(r.exception, InputError) and "torque_nm" in str(r.exception)
    r = run(*base, "--material", "unobtainium", ok=False)
    assert isinstance(r.exception, InputError) and "JOINTDB_MATERIALS" in str(r.exception)
    r = run(*base[:-4], "--model-kind", "n-point-translational", "--db", db, ok=False)
    assert isinstance(r.exception, InputError) and "rotation" in str(r.exception)
    r = run(*base, "--geometry", "diameter", ok=False)
    assert isinstance(r.exception, InputError) and "key=value" in str(r.exception)
    nan = tmp_path / "nan.h5"
    write_frf_file(nan, spring_joint())
    import h5py

    with h5py.File(nan, "r+") as f:
        v = f["values"][...]
        v[3, 0, 0, 0] = np.nan
        f["values"][...] = v
    reseal(nan)
    r = run("catalogue", nan, "--name", "X", "--type", "tool-holder", "--model-kind", "spring-damper-planar",
            "--db", db, ok=False)
    assert isinstance(r.exception, InputError) and "NaN" in str(r.exception)
    assert run_json("joints", "list", "--db", db) == []
    r = run("joints", "show", "nope", "--db", db, ok=False)
    assert isinstance(r.exception, NotFoundError)
    run(*base)
    r = run("catalogue", files[20], "--name", "X", "--type", "holder-spindle", "--model-kind",
            "spring-damper-planar", "--db", db, ok=False)
    assert isinstance(r.exception, ConflictError)


def test_exchange_file_from_identify_is_read_with_its_metadata(db, tmp_path):
    io = pytest.importorskip("jointdb.io")
    path = tmp_path / "joint.h5"
    io.write_frf_hdf5(path, spring_joint(), {
        "kind": "joint", "joint_model": "planar", "joint_type": "tool-holder",
        "conditions": {"materials": ["steel", "carbide"], "torque_nm": 30.0, "geometry": {"d_m": 0.012}},
        "quality": {"residual_rel": 0.002, "passive_fraction": 1.0, "notes": "text is skipped",
                    "cond": {"max": 12.5}},
        "settings": {"smoothing": 21},
    })
    r = run("catalogue", path, "--name", "TH-id", "--torque", 35, "--db", db, ok=False)
    assert isinstance(r.exception, InputError)  # the option contradicts the file: refused, naming both values
    assert "torque_nm = 30 but --torque gives 35" in str(r.exception) and "--force" in str(r.exception)
    assert run_json("joints", "list", "--db", db) == []
    out = run_json("catalogue", path, "--name", "TH-id", "--torque", 35, "--force", "--db", db)
    assert out["joint_type"] == "tool-holder" and out["model_kind"] == "spring-damper-planar"
    assert out["torque_nm"] == 35.0  # the option overrides the file when asked
    assert out["materials"] == "steel + tungsten-carbide" and json.loads(out["geometry"]) == {"d_m": 0.012}
    assert json.loads(out["quality"]) == {"cond.max": 12.5, "passive_fraction": 1.0, "residual_rel": 0.002}
    assert out["method"] == "irc-planar" and json.loads(out["parameters"]) == {"settings": {"smoothing": 21}}
    assert list(json.loads(out["input_files"])) == ["joint.h5"]


def test_db_upgrade_downgrade_commands(tmp_path):
    url = tmp_path / "m.sqlite"
    assert run_json("db", "upgrade", "--db", url)["revision"] == head_revision()
    from jointdb.store._db import _script

    below_head = _script().get_revision(head_revision()).down_revision
    assert run_json("db", "downgrade", "--yes", "--db", url)["revision"] == below_head
    r = run("db", "downgrade", "--to", "base", "--db", url, ok=False)
    assert isinstance(r.exception, InputError) and "--yes" in str(r.exception)
    assert run_json("db", "downgrade", "--to", "base", "--yes", "--db", url)["revision"] is None
    assert run_json("db", "upgrade", "--db", url)["revision"] == head_revision()
    info = run_json("db", "info", "--db", url)
    assert info["revision"] == info["head"] == head_revision()


def test_exit_codes_and_one_line_errors(tmp_path):
    """Through the real entry point: exit code of the error class, one stderr line, no traceback."""
    jointdb = [sys.executable, "-c", "from jointdb.cli import main; main()"]
    db = str(tmp_path / "e.sqlite")
    store_blobs = tmp_path / "e.sqlite.blobs"
    write_frf_file(tmp_path / "j.h5", spring_joint())
    subprocess.run(jointdb + ["catalogue", str(tmp_path / "j.h5"), "--name", "A", "--type", "tool-holder",
                              "--model-kind", "spring-damper-planar", "--db", db], check=True, capture_output=True)
    out = subprocess.run(jointdb + ["joints", "show", "missing", "--db", db], capture_output=True, text=True)
    assert out.returncode == NotFoundError.exit_code
    assert out.stderr.strip().splitlines() == ["error: no joint named 'missing' (see `jointdb joints list`)"]
    blob = next(store_blobs.glob("*/*.h5"))
    data = bytearray(blob.read_bytes())
    data[len(data) // 2] ^= 0xFF
    blob.write_bytes(bytes(data))
    out = subprocess.run(jointdb + ["db", "check", "--db", db], capture_output=True, text=True)
    assert out.returncode == 5 and "problem: A v1" in out.stderr and "Traceback" not in out.stderr


def test_catalogue_straight_from_a_campaign(tmp_path):
    """`jointdb catalogue campaign.json`: identify, then store with input hashes and raw measurements."""
    from pathlib import Path

    campaign = Path(__file__).resolve().parents[2] / "fixtures" / "campaigns" / "th-steel-30nm" / "campaign.json"
    if not campaign.is_file():
        pytest.skip(f"campaign fixture {campaign} is not present")
    db = tmp_path / "c.sqlite"
    out = run_json("catalogue", campaign, "--name", "th-camp", "--db", db)
    assert out["joint_type"] == "tool-holder" and out["model_kind"] == "spring-damper-planar"
    files = json.loads(out["input_files"])
    assert "campaign.json" in files and any(name.endswith(".uff") for name in files)
    assert "validation.identified_joint_error_mean" in json.loads(out["quality"])
    from jointdb.store import Repository

    repo = Repository(db)
    jv = repo.get("th-camp")
    assert set(jv.raw_blobs) == {"measured"} and repo.load_raw(jv, "measured").n_freq > 0
    assert repo.check().ok


def test_db_path_in_a_missing_directory_is_refused_not_created(tmp_path):
    target = tmp_path / "nodir" / "x.sqlite"
    write_frf_file(tmp_path / "j.h5", spring_joint())
    r = run("catalogue", tmp_path / "j.h5", "--name", "A", "--type", "tool-holder",
            "--model-kind", "spring-damper-planar", "--db", target, ok=False)
    assert r.exit_code != 0 and isinstance(r.exception, InputError) and "does not exist" in str(r.exception)
    assert not target.parent.exists()


def test_reading_commands_do_not_create_a_mistyped_database(tmp_path):
    target = tmp_path / "typo.sqlite"
    for args in (["joints", "list"], ["query", "--type", "tool-holder", "--torque", "3"], ["db", "check"]):
        r = run(*args, "--db", target, ok=False)
        assert isinstance(r.exception, NotFoundError) and "does not exist" in str(r.exception), args
    assert not target.exists()
