"""Export to one portable HDF5 bundle and import elsewhere, refusing silent overwrites."""

from __future__ import annotations

import json

import h5py
import pytest
from store_helpers import blob_files, count_rows, planar_conditions, spring_joint

from jointdb.errors import ConflictError, IntegrityError, NotFoundError
from jointdb.store import Provenance, Repository


@pytest.fixture
def source(tmp_path):
    repo = Repository(tmp_path / "lab.sqlite")
    for i, k in enumerate((2e6, 2.5e6, 3e6)):
        repo.catalogue("T1", "tool-holder", spring_joint(k=(k, 8e4)), planar_conditions(torque=20.0 + 10 * i),
                       "spring-damper-planar",
                       Provenance(method="irc-planar", parameters={"i": i}, input_files={"tip.uff": f"{i:064x}"}),
                       {"identification_residual": 0.01 * (i + 1)}, author="lab",
                       raw_frfs={"tip": spring_joint(k=(k * 10, 8e5), dofs=("1x", "1ry"))}, force=True)
    repo.catalogue("H1", "holder-spindle", spring_joint(k=(9e7, 5e6)), planar_conditions(torque=100.0),
                   "spring-damper-planar")
    repo.label("T1", 2, "released")
    repo.deprecate("T1", 1, reason="loose bolt")
    yield repo
    repo.close()


def test_export_import_keeps_versions_and_provenance(source, repo, tmp_path):
    bundle = tmp_path / "lab.h5"
    counts = source.export(None, bundle)
    assert (counts["joints"], counts["versions"]) == (2, 4) and len(counts["bundle_sha256"]) == 64
    summary = repo.import_(bundle, author="design", force=True)
    assert summary["new_versions"] == 4 and summary["unchanged_versions"] == 0
    for name in ("T1", "H1"):
        for a, b in zip(source.history(name), repo.history(name), strict=True):
            assert a == b  # uuid, created_at, author, provenance, quality, record hash, state, labels
            assert repo.load_frf(b).allclose(source.load_frf(a), rtol=0)
            if a.raw_blobs:
                assert repo.load_raw(b, "tip").allclose(source.load_raw(a, "tip"), rtol=0)
    assert repo.get("T1", label="released").version == 2
    assert repo.get("T1", 1).state == "deprecated"
    assert repo.check().ok
    # identical content again: a no-op
    before = count_rows(repo)
    again = repo.import_(bundle)
    assert again["new_versions"] == 0 and again["unchanged_versions"] == 4
    assert {k: v for k, v in count_rows(repo).items() if k != "audit_log"} == {
        k: v for k, v in before.items() if k != "audit_log"}


def test_import_appends_new_versions_of_a_shared_history(source, repo, tmp_path):
    source.export(["T1"], tmp_path / "a.h5")
    repo.import_(tmp_path / "a.h5", force=True)
    source.catalogue("T1", "tool-holder", spring_joint(k=(4e6, 8e4)), planar_conditions(torque=50.0),
                     "spring-damper-planar", force=True)
    source.export(["T1"], tmp_path / "b.h5")
    summary = repo.import_(tmp_path / "b.h5", force=True)
    assert summary["new_versions"] == 1 and summary["unchanged_versions"] == 3
    assert [v.uuid for v in repo.history("T1")] == [v.uuid for v in source.history("T1")]


def test_conflicting_bundle_is_refused_and_writes_nothing(source, repo, tmp_path):
    # the target has its own T1 v1 (different content): the bundle's v1..v3 conflict
    repo.catalogue("T1", "tool-holder", spring_joint(k=(7e6, 8e4)), planar_conditions(), "spring-damper-planar")
    source.export(None, tmp_path / "lab.h5")
    before, blobs_before = count_rows(repo), blob_files(repo)
    with pytest.raises(ConflictError, match="'T1' version 1 already exists here with different content"):
        repo.import_(tmp_path / "lab.h5")
    assert count_rows(repo) == before and blob_files(repo) == blobs_before
    with pytest.raises(NotFoundError):
        repo.get("H1")  # the non-conflicting joint of the same bundle was not imported either


def test_joint_type_conflict_is_refused(source, repo, tmp_path):
    repo.catalogue("H1", "tool-holder", spring_joint(), planar_conditions(), "spring-damper-planar")
    source.export(["H1"], tmp_path / "h.h5")
    with pytest.raises(ConflictError, match="holder-spindle in the bundle"):
        repo.import_(tmp_path / "h.h5")


def test_tampered_bundle_is_refused(source, repo, tmp_path):
    bundle = tmp_path / "lab.h5"
    source.export(["T1"], bundle)
    with h5py.File(bundle, "r+") as f:
        g = f["joints/j0000/v0002"]
        record = json.loads(g.attrs["record"])
        record["conditions"]["torque_nm"] = 99.0  # silently "improve" a condition
        g.attrs["record"] = json.dumps(record, sort_keys=True)
    before = count_rows(repo)
    with pytest.raises(IntegrityError, match="record hash mismatch"):
        repo.import_(bundle)
    assert count_rows(repo) == before


def test_export_failure_leaves_no_partial_file_and_missing_bundle_is_not_found(source, repo, tmp_path):
    from jointdb.errors import InputError

    with pytest.raises(InputError, match="does not exist"):
        source.export(None, tmp_path / "nodir" / "x.h5")
    # a corrupt blob stops the export half-way: nothing is left behind
    jv = source.get("H1")
    path = source.blobs.path(jv.blob_sha256)
    data = bytearray(path.read_bytes())
    data[-100] ^= 0xFF
    path.write_bytes(bytes(data))
    with pytest.raises(IntegrityError):
        source.export(None, tmp_path / "out.h5")
    assert sorted(p.name for p in tmp_path.iterdir() if "out" in p.name) == []
    with pytest.raises(NotFoundError, match="does not exist"):
        repo.import_(tmp_path / "missing.h5")
