"""Bundles carry labels and states under the bundle hash, validate them like the CLI does, and
can be signed (Ed25519) so that an edit with every hash recomputed is still refused."""

from __future__ import annotations

import json
import os
import stat

import h5py
import pytest
from store_helpers import assert_one_line_error, count_rows, planar_conditions, run_main, spring_joint, tree_state

from jointdb.errors import ConflictError, InputError, IntegrityError, NotFoundError
from jointdb.store import Repository
from jointdb.store._bundle_read import manifest_sha256
from jointdb.store._records import record_sha256
from jointdb.store import create_key_pair, load_private_key, load_public_key


@pytest.fixture
def lab(tmp_path):
    repo = Repository(tmp_path / "lab.sqlite")
    for torque in (30.0, 40.0):
        repo.catalogue("T1", "tool-holder", spring_joint(k=(torque * 1e5, 8e4)), planar_conditions(torque=torque),
                       "spring-damper-planar", force=True)
    repo.label("T1", 2, "released")
    repo.deprecate("T1", 1, reason="loose nut")
    yield repo
    repo.close()


def rehash(bundle) -> None:
    """Recompute every record hash and the bundle hash after an edit (what a forger would do)."""
    with h5py.File(bundle, "r+") as f:
        joints = []
        for gname in sorted(f["joints"]):
            g = f["joints"][gname]
            versions = []
            for vname in sorted(k for k in g if k.startswith("v")):
                record = json.loads(g[vname].attrs["record"])
                g[vname].attrs["record_sha256"] = record_sha256(record)
                versions.append({"record": record, "digest": record_sha256(record)})
            joints.append({k: str(g.attrs[k]) for k in ("name", "joint_type", "created_at", "created_by")}
                          | {"labels": json.loads(g.attrs["labels"]), "states": json.loads(g.attrs["states"]),
                             "versions": versions})
        f.attrs["bundle_sha256"] = manifest_sha256(joints)


def edit(bundle, group="joints/j0000", **attrs) -> None:
    with h5py.File(bundle, "r+") as f:
        for key, value in attrs.items():
            f[group].attrs[key] = value


def test_labels_and_states_are_validated_on_import(lab, tmp_path):
    for labels, says in (({"'; DROP TABLE labels; --": 1}, "label"), ({"released": 7}, "version must be"),
                         ({"released": "2"}, "version must be"), ([1, 2], "labels must be")):
        bundle = tmp_path / "b.h5"
        lab.export(None, bundle)
        edit(bundle, labels=json.dumps(labels))
        rehash(bundle)  # only the validation can stop it now
        target = Repository(tmp_path / f"t{len(says)}.sqlite")
        with pytest.raises(InputError, match=says):
            target.import_(bundle)
        assert count_rows(target)["labels"] == 0 and count_rows(target)["joints"] == 0
        target.close()
        bundle.unlink()
    for mutate, says in ((lambda s: s[0].update(at="yesterday"), "not an ISO 8601 time"),
                         (lambda s: s[0].update(at="2026-01-31T12:00:00"), "has no time zone"),
                         (lambda s: s[0].update(state="gone"), "state must be"),
                         (lambda s: s[0].update(version=9), "version must be"),
                         (lambda s: s[0].update(sneaky=1), "exactly version, state, reason, author, at")):
        bundle = tmp_path / "s.h5"
        lab.export(None, bundle)
        with h5py.File(bundle, "r") as f:
            states = json.loads(f["joints/j0000"].attrs["states"])
        mutate(states)
        edit(bundle, states=json.dumps(states))
        rehash(bundle)
        with pytest.raises(InputError, match=says):
            Repository(tmp_path / "s.sqlite").import_(bundle)
        bundle.unlink()
    bundle = tmp_path / "c.h5"
    lab.export(None, bundle)
    edit(bundle, created_at="last tuesday")
    rehash(bundle)
    with pytest.raises(InputError, match="created_at: 'last tuesday' is not an ISO 8601 time"):
        Repository(tmp_path / "c.sqlite").import_(bundle)


def test_the_bundle_hash_covers_labels_and_states(lab, tmp_path):
    for attrs in ({"labels": json.dumps({"released": 1})}, {"states": "[]"}, {"created_by": "mallory"}):
        bundle = tmp_path / "h.h5"
        lab.export(None, bundle)
        edit(bundle, **attrs)  # a valid edit, hashes not recomputed
        with pytest.raises(IntegrityError, match="bundle hash mismatch"):
            Repository(tmp_path / "h.sqlite").import_(bundle)
        bundle.unlink()


def test_a_signed_bundle_refuses_an_edit_with_every_hash_recomputed(lab, tmp_path):
    key, pub = create_key_pair(tmp_path / "lab-key")
    assert stat.S_IMODE(os.stat(key).st_mode) == 0o600
    other, other_pub = create_key_pair(tmp_path / "other-key")
    bundle = tmp_path / "signed.h5"
    counts = lab.export(None, bundle, sign_key=load_private_key(key))
    assert len(counts["signed_by"]) == 16
    target = Repository(tmp_path / "t.sqlite")
    summary = target.import_(bundle, trusted_keys=[load_public_key(pub)], require_signature=True, force=True)
    assert summary["new_versions"] == 2 and summary["signature_verified"] and summary["signed_by"] == counts["signed_by"]
    assert target.audit("T1", limit=1)[0]["details"]["signed_by"] == counts["signed_by"]
    target.close()

    forged = tmp_path / "forged.h5"
    lab.export(None, forged, sign_key=load_private_key(key))
    with h5py.File(forged, "r+") as f:
        g = f["joints/j0000/v0002"]
        record = json.loads(g.attrs["record"])
        record["conditions"]["torque_nm"] = 99.0  # the 'improved' condition
        g.attrs["record"] = json.dumps(record, sort_keys=True)
    rehash(forged)
    fresh = Repository(tmp_path / "f.sqlite")
    assert fresh.import_(forged, force=True)["new_versions"] == 2  # hashes alone cannot tell: why signatures exist
    fresh.close()
    for trusted in ([pub], [other_pub], [pub, other_pub]):
        with pytest.raises(IntegrityError, match="signature does not verify"):
            Repository(tmp_path / "g.sqlite").import_(forged, trusted_keys=[load_public_key(p) for p in trusted],
                                                      require_signature=True)
    unsigned = tmp_path / "unsigned.h5"
    lab.export(None, unsigned)
    with pytest.raises(IntegrityError, match="not signed"):
        Repository(tmp_path / "g.sqlite").import_(unsigned, trusted_keys=[load_public_key(pub)],
                                                  require_signature=True)
    with pytest.raises(IntegrityError, match="signature does not verify"):  # signed by a key not trusted
        Repository(tmp_path / "g.sqlite").import_(bundle, trusted_keys=[load_public_key(other_pub)])
    with pytest.raises(ConflictError, match="already exists"):
        create_key_pair(tmp_path / "lab-key")


def test_cli_signed_round_trip_and_a_refused_bundle_creates_no_database(lab, tmp_path, capsys):
    code, out, err = run_main(capsys, "keys", "create", tmp_path / "k", "--json")
    assert code == 0 and json.loads(out)["public_key"] == str(tmp_path / "k.pub"), err
    bundle = tmp_path / "lab.h5"
    code, out, err = run_main(capsys, "joints", "export", bundle, "--sign", tmp_path / "k", "--db", lab.url[10:],
                              "--json")
    assert code == 0 and json.loads(out)["versions"] == 2, err
    target = tmp_path / "new" / "t.sqlite"
    target.parent.mkdir()
    before = tree_state(tmp_path)
    with h5py.File(bundle, "r+") as f:
        f["joints/j0000"].attrs["labels"] = json.dumps({"released": 1})
    rehash(bundle)
    before = tree_state(tmp_path)
    assert_one_line_error(run_main(capsys, "joints", "import", bundle, "--require-signature", "--trust",
                                   tmp_path / "k.pub", "--db", target), IntegrityError.exit_code,
                          "signature does not verify")
    assert_one_line_error(run_main(capsys, "joints", "import", bundle, "--require-signature", "--db", target),
                          InputError.exit_code, "--trust")
    assert_one_line_error(run_main(capsys, "joints", "import", tmp_path / "nope.h5", "--db", target),
                          NotFoundError.exit_code, "does not exist")
    assert tree_state(tmp_path) == before and list(target.parent.iterdir()) == []
    code, out, err = run_main(capsys, "joints", "import", bundle, "--db", target, "--force", "--json")
    assert code == 0 and "signature not checked" in err and json.loads(out)["signature_verified"] is False, err
