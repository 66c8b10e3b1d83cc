"""Hostile and damaged records (issue 20, item 1): nothing unreadable is committed, every read path
survives a row that is damaged anyway, listing is one SQL statement per page."""

from __future__ import annotations

import json
import re
import warnings

import pytest
from sqlalchemy import event
from store_helpers import alter_version_row, count_rows, nested_dict, run_main, spring_joint

from jointdb.errors import InputError, IntegrityError

KIND = "spring-damper-planar"


def _catalogue(repo, name, torque=40.0, **cond):
    cond = {"materials": ["tungsten-carbide", "steel"], "torque_nm": torque, **cond}
    return repo.catalogue(name, "tool-holder", spring_joint(), cond, KIND)


# ----------------------------------------------------------------------------- A: refused before the write
def test_nesting_300_is_refused_before_anything_is_committed(repo):
    _catalogue(repo, "T1")
    before = count_rows(repo)
    with pytest.raises(InputError, match=r"conditions\.extra: nested more than 64 levels"):
        _catalogue(repo, "T1", extra=nested_dict(300))
    assert count_rows(repo) == before
    assert [v.version for v in repo.history("T1")] == [1]
    assert [v.name for v in repo.list_joints()] == ["T1"]
    _catalogue(repo, "T2", extra=nested_dict(64))  # the limit itself is accepted and reads back
    assert repo.get("T2").conditions.extra == nested_dict(64)


def test_numbers_beyond_what_a_record_may_hold_are_refused_before_the_write(repo):
    """1e308 is a finite float, but beyond the 1e300 a stored record may hold: accepting it at the
    write made a version that every later read refused (found by tests/security)."""
    before = count_rows(repo)
    with pytest.raises(InputError, match=r"geometry\['diameter_m'\].*1e\+300"):
        _catalogue(repo, "BIG", geometry={"diameter_m": 1e308})
    with pytest.raises(InputError, match=r"torque_nm.*1e\+300"):
        _catalogue(repo, "BIG", torque=1e308)
    with pytest.raises(InputError, match=r"quality metric 'fit_error'.*1e\+300"):
        repo.catalogue("BIG", "tool-holder", spring_joint(), {"materials": ["steel"]}, KIND,
                       quality={"fit_error": 1e308})
    assert count_rows(repo) == before
    _catalogue(repo, "BIG", geometry={"diameter_m": 1e300})  # the limit itself reads back
    assert repo.get("BIG").conditions.geometry["diameter_m"] == 1e300


@pytest.mark.parametrize("field, value, message", [
    ("extra", {"k\x00": 1}, "control character U+0000"),
    ("extra", {"note": "a\x00b"}, "control character U+0000"),
    ("extra", {"note": "x" * 10_001}, "the limit is 10000"),
    ("extra", {"x": [0] * 100_001}, "the limit is 100000"),
    ("extra", {"x": ["y" * 9000] * 300}, "bytes encoded; the limit is"),
    ("extra", {"x": float("nan")}, "must be finite"),
    ("extra", {"x": 10 ** 400}, "must be finite"),
    ("extra", {"x": {1, 2}}, "must be JSON"),
    ("extra", [1, 2], "conditions.extra must be a JSON object"),
    ("materials", 7, "conditions.materials must be a list"),
])
def test_hostile_conditions_are_input_errors_naming_the_field(repo, field, value, message):
    before = count_rows(repo)
    with pytest.raises(InputError, match=re.escape(message)):
        repo.catalogue("T", "tool-holder", spring_joint(), {"materials": ["steel"], field: value}, KIND)
    assert count_rows(repo) == before


@pytest.mark.parametrize("kwargs, message", [
    ({"provenance": {"method": "irc\x00"}}, "provenance.method: holds the control character U+0000"),
    ({"provenance": {"method": "irc", "parameters": {"p": nested_dict(100)}}}, "provenance.parameters: nested"),
    ({"provenance": {"method": "irc", "bogus": 1}}, "unknown fields bogus"),
    ({"provenance": {"method": "irc", "input_files": {"a\x00": "0" * 64}}}, "input_files key"),
    ({"quality": {"fit\x00": 1.0}}, "quality metric name"),
    ({"author": "eve\x00"}, "author: holds the control character"),
])
def test_hostile_provenance_quality_author_are_refused(repo, kwargs, message):
    before = count_rows(repo)
    with pytest.raises(InputError, match=re.escape(message)):
        repo.catalogue("T", "tool-holder", spring_joint(), {"materials": ["steel"]}, KIND, **kwargs)
    assert count_rows(repo) == before


def test_deprecate_reason_and_lookups_refuse_control_characters(repo):
    _catalogue(repo, "T1")
    before = count_rows(repo)
    with pytest.raises(InputError, match="reason: holds the control character U\\+0000"):
        repo.deprecate("T1", 1, reason="bad\x00")
    assert count_rows(repo) == before
    with pytest.raises(InputError, match="label"):  # PostgreSQL would refuse the NUL with an internal error
        repo.get("T1", label="\x00")
    with pytest.raises(InputError, match="control characters"):
        repo.get("T\x00")
    with pytest.raises(InputError, match="control characters"):
        repo.list_page(name_contains="\x00")


# ----------------------------------------------------------------------------- B: damaged rows
def _damage(backend, repo, name: str) -> None:
    """Make the ``extra`` column of ``name`` v1 unreadable: garbage bytes in the SQLite file (a flipped
    byte), a value of the wrong shape on PostgreSQL (its json type refuses text that is not JSON)."""
    if backend.name == "sqlite":
        repo.close()  # checkpoints the WAL into the file
        path = backend.url.removeprefix("sqlite:///")
        data = open(path, "rb").read()
        marker = json.dumps({"marker": f"DAMAGE-{name}"}).encode()
        assert data.count(marker) == 1
        with open(path, "wb") as fh:
            fh.write(data.replace(marker, marker.replace(b":", b";")))
    else:
        alter_version_row(backend.url, "UPDATE joint_versions SET extra = '[\"not\", \"an\", \"object\"]' "
                                       f"WHERE joint_id = (SELECT id FROM joints WHERE name = '{name}')")


def test_a_damaged_row_is_named_and_the_rest_still_answers(backend, capsys):
    repo = backend.repo()
    for n in ("A", "B", "C"):
        _catalogue(repo, n, extra={"marker": f"DAMAGE-{n}"})
    _damage(backend, repo, "B")
    repo = backend.repo()
    try:
        page = repo.list_page()
        assert [v.name for v in page.items] == ["A", "C"]
        assert [(d.name, d.version) for d in page.damaged] == [("B", 1)]
        with pytest.raises(IntegrityError, match=r"^B v1: stored record is damaged"):
            repo.get("B")
        damaged: list = []
        assert repo.history("B", damaged=damaged) == [] and damaged[0].version == 1
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            found = repo.nearest("tool-holder", {"torque_nm": 40.0}, k=3)
        assert sorted(m.version.name for m in found) == ["A", "C"]
        assert any("B v1" in str(w.message) for w in caught)
        assert any("B v1" in p for p in repo.check().problems)
    finally:
        repo.close()
    for args, shown in ((("joints", "list"), "B v1"), (("joints", "show", "B"), "B v1"),
                        (("db", "check"), "B v1")):
        code, out, err = run_main(capsys, *args, "--db", backend.url, "--blobs", backend.blobs)
        assert code == 5, (args, out, err)
        assert "Traceback" not in err and shown in out + err
    code, out, _ = run_main(capsys, "joints", "list", "--db", backend.url, "--blobs", backend.blobs, "--json")
    assert code == 5 and {r["name"] for r in json.loads(out)} == {"A", "C"}


# ----------------------------------------------------------------------------- C: listing in SQL
def test_a_page_of_the_listing_is_a_constant_number_of_statements(repo):
    frf = spring_joint()
    for i in range(55):
        repo.catalogue(f"J{i:03d}", "tool-holder", frf, {"materials": ["steel"], "torque_nm": 10.0 + i}, KIND)
    repo.label("J010", 1, "released")
    statements: list[str] = []

    def count(conn, cursor, statement, *a):
        if not statement.lstrip().upper().startswith("BEGIN"):  # SQLite's own BEGIN of the read transaction
            statements.append(statement)

    event.listen(repo.read_engine, "before_cursor_execute", count)
    try:
        counts = {}
        for limit in (5, 50):
            statements.clear()
            page = repo.list_page(limit=limit)
            assert len(page.items) == limit and page.total == 55 and page.next
            counts[limit] = len(statements)
        assert counts[5] == counts[50] == 1, counts
        statements.clear()
        page = repo.list_page(limit=50, after=page.next)
        assert [v.name for v in page.items] == [f"J{i:03d}" for i in range(50, 55)] and page.next is None
        assert len(statements) == 1
        statements.clear()
        assert len(repo.list_joints()) == 55 and len(statements) == 1
    finally:
        event.remove(repo.read_engine, "before_cursor_execute", count)
    sel = repo.list_page(torque_min=20.0, torque_max=24.0, materials=["steel"], limit=50)
    assert [v.torque_nm if False else v.conditions.torque_nm for v in sel.items] == [20.0, 21.0, 22.0, 23.0, 24.0]
    assert [(v.name, v.labels) for v in repo.list_page(label="released").items] == [("J010", ("released",))]


def test_listing_shows_the_version_get_shows(repo):
    _catalogue(repo, "A")
    repo.catalogue("A", "tool-holder", spring_joint(k=(3e6, 8e4)), {"materials": ["tungsten-carbide", "steel"],
                                                                   "torque_nm": 40.0}, KIND)  # re-identified
    _catalogue(repo, "B")
    repo.deprecate("A", 2, reason="bad fit")
    _catalogue(repo, "C")
    repo.deprecate("C", None, reason="withdrawn")
    listed = {v.name: (v.version, v.state) for v in repo.list_joints()}
    assert listed == {n: (repo.get(n).version, repo.get(n).state) for n in "ABC"}
    assert listed == {"A": (1, "active"), "B": (1, "active"), "C": (1, "deprecated")}
    assert [v.name for v in repo.list_joints(include_deprecated=False)] == ["A", "B"]
    assert [v.name for v in repo.list_page(state="deprecated").items] == ["C"]


# ----------------------------------------------------------------------------- D: model files
def test_a_damping_type_that_is_not_text_is_a_field_named_error(tmp_path, capsys):
    from jointdb.fe import model_from_dict

    model = {"segments": [{"length": 0.1, "outer_diameter": 0.02}], "damping": [{"type": [1, 2], "zeta": 0.01}]}
    with pytest.raises(InputError, match=r"damping\[0\]\.type: must be one of"):
        model_from_dict(model)
    path = tmp_path / "m.json"
    path.write_text(json.dumps(model))
    code, _, err = run_main(capsys, "modes", path)
    assert code == 2 and "Traceback" not in err and "damping[0].type" in err


def test_a_corrupt_blob_is_named_by_its_version_not_its_path(tmp_path):
    from jointdb.store import Repository

    repo = Repository(tmp_path / "j.sqlite")
    jv = _catalogue(repo, "T1")
    path = repo.blobs.path(jv.blob_sha256)
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0x01
    path.chmod(0o644)
    path.write_bytes(bytes(data))
    with pytest.raises(IntegrityError, match=r"^T1 v1: its FRF blob [0-9a-f]{64} is corrupt") as caught:
        repo.load_frf(jv)
    assert str(tmp_path) not in str(caught.value)
    path.unlink()
    with pytest.raises(Exception, match=r"^T1 v1: its FRF blob [0-9a-f]{64} is missing") as caught:
        repo.load_frf(jv)
    assert str(tmp_path) not in str(caught.value)
    repo.close()


def test_a_row_an_older_version_wrote_beyond_todays_limits_is_reported_not_served(repo, monkeypatch):
    """Depth 300 was accepted before issue 20 (and then broke every list): read back, it is damaged."""
    from jointdb.schemas import _limits

    _catalogue(repo, "A")
    with monkeypatch.context() as m:
        m.setattr(_limits, "MAX_FIELD_DEPTH", 1000)  # as an older jointdb wrote it
        _catalogue(repo, "B", extra=nested_dict(300))
    page = repo.list_page()
    assert [v.name for v in page.items] == ["A"]
    assert [(d.name, d.version) for d in page.damaged] == [("B", 1)] and "nested more than 64" in page.damaged[0].reason
    with pytest.raises(IntegrityError, match="^B v1: stored record is damaged"):
        repo.get("B")


def test_gc_refuses_while_a_raw_blobs_column_is_unreadable(backend):
    """A version whose raw_blobs column cannot be read names blobs nobody can know: collecting
    "unreferenced" blobs then would delete its raw measurements. gc refuses and removes nothing."""
    repo = backend.repo()
    raw = spring_joint(k=(9e6, 9e5), dofs=("1x", "1ry"))
    jv = repo.catalogue("RAW", "tool-holder", spring_joint(), {"materials": ["steel"], "torque_nm": 40.0}, KIND,
                        raw_frfs={"tip": raw})
    digest = jv.raw_blobs["tip"]
    if backend.name == "sqlite":
        repo.close()
        path = backend.url.removeprefix("sqlite:///")
        data = open(path, "rb").read()
        stored = json.dumps({"tip": digest}).encode()
        assert data.count(stored) == 1
        with open(path, "wb") as fh:
            fh.write(data.replace(stored, stored.replace(b":", b";")))
    else:
        alter_version_row(backend.url, "UPDATE joint_versions SET raw_blobs = '[\"not\", \"an\", \"object\"]' "
                                       "WHERE joint_id = (SELECT id FROM joints WHERE name = 'RAW')")
    repo = backend.repo()
    try:
        with pytest.raises(IntegrityError, match=r"db gc refused: joint 'RAW' v1 has a damaged raw_blobs column"):
            repo.gc(min_age_s=0.0)
        assert digest in {b.sha256 for b in repo.blobs.walk()}  # the raw measurement is still there
    finally:
        repo.close()
