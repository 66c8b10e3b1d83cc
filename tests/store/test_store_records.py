"""Versioned records: numbering, immutability, pinning, labels, deprecation, bad input."""

from __future__ import annotations

import time
from datetime import timedelta

import numpy as np
import pytest
import sqlalchemy as sa
from sqlalchemy.orm import Session
from store_helpers import blob_files, count_rows, planar_conditions, spring_joint

from jointdb.errors import ConflictError, InputError, NotFoundError
from jointdb.frf import FRF
from jointdb.store import Conditions, Provenance
from jointdb.store._models import VersionRow


def _cat(repo, name="T1", k=2e6, torque=40.0, **kw):
    return repo.catalogue(
        name,
        "tool-holder",
        spring_joint(k=(k, 8e4)),
        planar_conditions(torque=torque),
        "spring-damper-planar",
        Provenance(method="irc-planar", parameters={"root": "passive"}, input_files={"tip.uff": "a" * 64}),
        {"identification_residual": 1e-3},
        **kw,
    )


def test_catalogue_and_get_round_trip(repo):
    v1 = _cat(repo, author="alice")
    assert (v1.name, v1.version, v1.parent_version) == ("T1", 1, None)
    assert v1.conditions.materials == ("tungsten-carbide", "steel")
    assert v1.provenance.author == "alice" and v1.provenance.method == "irc-planar"
    assert v1.provenance.input_files == {"tip.uff": "a" * 64}
    assert v1.provenance.software_version
    got = repo.get("T1")
    assert got == v1
    assert repo.load_frf(got).allclose(spring_joint(k=(2e6, 8e4)), rtol=0)
    v2 = _cat(repo, k=3e6)
    assert (v2.version, v2.parent_version) == (2, 1)
    assert repo.get("T1").version == 2
    assert [v.version for v in repo.history("T1")] == [1, 2]


def test_numbering_is_gapless_per_joint(repo):
    for i in range(5):
        _cat(repo, "A", k=1e6 + i)
        if i % 2:
            _cat(repo, "B", k=5e6 + i)
    assert [v.version for v in repo.history("A")] == [1, 2, 3, 4, 5]
    assert [v.version for v in repo.history("B")] == [1, 2]
    assert repo.check().ok


def test_pinned_query_returns_same_bytes_forever(repo):
    v1 = _cat(repo)
    first = repo.load_frf(repo.get("T1", version=1))
    path = repo.blobs.path(v1.blob_sha256)
    raw_before = path.read_bytes()
    for k in (3e6, 4e6, 5e6):
        _cat(repo, k=k)
    repo.label("T1", 3, "released")
    repo.deprecate("T1", 1, reason="superseded")
    again = repo.get("T1", version=1)
    assert again.blob_sha256 == v1.blob_sha256 and again.record_sha256 == v1.record_sha256
    frf = repo.load_frf(again)
    assert frf.values.tobytes() == first.values.tobytes() and frf.freq.tobytes() == first.freq.tobytes()
    assert path.read_bytes() == raw_before
    assert again.state == "deprecated"


def test_versions_are_immutable_in_orm(repo):
    _cat(repo)
    with Session(repo.write_engine) as s:
        row = s.scalar(sa.select(VersionRow))
        row.torque_nm = 99.0
        with pytest.raises(ConflictError, match="immutable"):
            s.commit()
        s.rollback()
    with Session(repo.write_engine) as s:
        row = s.scalar(sa.select(VersionRow))
        s.delete(row)
        with pytest.raises(ConflictError, match="never deleted"):
            s.commit()
    assert repo.get("T1").conditions.torque_nm == 40.0


@pytest.mark.parametrize(
    "sql",
    [
        "UPDATE joint_versions SET torque_nm = 99",
        "DELETE FROM joint_versions",
        "UPDATE joints SET joint_type = 'other'",
        "DELETE FROM audit_log",
        "UPDATE joint_states SET state = 'active'",
    ],
)
def test_versions_are_immutable_in_database(repo, sql):
    _cat(repo)
    repo.deprecate("T1", 1)
    with pytest.raises(sa.exc.DBAPIError, match="immutable"):
        with repo.write_engine.begin() as conn:
            conn.exec_driver_sql(sql)
    assert repo.get("T1", 1).conditions.torque_nm == 40.0
    assert repo.check().ok


def test_point_in_time_and_labels(repo):
    v1 = _cat(repo)
    time.sleep(0.01)
    v2 = _cat(repo, k=3e6)
    assert repo.get("T1", at=v1.created_at).version == 1
    assert repo.get("T1", at=v2.created_at).version == 2
    assert repo.get("T1", at=v1.created_at.isoformat()).version == 1
    with pytest.raises(NotFoundError, match="had no version"):
        repo.get("T1", at=v1.created_at - timedelta(seconds=1))
    assert repo.get("T1", version=1, at=v2.created_at).version == 1
    with pytest.raises(NotFoundError, match="did not exist yet"):  # pinned version and time disagree
        repo.get("T1", version=2, at=v1.created_at)
    repo.label("T1", 1, "released")
    assert repo.get("T1", label="released").version == 1
    repo.label("T1", 2, "released")  # labels move
    assert repo.get("T1", label="released").version == 2
    assert repo.get("T1", 2).labels == ("released",)
    with pytest.raises(NotFoundError, match="no label"):
        repo.get("T1", label="nope")
    with pytest.raises(NotFoundError, match="no version 7"):
        repo.label("T1", 7, "x")
    with pytest.raises(InputError):
        repo.get("T1", label="released", version=1)
    actions = [a["action"] for a in repo.audit("T1")]
    assert actions.count("label") == 2 and actions.count("catalogue") == 2


def test_deprecate_is_a_new_state_not_a_deletion(repo):
    _cat(repo)
    _cat(repo, k=3e6)
    before = count_rows(repo)
    hist = repo.deprecate("T1", 2, reason="loose bolt")
    assert [v.state for v in hist] == ["active", "deprecated"]
    assert repo.get("T1").version == 1  # latest non-deprecated
    assert repo.get("T1", 2).state == "deprecated"
    repo.deprecate("T1", reason="joint withdrawn")
    assert repo.get("T1").state == "deprecated"
    repo.deprecate("T1", undo=True)
    assert repo.get("T1").version == 2 and repo.get("T1").state == "active"
    after = count_rows(repo)
    assert after["joint_versions"] == before["joint_versions"] == 2
    assert after["joint_states"] == 3


def test_parent_and_type_conflicts(repo):
    _cat(repo)
    blobs_before = blob_files(repo)
    with pytest.raises(ConflictError, match="tool-holder joint"):
        repo.catalogue("T1", "holder-spindle", spring_joint(k=(7e6, 1e5)), planar_conditions(), "spring-damper-planar")
    with pytest.raises(ConflictError, match="parent version 5"):
        _cat(repo, parent=5, k=7e6)
    assert blob_files(repo) == blobs_before  # refused before any blob was written
    v = _cat(repo, parent=1, k=3e6)  # another FRF (identical content would write nothing)
    assert v.parent_version == 1


BAD_CASES = {
    "negative torque": (lambda: dict(conditions={"materials": ["steel"], "torque_nm": -5.0}), "torque_nm"),
    "negative preload": (lambda: dict(conditions={"preload_n": -1.0}), "preload_n"),
    "unknown material": (lambda: dict(conditions={"materials": ["unobtainium"]}), "unknown material 'unobtainium'"),
    "non-numeric geometry": (lambda: dict(conditions={"geometry": {"diameter_m": "big"}}), "geometry"),
    "rotation in n-point model": (
        lambda: dict(model_kind="n-point-translational"), "DOF 3ry is a rotation"),
    "unknown model kind": (lambda: dict(model_kind="magic"), "unknown model kind"),
    "3-D DOF in planar model": (
        lambda: dict(frf=spring_joint(dofs=("3x", "3z"))), "DOF 3z does not fit"),
    "full-matrix with one node": (lambda: dict(model_kind="full-matrix"), "exactly two joint nodes"),
    "non-square joint FRF": (
        lambda: dict(frf=FRF(np.linspace(1, 10, 4), np.ones((4, 1, 2)), ["3x"], ["3x", "3ry"])), "square"),
    "outputs differ from inputs": (
        lambda: dict(frf=FRF(np.linspace(1, 10, 4), np.ones((4, 2, 2)), ["3x", "3ry"], ["3ry", "3x"])), "square"),
    "mobility not receptance": (lambda: dict(frf=spring_joint().to("mobility")), "receptance"),
    "bad joint type": (lambda: dict(joint_type="tool holder!"), "joint type"),
    "empty name": (lambda: dict(name=""), "joint name"),
    "NaN quality": (lambda: dict(quality={"residual": float("nan")}), "quality metric"),
    "bad input hash": (lambda: dict(provenance={"method": "irc", "input_files": {"a.uff": "123"}}), "SHA-256"),
    "not an FRF": (lambda: dict(frf=np.ones((4, 2, 2))), "must be a jointdb.frf.FRF"),
}


@pytest.mark.parametrize("case", sorted(BAD_CASES))
def test_bad_input_is_refused_and_writes_nothing(repo, case):
    _cat(repo)  # an existing joint, so a refused write would show up as a new version
    make, expected = BAD_CASES[case]
    before, blobs_before = count_rows(repo), blob_files(repo)
    args = dict(
        name="T1",
        joint_type="tool-holder",
        frf=spring_joint(k=(7e6, 1e5)),
        conditions=planar_conditions(),
        model_kind="spring-damper-planar",
        provenance=None,
        quality=None,
    )
    with pytest.raises(InputError, match=expected):
        args.update(make())
        repo.catalogue(**args)
    assert count_rows(repo) == before
    assert blob_files(repo) == blobs_before


def test_nan_in_frf_is_refused_at_the_door():
    values = np.ones((4, 1, 1), complex)
    values[2, 0, 0] = np.nan
    with pytest.raises(InputError, match="NaN"):
        FRF(np.linspace(1, 10, 4), values, ["1x"], ["1x"])


def test_materials_list_is_extensible(repo, monkeypatch):
    with pytest.raises(InputError, match="JOINTDB_MATERIALS"):
        Conditions(materials=("inconel",))
    monkeypatch.setenv("JOINTDB_MATERIALS", "inconel, cfrp")
    assert Conditions(materials=("Inconel", "carbide")).materials == ("inconel", "tungsten-carbide")


def test_diff_reports_conditions_and_frf(repo):
    _cat(repo, k=2e6)
    _cat(repo, k=2e6 * 1.25, torque=60.0, force=True)
    d = repo.diff("T1", 1, 2)
    assert d.conditions["torque_nm"] == (40.0, 60.0)
    entries = {(e["output"], e["input"]): e["max_rel_diff"] for e in d.frf_entries}
    # h = 1/(k + iωc): |h2 - h1| / max|h1| is largest at low frequency, close to 1 - 1/1.25 = 0.2
    assert entries[("3x", "3x")] == pytest.approx(0.2, rel=1e-3)
    assert entries[("3ry", "3ry")] == 0.0
    assert d.max_relative_difference == entries[("3x", "3x")]
    same = repo.diff("T1", 1, 1)
    assert same.same_blob and same.max_relative_difference == 0.0 and not same.conditions


def test_duplicate_version_number_is_refused_by_the_database(repo):
    _cat(repo)
    with pytest.raises(sa.exc.IntegrityError):
        with repo.write_engine.begin() as conn:
            conn.exec_driver_sql(
                "INSERT INTO joint_versions (joint_id, version, uuid, created_at, author, materials, geometry, extra,"
                " model_kind, dofs, quantity, n_freq, freq_min_hz, freq_max_hz, blob_sha256, raw_blobs, input_files,"
                " method, method_params, software_version, quality, record_sha256)"
                " SELECT joint_id, version, 'other-uuid', created_at, author, materials, geometry, extra, model_kind,"
                " dofs, quantity, n_freq, freq_min_hz, freq_max_hz, blob_sha256, raw_blobs, input_files, method,"
                " method_params, software_version, quality, record_sha256 FROM joint_versions"
            )


def test_write_is_retried_after_a_unique_conflict(repo):
    """A version-number race (unique violation) rolls back and retries with the next number."""
    calls = []

    def write(session):
        calls.append(1)
        if len(calls) < 3:
            raise sa.exc.IntegrityError("INSERT ...", {}, Exception("UNIQUE constraint failed: joint_versions"))
        return "done"

    assert repo._retrying(write) == "done" and len(calls) == 3

    def check_violation(session):
        raise sa.exc.IntegrityError("INSERT ...", {}, Exception("CHECK constraint failed: version_positive"))

    with pytest.raises(sa.exc.IntegrityError):  # other integrity errors are not retried
        repo._retrying(check_violation)
