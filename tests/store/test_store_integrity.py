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


def test_an_frf_with_a_negative_zero_reads_back_bit_for_bit(repo):
    """A −0.0 part (an inverted diagonal joint has them off the diagonal) is catalogued and read back exactly: the
    reader built the complex values as ``re + 1j·im``, which turns −0.0 into +0.0, so the content no longer hashed
    to its name and the version could never be read ("corrupt")."""
    import numpy as np

    from jointdb.frf import FRF
    from jointdb.io._frfjson import frf_from_json, frf_json
    from jointdb.store import Conditions

    f = np.linspace(100.0, 1000.0, 10)
    h = np.zeros((f.size, 2, 2), complex)
    h[:, 0, 0], h[:, 1, 1] = 1e-7 - 1e-9j, 1e-5 - 1e-7j
    h[:, 0, 1] = complex(-0.0, 0.0)
    frf = FRF(f, h, ["3x", "3ry"], ["3x", "3ry"])
    v = repo.catalogue("negative-zero", "tool-holder", frf, Conditions(("steel",), torque_nm=60.0),
                       "spring-damper-planar")
    back = repo.load_frf(v)
    assert np.array_equal(back.values.view(np.uint64), frf.values.view(np.uint64))
    assert np.signbit(back.values[:, 0, 1].real).all()
    via_json = frf_from_json(frf_json(frf))
    assert np.signbit(via_json.values[:, 0, 1].real).all()
