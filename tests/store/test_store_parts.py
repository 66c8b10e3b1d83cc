"""Parts of stacks as versioned records (issue 21, item 2): spindles, holders and tools catalogued with the
joints' guarantees — immutable versions, labels, provenance, verification on read, the history chain —
on SQLite and PostgreSQL, and a stack assembled from them predicts exactly what the same stack inline does."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import sqlalchemy as sa
from store_helpers import alter_version_row, refused_statements, reseal

from jointdb.errors import ConflictError, InputError, IntegrityError, NotFoundError

ROOT = Path(__file__).resolve().parents[2]
DEMO_STACK = ROOT / "jointdb" / "data" / "catalogue" / "demo-stack.json"
EXPLICIT = {"tool-holder": {"k": [8e7, 6e5], "c": [120.0, 4.0]}, "holder-spindle": {"k": [3e8, 2e6], "c": [300.0, 9.0]}}


def demo_doc() -> dict:
    doc = json.loads(DEMO_STACK.read_text())
    doc["interfaces"] = json.loads(json.dumps(EXPLICIT))  # no joint database needed for the comparison
    doc["frequency"] = {"min": 50.0, "max": 3000.0, "step": 25.0}
    return doc


def nose_frf(doc: dict, node: int = 7):
    """The modelled spindle's nose receptances (x, y, rx, ry) at ``node``: a 'measured' FRF set."""
    from jointdb.fe import model_from_dict
    from jointdb.frf import Dof

    model = model_from_dict(doc["spindle"]["model"])
    f = np.arange(50.0, 3000.0 + 1e-9, 25.0)
    frf = model.frf(f, ["nose"], directions=("x", "y", "rx", "ry"))
    return frf.replace(outputs=tuple(Dof(node, d.direction) for d in frf.outputs),
                       inputs=tuple(Dof(node, d.direction) for d in frf.inputs))


def add_demo_parts(repo, doc: dict) -> None:
    repo.add_part("em12", "tool", doc["tool"], attributes={"description": "12 mm 4-flute carbide end mill"})
    repo.add_part("er32-hsk63", "holder", doc["holder"],
                  attributes={"family": "ER32", "taper": "HSK-A63", "bore_mm": 12})
    repo.add_part("mill-spindle", "spindle", doc["spindle"], attributes={"machine": "demo-mill"}, label="released")


def test_round_trip_labels_history_and_identical_content(repo):
    doc = demo_doc()
    add_demo_parts(repo, doc)
    holder = repo.get_part("er32-hsk63")
    assert (holder.kind, holder.version, holder.payload) == ("holder", 1, doc["holder"])
    assert holder.attributes == {"family": "ER32", "taper": "HSK-A63", "bore_mm": 12.0}
    assert holder.provenance["software_version"] and holder.provenance["parent_version"] is None
    assert repo.get_part("mill-spindle", label="released").payload == doc["spindle"]
    # identical content: nothing written, the same version back
    assert repo.add_part("er32-hsk63", "holder", doc["holder"],
                         attributes={"family": "ER32", "taper": "HSK-A63", "bore_mm": 12}).uuid == holder.uuid
    longer = json.loads(json.dumps(doc["holder"]))
    longer["segments"][1]["length"] = 0.04
    v2 = repo.add_part("er32-hsk63", "holder", longer, attributes={"family": "ER32", "taper": "HSK-A63"})
    assert (v2.version, v2.parent_version, v2.payload["segments"][1]["length"]) == (2, 1, 0.04)
    assert [p.version for p in repo.part_history("er32-hsk63")] == [1, 2]
    assert repo.get_part("er32-hsk63", 1).payload == doc["holder"]  # the old version is unchanged
    repo.label_part("er32-hsk63", 1, "released")
    assert repo.resolve_part("er32-hsk63@released").version == 1
    repo.label_part("er32-hsk63", 2, "released")  # a label moves
    assert repo.resolve_part("er32-hsk63@released").version == 2
    assert {p.name: p.version for p in repo.list_parts()} == {"em12": 1, "er32-hsk63": 2, "mill-spindle": 1}
    assert [p.name for p in repo.list_parts("holder", family="ER32")] == ["er32-hsk63"]
    assert [p.name for p in repo.list_parts(machine="demo-mill")] == ["mill-spindle"]
    assert repo.list_parts("tool", family="ER32") == []
    actions = [a["action"] for a in repo.audit(limit=20)]
    assert actions.count("part-add") == 4 and actions.count("part-label") == 3
    report = repo.check()
    assert report.ok, report.problems  # the history chain covers the part rows


def test_refusals_name_the_field(repo):
    doc = demo_doc()
    with pytest.raises(InputError, match="machine"):
        repo.add_part("s", "spindle", doc["spindle"])
    with pytest.raises(InputError, match="segments"):
        repo.add_part("h", "holder", {"material": "steel", "segments": []})
    with pytest.raises(InputError, match="file paths"):
        repo.add_part("s", "spindle", {"model": "/etc/passwd", "point": "nose"}, attributes={"machine": "m"})
    with pytest.raises(InputError, match="no point"):
        repo.add_part("s", "spindle", {**doc["spindle"], "point": "tail"}, attributes={"machine": "m"})
    with pytest.raises(InputError, match="part name"):
        repo.add_part("a@1", "tool", doc["tool"])
    with pytest.raises(InputError, match="a tool has no family"):
        repo.add_part("t", "tool", doc["tool"], attributes={"family": "ER32"})
    nested: dict = {}
    cur = nested
    for _ in range(80):
        cur["a"] = {}
        cur = cur["a"]
    with pytest.raises(InputError, match="nested"):
        repo.add_part("t", "tool", {**doc["tool"], "x": nested})
    repo.add_part("t", "tool", doc["tool"])
    with pytest.raises(ConflictError, match="is a tool"):
        repo.add_part("t", "holder", doc["holder"])
    with pytest.raises(NotFoundError):
        repo.get_part("t", 2)
    with pytest.raises(NotFoundError):
        repo.resolve_part("t@released")
    with pytest.raises(NotFoundError):
        repo.get_part("nope")
    assert [p.name for p in repo.list_parts()] == ["t"]  # nothing else was written


def test_database_refuses_update_and_delete_of_part_history(repo):
    add_demo_parts(repo, demo_doc())
    engine = sa.create_engine(repo.url)
    try:
        for sql in ("UPDATE part_versions SET author = 'mallory'", "DELETE FROM part_versions",
                    "UPDATE parts SET name = 'x'", "DELETE FROM parts"):
            with pytest.raises(sa.exc.DBAPIError, match="immutable"):
                with engine.begin() as conn:
                    conn.exec_driver_sql(sql)
    finally:
        engine.dispose()
    assert repo.get_part("mill-spindle").author != "mallory"


def test_a_rewritten_record_is_refused_on_read_and_reported(backend):
    repo = backend.repo()
    try:
        add_demo_parts(repo, demo_doc())
        alter_version_row(backend.url, "UPDATE part_versions SET attributes = "
                                       "'{\"family\": \"ER40\", \"bore_mm\": 16.0}' WHERE family = 'ER32'",
                          table="part_versions")
        with pytest.raises(IntegrityError, match="er32-hsk63 v1.*does not match its hash"):
            repo.get_part("er32-hsk63", 1)
        with pytest.raises(IntegrityError):
            repo.list_parts()
        problems = "\n".join(repo.check(verify_blobs=False).problems)
        assert "part er32-hsk63 v1: record hash mismatch" in problems
        assert "part_version row" in problems and "rewritten" in problems  # the history chain sees it too
    finally:
        repo.close()


def test_measured_spindle_blob_is_verified_on_read(repo):
    frf = nose_frf(demo_doc())
    part = repo.add_part("ms", "spindle", {"node": 7}, frf=frf, attributes={"machine": "m1"})
    assert part.blob_sha256 and part.payload == {"node": 7}
    back = repo.load_part_frf(part)
    assert np.array_equal(back.values, frf.values) and np.array_equal(back.freq, frf.freq)
    assert repo.check().ok
    assert repo.gc(min_age_s=0.0) == []  # the part's blob is referenced: never collected
    import os

    import h5py

    path = repo.blobs.path(part.blob_sha256)
    os.chmod(path, 0o644)
    with h5py.File(path, "r+") as f:  # one value rewritten through HDF5 (its chunk checksums recomputed) ...
        v = f["values"][...]
        v[10, 0, 0, 0] *= 1.0000001
        f["values"][...] = v
    reseal(path)  # ... and the file's own whole-file checksum forged too: the content hash still catches it
    with pytest.raises(IntegrityError, match="ms v1: its FRF blob .* corrupt"):
        repo.load_part_frf(repo.get_part("ms"))
    assert any("part ms v1" in p for p in repo.check().problems)


def test_measured_spindle_needs_its_dofs(repo):
    frf = nose_frf(demo_doc()).select(outputs=["7x", "7y"], inputs=["7x", "7y"])
    with pytest.raises(InputError, match="7ry"):
        repo.add_part("ms", "spindle", {"node": 7}, frf=frf, attributes={"machine": "m1"})
    with pytest.raises(InputError, match="only a measured spindle"):
        repo.add_part("t", "tool", demo_doc()["tool"], frf=nose_frf(demo_doc()))


def test_stack_from_parts_predicts_the_same_tip_frf_as_inline(repo):
    from jointdb import usecases

    doc = demo_doc()
    add_demo_parts(repo, doc)
    by_ref = {**doc, "tool": {"part": "em12@1"}, "holder": {"part": "er32-hsk63@1"},
              "spindle": {"part": "mill-spindle@released"}}
    spec_ref = usecases.stack_from_document(by_ref, repo)
    spec_inline = usecases.stack_from_document(doc, repo)
    a = usecases.predict_stack(spec_ref, repo).prediction
    b = usecases.predict_stack(spec_inline, repo).prediction
    assert np.array_equal(a.tip.values, b.tip.values) and np.array_equal(a.rigid.values, b.rigid.values)
    assert [(p["slot"], p["part"]) for p in spec_ref.parts] == [
        ("tool", "em12@1"), ("holder", "er32-hsk63@1"), ("spindle", "mill-spindle@1")]
    assert spec_ref.parts[2]["ref"] == "mill-spindle@released"
    assert spec_ref.parts[1]["record_sha256"] == repo.get_part("er32-hsk63", 1).record_sha256
    assert spec_inline.parts == ()
    with pytest.raises(InputError, match="tool.part: er32-hsk63@1 is a holder, not a tool"):
        usecases.stack_from_document({**doc, "tool": {"part": "er32-hsk63@1"}}, repo)
    with pytest.raises(InputError, match="alone"):
        usecases.stack_from_document({**doc, "tool": {"part": "em12@1", "material": "steel"}}, repo)


def test_stack_with_a_measured_spindle_part_predicts_as_the_file(repo, tmp_path):
    from jointdb import usecases
    from jointdb.usecases import write_frf_file

    doc = demo_doc()
    frf = nose_frf(doc)
    write_frf_file(tmp_path / "nose.h5", frf)
    inline = {**doc, "spindle": {"file": "nose.h5", "node": 7}}
    (tmp_path / "inline.json").write_text(json.dumps(inline))
    repo.add_part("ms", "spindle", {"node": 7}, frf=frf, attributes={"machine": "m1"})
    (tmp_path / "ref.json").write_text(json.dumps({**doc, "spindle": {"part": "ms@1"}}))
    a = usecases.predict_stack(usecases.load_stack(tmp_path / "ref.json", repo), repo).prediction
    b = usecases.predict_stack(usecases.load_stack(tmp_path / "inline.json"), repo).prediction
    assert np.array_equal(a.tip.values, b.tip.values)
    # the measured spindle gives (nearly) what its model gives: the FRF set is the model's own receptance
    c = usecases.predict_stack(usecases.stack_from_document(doc, repo), repo).prediction
    assert np.allclose(a.tip.values, c.tip.values, rtol=1e-9, atol=1e-15)


def test_cli_parts_add_list_show_label_and_predict(tmp_path, run_cli):
    """The parts commands through the console entry point, in this process (``run_cli`` of tests/conftest.py)."""
    db = tmp_path / "j.sqlite"
    stack = DEMO_STACK
    rc, out, err = run_cli("parts", "add", "holder", "er32-hsk63", "--from-stack", stack, "--family", "ER32",
                           "--taper", "HSK-A63", "--bore-mm", "12", "--db", db, "--json")
    assert rc == 0, err
    assert json.loads(out)["attributes"]["bore_mm"] == 12.0 and "catalogued er32-hsk63@1" in err
    assert json.loads(out)["provenance"]["input_files"]["demo-stack.json"]
    for args in (("tool", "em12", "--from-stack", stack),
                 ("spindle", "mill-spindle", "--from-stack", stack, "--machine", "demo-mill")):
        rc, out, err = run_cli("parts", "add", *args, "--db", db)
        assert rc == 0, err
    rc, out, err = run_cli("parts", "add", "holder", "er32-hsk63", "--from-stack", stack, "--family", "ER32",
                           "--taper", "HSK-A63", "--bore-mm", "12", "--db", db)
    assert rc == 0 and "identical to er32-hsk63@1" in err
    rc, out, err = run_cli("parts", "label", "er32-hsk63@1", "released", "--db", db)
    assert rc == 0 and "released -> er32-hsk63@1" in err
    rc, out, err = run_cli("parts", "list", "--kind", "holder", "--db", db, "--json")
    assert rc == 0 and [(p["name"], p["labels"]) for p in json.loads(out)] == [("er32-hsk63", ["released"])]
    rc, out, err = run_cli("parts", "show", "mill-spindle@1", "--db", db, "--json")
    assert rc == 0 and json.loads(out)["payload"]["point"] == "nose"
    rc, out, err = run_cli("parts", "add", "spindle", "s2", "--from-stack", stack, "--db", db)
    assert rc == InputError.exit_code
    assert err.startswith("error: attributes.machine") and "Traceback" not in err
    doc = demo_doc()
    by_ref = {**doc, "tool": {"part": "em12@1"}, "holder": {"part": "er32-hsk63@released"},
              "spindle": {"part": "mill-spindle@1"}}
    (tmp_path / "ref.json").write_text(json.dumps(by_ref))
    (tmp_path / "inline.json").write_text(json.dumps(doc))
    rc, out_ref, err = run_cli("predict", tmp_path / "ref.json", "--db", db, "--json", "--out", tmp_path / "a.h5")
    assert rc == 0, err
    assert "holder: part er32-hsk63@1 (er32-hsk63@released)" in err
    rc, out_inline, err = run_cli("predict", tmp_path / "inline.json", "--db", db, "--json", "--out",
                                  tmp_path / "b.h5")
    assert rc == 0, err
    assert [p["part"] for p in json.loads(out_ref)["parts"]] == ["em12@1", "er32-hsk63@1", "mill-spindle@1"]
    from jointdb.io import read_frf_hdf5

    assert np.array_equal(read_frf_hdf5(tmp_path / "a.h5").values, read_frf_hdf5(tmp_path / "b.h5").values)
    rc, _, err = run_cli("predict", tmp_path / "ref.json", "--db", tmp_path / "missing.sqlite")
    assert rc != 0 and "does not exist" in err and not (tmp_path / "missing.sqlite").exists()


def test_app_role_appends_parts_but_cannot_rewrite_them(two_roles):
    from jointdb.store import Repository

    repo = Repository(two_roles.app_url, blobs=two_roles.blobs, auto_create=False)
    try:
        doc = demo_doc()
        add_demo_parts(repo, doc)
        repo.add_part("ms", "spindle", {"node": 7}, frf=nose_frf(doc), attributes={"machine": "m1"})
        repo.label_part("er32-hsk63", 1, "default")
        assert repo.check(verify_blobs=True).ok
    finally:
        repo.close()
    assert refused_statements(two_roles.app_url, [
        "UPDATE parts SET name = 'x'", "DELETE FROM parts", "TRUNCATE parts",
        "UPDATE part_versions SET author = 'x'", "DELETE FROM part_versions", "TRUNCATE part_versions",
        "ALTER TABLE part_versions DISABLE TRIGGER ALL", "DROP TABLE part_versions",
        "UPDATE part_labels SET part_id = part_id", "DELETE FROM part_labels", "TRUNCATE part_labels"]) == []


from test_store_roles import two_roles  # noqa: E402,F401  (the two-role PostgreSQL fixture)


def test_downgrade_below_0009_is_refused_while_parts_exist(tmp_path, run_cli):
    db = tmp_path / "d.sqlite"
    from jointdb.store import Repository

    with Repository(db) as repo:
        repo.add_part("em12", "tool", demo_doc()["tool"])
    rc, out, err = run_cli("db", "downgrade", "--to", "0008", "--yes", "--db", db)
    assert rc == InputError.exit_code and "holds catalogued parts" in err and "Traceback" not in err
    with Repository(db) as repo:  # nothing was dropped
        assert repo.get_part("em12").version == 1 and repo.check().ok
    empty = tmp_path / "e.sqlite"
    Repository(empty).close()
    rc, out, err = run_cli("db", "downgrade", "--to", "0008", "--yes", "--db", empty)
    assert rc == 0, err
    rc, out, err = run_cli("db", "upgrade", "--db", empty)
    assert rc == 0, err


def test_a_stack_naming_parts_never_creates_a_database(tmp_path):
    from jointdb import usecases

    missing = tmp_path / "none.sqlite"
    with pytest.raises(NotFoundError, match="does not exist"):
        usecases.stack_from_document({**demo_doc(), "tool": {"part": "em12@1"}}, missing)
    assert not missing.exists()
    assert usecases.stack_from_document(demo_doc(), missing).parts == ()  # no reference: no database opened


def test_concurrent_writers_number_part_versions_without_gaps(backend):
    from concurrent.futures import ThreadPoolExecutor

    doc = demo_doc()

    def write(worker: int) -> list[int]:
        repo = backend.repo()
        try:
            out = []
            for i in range(3):
                holder = json.loads(json.dumps(doc["holder"]))
                holder["loss_factor"] = 0.001 * (1 + worker * 3 + i)  # distinct content: a new version each
                out.append(repo.add_part("shared-holder", "holder", holder, author=f"w{worker}").version)
            return out
        finally:
            repo.close()

    with ThreadPoolExecutor(4) as pool:
        numbers = sorted(n for got in pool.map(write, range(4)) for n in got)
    assert numbers == list(range(1, 13))
    repo = backend.repo()
    try:
        assert [p.version for p in repo.part_history("shared-holder")] == list(range(1, 13))
        assert repo.check(verify_blobs=False).ok  # one chain entry per row, in commit order
    finally:
        repo.close()
