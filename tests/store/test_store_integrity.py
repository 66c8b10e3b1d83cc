"""Reads verify the record hash: an altered or damaged row is refused (exit 5), never shown or ranked."""

from __future__ import annotations

import sqlite3

import pytest
from store_helpers import alter_version_row, assert_one_line_error, planar_conditions, run_cli, spring_joint

from jointdb.errors import IntegrityError
from jointdb.store import DamagedRecordWarning, Repository


def _two_joints(repo):
    repo.catalogue("T1", "tool-holder", spring_joint(), planar_conditions(torque=40.0), "spring-damper-planar")
    repo.catalogue("T2", "tool-holder", spring_joint(k=(3e6, 8e4)), planar_conditions(torque=80.0),
                   "spring-damper-planar")


def test_an_altered_row_is_refused_by_every_read(backend, tmp_path):
    repo = backend.repo()
    _two_joints(repo)
    alter_version_row(backend.url, "UPDATE joint_versions SET torque_nm = 999 WHERE version = 1 AND "
                                   "joint_id = (SELECT id FROM joints WHERE name = 'T1')")
    for read in (lambda: repo.get("T1"), lambda: repo.get("T1", 1), lambda: repo.load_frf("T1", 1),
                 lambda: repo.export(["T1"], tmp_path / "b.h5"), lambda: repo.diff("T1", 1, other="T2")):
        with pytest.raises(IntegrityError, match="T1 v1: stored record does not match its record hash"):
            read()
    # lists leave the altered version out and name it (issue 20: the rest of a list still answers)
    for read, rest in ((lambda: repo.history("T1"), []), (lambda: [v.name for v in repo.list_joints()], ["T2"]),
                       (lambda: [m.version.name for m in
                                 repo.nearest("tool-holder", planar_conditions(torque=999.0), k=2)], ["T2"])):
        with pytest.warns(DamagedRecordWarning, match="T1 v1: stored record does not match its record hash"):
            assert read() == rest
    assert repo.get("T2").conditions.torque_nm == 80.0  # an intact joint stays readable
    assert not (tmp_path / "b.h5").exists()
    env = {"JOINTDB_BLOBS": str(backend.blobs)}
    for args in (["joints", "show", "T1"], ["query", "--type", "tool-holder", "--torque", "999"],
                 ["joints", "history", "T1"], ["joints", "list"]):
        result = run_cli(*args, "--db", backend.url, env=env)
        assert_one_line_error(result, IntegrityError.exit_code, "record hash")
        assert "999" not in result[1]  # the altered version is never printed (lists show the rest)
    assert not repo.check().ok
    repo.close()


def test_a_flipped_byte_in_the_sqlite_file_is_refused_on_read(tmp_path):
    db = tmp_path / "f.sqlite"
    repo = Repository(db)
    _two_joints(repo)
    repo.close()  # the WAL is checkpointed into the file
    data = bytearray(db.read_bytes())
    at = data.find(b'"tungsten-carbide"')
    assert at > 0
    while at > 0:  # every copy (live rows and free pages): 'tungsten' -> 'tungsteo'; pages stay valid SQLite
        data[at + 5] ^= 0x01
        at = data.find(b'"tungsten-carbide"', at + 1)
    db.write_bytes(bytes(data))
    result = run_cli("joints", "show", "T1", "--db", db)
    assert_one_line_error(result, IntegrityError.exit_code, "record hash")
    result = run_cli("query", "--type", "tool-holder", "--torque", "40", "--material", "carbide+steel",
                     "--db", db)
    assert_one_line_error(result, IntegrityError.exit_code, "record hash")


def test_a_non_hex_blob_digest_is_never_used_in_a_path(tmp_path):
    from jointdb.store._records import record_dict, record_sha256

    db = tmp_path / "h.sqlite"
    repo = Repository(db)
    _two_joints(repo)
    repo.close()
    conn = sqlite3.connect(db)
    conn.execute("DROP TRIGGER joint_versions_no_update")
    conn.execute("UPDATE joint_versions SET blob_sha256 = '../../../../etc/passwd' WHERE id = 1")
    conn.commit()
    conn.close()
    repo = Repository(db)
    with repo._read() as s:  # make the row internally consistent: only the digest check is left
        from jointdb.store._models import JointRow, VersionRow

        row = s.get(VersionRow, 1)
        joint = s.get(JointRow, row.joint_id)
        digest = record_sha256(record_dict(joint.name, joint.joint_type, row))
    conn = sqlite3.connect(db)
    conn.execute("UPDATE joint_versions SET record_sha256 = ? WHERE id = 1", (digest,))
    conn.commit()
    conn.close()
    jv = repo.get("T1")
    with pytest.raises(IntegrityError, match="not a SHA-256 hex digest"):
        repo.load_frf(jv)
    report = repo.check()
    assert not report.ok and any("not a SHA-256 hex digest" in p for p in report.problems)
    repo.close()
