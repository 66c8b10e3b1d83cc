"""Issue 20, items 5 and 6: a version is the same joint re-identified (a contradicting v2 is refused
on the library, the CLI and bundle import, with both values named; force means it and the audit
says so), identical content writes nothing (also under concurrent writers), and ``--trust``
implies signature verification (no unchecked fingerprint is ever printed)."""

from __future__ import annotations

import json
import threading

import h5py
import pytest
from store_helpers import assert_one_line_error, planar_conditions, run_main, spring_joint

from jointdb.errors import ConflictError, IntegrityError
from jointdb.store import Conditions, Repository
from jointdb.store import create_key_pair, load_private_key

CARBIDE_80 = dict(materials=("tungsten-carbide", "steel"), torque=80.0)
STEEL_30 = dict(materials=("steel", "steel"), torque=30.0)


def _carbide(repo, k=2e6, **kw):
    return repo.catalogue("th-er32-carbide-080nm", "tool-holder", spring_joint(k=(k, 8e4)),
                          planar_conditions(**CARBIDE_80), "spring-damper-planar", **kw)


def _steel(repo, **kw):
    return repo.catalogue("th-er32-carbide-080nm", "tool-holder", spring_joint(k=(9e5, 8e4)),
                          planar_conditions(**STEEL_30), "spring-damper-planar", **kw)


def test_contradicting_v2_is_refused_with_both_values_and_forced_v2_is_audited(repo):
    _carbide(repo)
    with pytest.raises(ConflictError) as err:
        _steel(repo)
    text = str(err.value)
    assert "torque_nm 80 (v1) -> 30" in text and "tungsten-carbide+steel (v1) -> steel+steel" in text, text
    assert len(repo.history("th-er32-carbide-080nm")) == 1
    hits = repo.nearest("tool-holder", Conditions(("carbide", "steel"), torque_nm=80.0), k=1)
    assert hits[0].version.conditions.torque_nm == 80.0  # the carbide joint still answers
    v2 = _steel(repo, force=True)
    assert v2.version == 2 and v2.conditions.torque_nm == 30.0
    entry = repo.audit("th-er32-carbide-080nm", limit=1)[0]
    forced = {c["condition"]: (c["from"], c["to"]) for c in entry["details"]["forced"]}
    assert forced["torque_nm"] == (80.0, 30.0) and forced["materials"][1] == ["steel", "steel"], entry


def test_filling_in_an_unknown_condition_is_allowed_changing_or_dropping_a_known_one_is_not(repo):
    name = "T-ins"

    def cat(k, **geometry):
        return repo.catalogue(name, "tool-holder", spring_joint(k=(k, 8e4)),
                              planar_conditions(geometry=geometry), "spring-damper-planar")

    cat(2e6)
    v2 = cat(2e6, insertion_m=0.035)  # the same FRF with one more condition recorded
    assert v2.version == 2 and repo.audit(name, limit=1)[0]["details"]["filled_in"] == ["geometry.insertion_m"]
    with pytest.raises(ConflictError, match=r"geometry.insertion_m 0.035 \(v2\) -> 0.045"):
        cat(2e6, insertion_m=0.045)
    with pytest.raises(ConflictError, match=r"geometry.insertion_m 0.035 \(v2\) -> none"):
        cat(3e6)
    with pytest.raises(ConflictError, match=r"model_kind spring-damper-planar \(v2\) -> n-point-translational, dofs"):
        repo.catalogue(name, "tool-holder", spring_joint(k=(2e6, 8e4), dofs=("3x", "3y")),
                       planar_conditions(geometry={"insertion_m": 0.035}), "n-point-translational")
    assert len(repo.history(name)) == 2


def test_identical_content_writes_nothing_and_says_so(repo):
    first, created = repo.catalogue_outcome("T1", "tool-holder", spring_joint(), planar_conditions(),
                                            "spring-damper-planar")
    again, created_again = repo.catalogue_outcome("T1", "tool-holder", spring_joint(), planar_conditions(),
                                                  "spring-damper-planar")
    assert created and not created_again and again.uuid == first.uuid
    assert len(repo.history("T1")) == 1
    forced = repo.catalogue("T1", "tool-holder", spring_joint(), planar_conditions(), "spring-damper-planar",
                            allow_identical=True)
    assert forced.version == 2


def test_concurrent_identical_writes_make_one_version(backend):
    repos = [backend.repo() for _ in range(6)]
    results, errors = [], []
    barrier = threading.Barrier(len(repos))

    def write(r):
        try:
            barrier.wait()
            results.append(r.catalogue_outcome("C1", "tool-holder", spring_joint(), planar_conditions(),
                                               "spring-damper-planar"))
        except Exception as exc:  # reported below
            errors.append(repr(exc))

    threads = [threading.Thread(target=write, args=(r,)) for r in repos]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors, errors
    assert sum(created for _, created in results) == 1 and {v.version for v, _ in results} == {1}
    assert len(repos[0].history("C1")) == 1
    for r in repos:
        r.close()


def _joint_file(path, torque, materials, k):
    from jointdb import io

    io.write_frf_hdf5(path, spring_joint(k=(k, 8e4)), {
        "kind": "joint", "joint_model": "planar", "joint_type": "tool-holder",
        "conditions": {"materials": list(materials), "torque_nm": torque}})
    return path


def test_cli_refuses_a_contradicting_v2_and_force_means_it(tmp_path, capsys):
    db = tmp_path / "j.sqlite"
    carbide = _joint_file(tmp_path / "carbide.h5", 80.0, ("tungsten-carbide", "steel"), 2e6)
    steel = _joint_file(tmp_path / "steel.h5", 30.0, ("steel", "steel"), 9e5)
    assert run_main(capsys, "catalogue", carbide, "--name", "th-er32-carbide-080nm", "--db", db)[0] == 0
    line = assert_one_line_error(run_main(capsys, "catalogue", steel, "--name", "th-er32-carbide-080nm",
                                          "--db", db), ConflictError.exit_code, "torque_nm 80 (v1) -> 30")
    assert "steel+steel" in line and ConflictError.exit_code == 4
    code, out, err = run_main(capsys, "catalogue", steel, "--name", "th-er32-carbide-080nm", "--force", "--json",
                              "--db", db)
    assert code == 0 and json.loads(out)["version"] == 2, err


def _bundle_with_contradicting_v2(tmp_path):
    """A bundle of th-er32 v1 (carbide 80) + v2 (steel 30, forced at the source); the target holds v1."""
    src = Repository(tmp_path / "src.sqlite")
    _carbide(src)
    target = Repository(tmp_path / "target.sqlite")
    src.export(None, tmp_path / "v1.h5")
    target.import_(tmp_path / "v1.h5")
    _steel(src, force=True)
    src.export(None, tmp_path / "v2.h5")
    src.close()
    return target, tmp_path / "v2.h5"


def test_import_refuses_a_contradicting_v2_and_force_is_audited(tmp_path, capsys):
    target, bundle = _bundle_with_contradicting_v2(tmp_path)
    with pytest.raises(ConflictError, match=r"v2 is not the same joint as v1 \(.*torque_nm 80 \(v1\) -> 30"):
        target.import_(bundle)
    assert len(target.history("th-er32-carbide-080nm")) == 1
    assert_one_line_error(run_main(capsys, "joints", "import", bundle, "--db", tmp_path / "target.sqlite"),
                          ConflictError.exit_code, "torque_nm 80 (v1) -> 30")
    summary = target.import_(bundle, force=True)
    assert summary["new_versions"] == 1
    forced = target.audit("th-er32-carbide-080nm", limit=1)[0]["details"]["forced"]
    assert {"condition": "torque_nm", "from": 80.0, "to": 30.0, "version": 2, "of_version": 1} in forced
    target.close()


def _signed_bundle(tmp_path):
    repo = Repository(tmp_path / "lab.sqlite")
    _carbide(repo)
    key, pub = create_key_pair(tmp_path / "lab-key")
    bundle = tmp_path / "signed.h5"
    repo.export(None, bundle, sign_key=load_private_key(key))
    repo.close()
    return bundle, pub


def test_trust_without_require_signature_refuses_a_stripped_signature(tmp_path, capsys):
    bundle, pub = _signed_bundle(tmp_path)
    with h5py.File(bundle, "r+") as f:  # the tamperer removes what would betray the edit
        del f.attrs["signature"]
        del f.attrs["signer_public_key"]
    target = tmp_path / "t.sqlite"
    assert_one_line_error(run_main(capsys, "joints", "import", bundle, "--trust", pub, "--db", target),
                          IntegrityError.exit_code, "not signed")
    assert not target.exists()
    _, other_pub = create_key_pair(tmp_path / "other-key")
    good, good_pub = _signed_bundle_in(tmp_path / "second")
    assert_one_line_error(run_main(capsys, "joints", "import", good, "--trust", other_pub, "--db", target),
                          IntegrityError.exit_code, "does not verify")
    code, out, err = run_main(capsys, "joints", "import", good, "--trust", good_pub, "--db", target, "--json")
    assert code == 0 and json.loads(out)["signature_verified"] is True and "signature verified" in err, err


def _signed_bundle_in(directory):
    directory.mkdir()
    return _signed_bundle(directory)


def test_no_fingerprint_is_printed_unless_the_signature_was_verified(tmp_path, capsys):
    bundle, _ = _signed_bundle(tmp_path)
    with h5py.File(bundle, "r+") as f:  # a claimed signer that never signed anything
        claimed = f.attrs["signer_public_key"]
        f.attrs["signer_public_key"] = "ab" * 32
    from jointdb.store._signing import fingerprint

    code, out, err = run_main(capsys, "joints", "import", bundle, "--db", tmp_path / "t.sqlite", "--json")
    assert code == 0, err
    assert "unsigned / signature not checked" in err
    for fp in (fingerprint(bytes.fromhex("ab" * 32)), fingerprint(bytes.fromhex(str(claimed)))):
        assert fp not in err and fp not in out
    assert json.loads(out)["signed_by"] is None and json.loads(out)["signature_verified"] is False
