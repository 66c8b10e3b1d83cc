"""Fuzz corpus of the store side: malformed bundles, database URLs and store/db command arguments.

Each case runs the real console entry point (in this process) and must give exactly one
``error:`` line on stderr, the documented exit code (2 bad input, 3 not found, 4 conflict,
5 integrity), no traceback (any exception other than SystemExit fails the test), and
leave every file and every database row as it was.
"""

from __future__ import annotations

import json
import os

import h5py
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from store_helpers import assert_one_line_error, db_rows, planar_conditions, run_main, spring_joint, tree_state

from jointdb.errors import ConflictError, InputError, IntegrityError, NotFoundError
from jointdb.store import Repository, write_frf_file
from jointdb.store._bundle_read import manifest_sha256
from jointdb.store._records import record_sha256
from jointdb.store import create_key_pair

BAD, MISSING, CONFLICT, INTEGRITY = (InputError.exit_code, NotFoundError.exit_code, ConflictError.exit_code,
                                     IntegrityError.exit_code)


# ----------------------------------------------------------------------------- the world
def _rehash(path) -> None:
    with h5py.File(path, "r+") as f:
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


def _record_edit(path, change, rehash=True, group="joints/j0000/v0001"):
    with h5py.File(path, "r+") as f:
        record = json.loads(f[group].attrs["record"])
        change(record)
        f[group].attrs["record"] = json.dumps(record, sort_keys=True)
    if rehash:
        _rehash(path)


def _attr_edit(path, rehash=True, group="joints/j0000", **attrs):
    with h5py.File(path, "r+") as f:
        for key, value in attrs.items():
            if value is None:
                del f[group].attrs[key]
            else:
                f[group].attrs[key] = value
    if rehash:
        _rehash(path)


def _h5(path, fn):
    with h5py.File(path, "r+") as f:
        fn(f)


def _nan_values(f):
    values = f["joints/j0000/v0001/frf/values"][...]
    values[0, 0, 0, 0] = np.nan
    del f["joints/j0000/v0001/frf/values"]
    f["joints/j0000/v0001/frf"].create_dataset("values", data=values)


def _scaled_values(f):
    values = f["joints/j0000/v0001/frf/values"][...]
    values[3, 0, 0, 0] *= 1.0001
    del f["joints/j0000/v0001/frf/values"]
    f["joints/j0000/v0001/frf"].create_dataset("values", data=values)


#: name -> (how to spoil a copy of a good bundle, exit code, text in the message)
BUNDLES = {
    "empty-file": (lambda p: p.write_bytes(b""), BAD, "not a jointdb bundle"),
    "text-file": (lambda p: p.write_text("joints: T1\n"), BAD, "not a jointdb bundle"),
    "random-bytes": (lambda p: p.write_bytes(np.random.default_rng(1).bytes(4096)), BAD, "not a jointdb bundle"),
    "hdf5-no-format": (lambda p: _h5(p, lambda f: f.attrs.__delitem__("format")), BAD, "not a jointdb bundle"),
    "other-format": (lambda p: _h5(p, lambda f: f.attrs.__setitem__("format", "pictures")), BAD, "'pictures'"),
    "format-version-99": (lambda p: _h5(p, lambda f: f.attrs.__setitem__("format_version", 99)), BAD, "format version"),
    "format-version-text": (lambda p: _h5(p, lambda f: f.attrs.__setitem__("format_version", "2")), BAD,
                            "format version"),
    "no-joints-group": (lambda p: _h5(p, lambda f: f.__delitem__("joints")), BAD, "joints group is missing"),
    "no-name": (lambda p: _attr_edit(p, rehash=False, name=None), BAD, "attribute 'name' is missing"),
    "name-with-slash": (lambda p: _attr_edit(p, name="a/b"), BAD, "joint name"),
    "bad-joint-type": (lambda p: _attr_edit(p, joint_type="Bad Type!"), BAD, "joint type"),
    "record-not-json": (lambda p: _h5(p, lambda f: f["joints/j0000/v0001"].attrs.__setitem__("record", "{")), BAD,
                        "not valid JSON"),
    "record-deep-json": (lambda p: _h5(p, lambda f: f["joints/j0000/v0001"].attrs.__setitem__(
        "record", "[" * 100_000 + "]" * 100_000)), BAD, "nested too deeply"),
    "record-edited": (lambda p: _record_edit(p, lambda r: r["conditions"].update(torque_nm=99.0), rehash=False),
                      INTEGRITY, "record hash mismatch"),
    "negative-torque": (lambda p: _record_edit(p, lambda r: r["conditions"].update(torque_nm=-1.0)), BAD,
                        "torque_nm"),
    "version-as-text": (lambda p: _record_edit(p, lambda r: r.update(version="1")), BAD, "version must be"),
    "uuid-garbage": (lambda p: _record_edit(p, lambda r: r.update(uuid="x")), BAD, "is not a UUID"),
    "created-yesterday": (lambda p: _record_edit(p, lambda r: r.update(created_at="yesterday")), BAD,
                          "not an ISO 8601 time"),
    "blob-digest-path": (lambda p: _record_edit(p, lambda r: r.update(blob_sha256="../../etc/passwd")), BAD,
                         "blob_sha256 is not a SHA-256"),
    "raw-key-path": (lambda p: _record_edit(p, lambda r: r.update(raw_blobs={"../x": "0" * 64})), BAD,
                     "raw_blobs must map"),
    "dofs-lie": (lambda p: _record_edit(p, lambda r: r.update(dofs=["9x", "9ry"])), BAD, "does not describe the FRF"),
    "quality-nan": (lambda p: _record_edit(p, lambda r: r.update(quality={"q": "nan"})), BAD, "quality"),
    "frf-missing": (lambda p: _h5(p, lambda f: f.__delitem__("joints/j0000/v0001/frf")), BAD, "FRF group is missing"),
    "frf-nan": (lambda p: _h5(p, _nan_values), BAD, "NaN"),
    "frf-edited": (lambda p: _h5(p, _scaled_values), INTEGRITY, "FRF content does not match its hash"),
    "frf-start-moved": (lambda p: _h5(p, lambda f: f["joints/j0000/v0001/frf/freq"].__setitem__(0, 11.0)), BAD,
                        "freq_min_hz '10.0' does not describe the FRF"),
    "label-sql": (lambda p: _attr_edit(p, labels=json.dumps({"'; DROP TABLE labels; --": 1})), BAD, "label"),
    "label-bad-version": (lambda p: _attr_edit(p, labels=json.dumps({"released": 7})), BAD, "version must be"),
    "labels-not-json": (lambda p: _attr_edit(p, rehash=False, labels="{released"), BAD, "not valid JSON"),
    "state-yesterday": (lambda p: _attr_edit(p, states=json.dumps([{"version": 1, "state": "deprecated", "reason": "",
                                                                    "author": "x", "at": "yesterday"}])),
                        BAD, "not an ISO 8601 time"),
    "state-unknown": (lambda p: _attr_edit(p, states=json.dumps([{"version": None, "state": "gone", "reason": "",
                                                                  "author": "x", "at": "2026-01-01T00:00:00+00:00"}])),
                      BAD, "state must be"),
    "numbering-gap": (lambda p: _record_edit(p, lambda r: r.update(version=3, parent_version=1),
                                             group="joints/j0000/v0002"), BAD, "not numbered 1..n"),
    "labels-edited-unhashed": (lambda p: _attr_edit(p, rehash=False, labels=json.dumps({"released": 1})), INTEGRITY,
                               "bundle hash mismatch"),
    "joint-twice": (lambda p: (_h5(p, lambda f: f.copy("joints/j0000", "joints/j0001")), _rehash(p)), BAD,
                    "appears twice"),
    "signature-not-hex": (lambda p: _h5(p, lambda f: (f.attrs.__setitem__("signature", "zz"),
                                                      f.attrs.__setitem__("signer_public_key", "00" * 32))),
                          INTEGRITY, "signature does not verify"),
    "signer-not-hex": (lambda p: _h5(p, lambda f: (f.attrs.__setitem__("signature", "00" * 64),
                                                   f.attrs.__setitem__("signer_public_key", "xyz"))),
                       BAD, "signer_public_key is not hex"),
}


@pytest.fixture(scope="module")
def world(tmp_path_factory):
    root = tmp_path_factory.mktemp("world")
    repo = Repository(root / "db.sqlite")
    repo.catalogue("T1", "tool-holder", spring_joint(), planar_conditions(torque=30.0), "spring-damper-planar")
    repo.catalogue("T1", "tool-holder", spring_joint(k=(3e6, 8e4)), planar_conditions(torque=40.0),
                   "spring-damper-planar", label="released", force=True)
    repo.deprecate("T1", 1, reason="loose nut")
    good = root / "good.h5"
    repo.export(None, good)
    other = Repository(root / "other.sqlite")  # a T1 with other content: importing into db conflicts
    other.catalogue("T1", "tool-holder", spring_joint(k=(7e6, 8e4)), planar_conditions(), "spring-damper-planar")
    other.export(None, root / "conflict.h5")
    other.close()
    (root / "other.sqlite").unlink()
    for name, (spoil, _, _) in BUNDLES.items():
        path = root / "bundles" / f"{name}.h5"
        path.parent.mkdir(exist_ok=True)
        path.write_bytes(good.read_bytes())
        spoil(path)
    write_frf_file(root / "joint.h5", spring_joint(k=(5e6, 8e4)))
    from jointdb.io import write_frf_hdf5

    for name, torque in (("meta.h5", 30.0), ("meta-negative.h5", -3.0)):
        write_frf_hdf5(root / name, spring_joint(k=(6e6, 8e4)), {
            "kind": "joint", "joint_model": "planar", "joint_type": "tool-holder",
            "conditions": {"materials": ["steel", "tungsten-carbide"], "torque_nm": torque}})
    (root / "notes.txt").write_text("not a joint\n")
    create_key_pair(root / "key")
    (root / "garbage.pem").write_text("-----BEGIN PUBLIC KEY-----\nAAAA\n-----END PUBLIC KEY-----\n")
    (root / "dir").mkdir()
    (root / "empty.sqlite").write_bytes(b"")
    (root / "bad-header.sqlite").write_bytes(b"SQLite format 3\x00" + b"\xff" * 2000)
    (root / "random.sqlite").write_bytes(np.random.default_rng(2).bytes(3000))
    import sqlite3

    conn = sqlite3.connect(root / "foreign.sqlite")
    conn.execute("CREATE TABLE t (x)")
    conn.commit()
    conn.close()
    repo.close()
    return root


@pytest.fixture
def unchanged(world, monkeypatch):
    """Runs the case and then checks that no file and no row changed."""
    monkeypatch.setenv("JOINTDB_AUTHOR", "fuzz")
    monkeypatch.delenv("JOINTDB_URL", raising=False)
    monkeypatch.delenv("JOINTDB_BLOBS", raising=False)
    files, rows = tree_state(world), db_rows(f"sqlite:///{world / 'db.sqlite'}")
    yield
    assert tree_state(world) == files
    assert db_rows(f"sqlite:///{world / 'db.sqlite'}") == rows


def _sub(args, world):
    return [str(a).replace("{w}", str(world)) for a in args]


# ----------------------------------------------------------------------------- bundles
@pytest.mark.parametrize("name", sorted(BUNDLES))
def test_malformed_bundle_is_refused(name, world, unchanged, capsys):
    _, code, says = BUNDLES[name]
    extra = ["--require-signature", "--trust", world / "key.pub"] if name.startswith("signature") else []
    for db in (world / "db.sqlite", world / "fresh.sqlite"):  # existing, and one that must not appear
        assert_one_line_error(run_main(capsys, "joints", "import", world / "bundles" / f"{name}.h5", *extra,
                                       "--db", db), code, says)
    assert not (world / "fresh.sqlite").exists()


BUNDLE_ARGS = [
    ("bundle-is-dir", ["joints", "import", "{w}/dir"], BAD, "is a directory"),
    ("bundle-missing", ["joints", "import", "{w}/none.h5"], MISSING, "does not exist"),
    ("trust-garbage", ["joints", "import", "{w}/good.h5", "--trust", "{w}/garbage.pem"], BAD, "not a PEM public key"),
    ("trust-missing", ["joints", "import", "{w}/good.h5", "--trust", "{w}/none.pub"], MISSING, "does not exist"),
    ("trust-private-key", ["joints", "import", "{w}/good.h5", "--trust", "{w}/key"], BAD, "not a PEM public key"),
    ("require-unsigned", ["joints", "import", "{w}/good.h5", "--require-signature", "--trust", "{w}/key.pub"],
     INTEGRITY, "not signed"),
    ("require-no-trust", ["joints", "import", "{w}/good.h5", "--require-signature"], BAD, "--trust"),
    ("conflicting", ["joints", "import", "{w}/conflict.h5"], CONFLICT, "already exists here with different content"),
]

# ----------------------------------------------------------------------------- database targets
TARGETS = [
    ("directory", "{w}/dir", BAD, "is a directory"),
    ("text-file", "{w}/notes.txt", BAD, "not a SQLite database"),
    ("empty-file", "{w}/empty.sqlite", BAD, "empty file (0 bytes)"),
    ("random-file", "{w}/random.sqlite", BAD, "not a SQLite database"),
    ("foreign-sqlite", "{w}/foreign.sqlite", BAD, "not a jointdb database"),
    ("bad-header", "{w}/bad-header.sqlite", INTEGRITY, "is damaged"),
    ("missing-file", "{w}/missing.sqlite", MISSING, "does not exist"),
    ("missing-dir-url", "sqlite:////nonexistent-jointdb-dir/x.sqlite", MISSING, "does not exist"),
    ("mysql", "mysql://u@h/db", BAD, "unsupported database 'mysql'"),
    ("memory", ":memory:", BAD, "in-memory"),
    ("sqlite-memory-url", "sqlite://", BAD, "in-memory"),
    ("garbage-url", "://nothing", BAD, "cannot read database URL"),
    ("pg-no-blobs", "postgresql+psycopg://u@127.0.0.1:1/x", BAD, ""),  # JOINTDB_BLOBS, or for db: no server
    ("unknown-driver", "postgresql+nosuchdriver://u@h/x", BAD, "unknown database driver"),
    ("long-path", "{w}/" + "x" * 5000 + ".sqlite", BAD, "database"),
]


@pytest.mark.parametrize("name, target, code, says", TARGETS, ids=[t[0] for t in TARGETS])
def test_unusable_database_target_is_refused(name, target, code, says, world, unchanged, capsys):
    target = _sub([target], world)[0]
    for args in (["joints", "list"], ["db", "check"], ["db", "downgrade", "--yes"]):
        assert_one_line_error(run_main(capsys, *args, "--db", target), code, says)


def test_unreachable_postgres_with_blobs_is_one_line(world, unchanged, capsys, monkeypatch):
    monkeypatch.setenv("JOINTDB_BLOBS", str(world / "pgblobs"))
    for args in (["joints", "list"], ["db", "info"], ["query", "--type", "tool-holder"]):
        assert_one_line_error(run_main(capsys, *args, "--db", "postgresql+psycopg://u@127.0.0.1:1/x"), BAD,
                              "cannot open database")
    assert not (world / "pgblobs").exists()


# ----------------------------------------------------------------------------- command arguments
CAT = ["catalogue", "{w}/joint.h5", "--name", "T9", "--type", "tool-holder", "--model-kind", "spring-damper-planar"]
ARGS = [
    ("label-space-slash", [*CAT, "--label", "a b/c"], BAD, "label"),
    ("label-sql", [*CAT, "--label", "'; DROP TABLE labels; --"], BAD, "label"),
    ("torque-negative", [*CAT, "--torque", "-5"], BAD, "torque_nm"),
    ("torque-nan", [*CAT, "--torque", "nan"], BAD, "finite"),
    ("preload-inf", [*CAT, "--preload", "inf"], BAD, "finite"),
    ("material-unknown", [*CAT, "--material", "unobtainium"], BAD, "unknown material"),
    ("geometry-no-equals", [*CAT, "--geometry", "diameter"], BAD, "key=value"),
    ("geometry-bad-key", [*CAT, "--geometry", "1bad=3"], BAD, "geometry key"),
    ("geometry-not-number", [*CAT, "--geometry", "d=abc"], BAD, "is not a number"),
    ("geometry-negative", [*CAT, "--geometry", "d=-1"], BAD, ">= 0"),
    ("quality-not-number", [*CAT, "--quality", "r=abc"], BAD, "is not a number"),
    ("model-kind-bogus", [*CAT[:-1], "bogus"], BAD, "unknown model kind"),
    ("type-bad", ["catalogue", "{w}/joint.h5", "--name", "T9", "--type", "Bad Type!", "--model-kind",
                  "spring-damper-planar"], BAD, "joint type"),
    ("name-slash", ["catalogue", "{w}/joint.h5", "--name", "a/b", *CAT[4:]], BAD, "joint name"),
    ("name-spaces", ["catalogue", "{w}/joint.h5", "--name", " T9", *CAT[4:]], BAD, "joint name"),
    ("parent-zero", [*CAT, "--parent", "0"], BAD, "--parent must be"),
    ("parent-missing", ["catalogue", "{w}/joint.h5", "--name", "T1", *CAT[4:], "--parent", "99"], CONFLICT,
     "parent version 99"),
    ("type-conflict", ["catalogue", "{w}/joint.h5", "--name", "T1", "--type", "holder-spindle", "--model-kind",
                       "spring-damper-planar"], CONFLICT, "is a tool-holder joint"),
    ("joint-file-missing", ["catalogue", "{w}/none.h5", *CAT[2:]], BAD, "no such file"),
    ("joint-file-text", ["catalogue", "{w}/notes.txt", *CAT[2:]], BAD, "not an HDF5 file"),
    ("joint-file-dir", ["catalogue", "{w}/dir", *CAT[2:]], BAD, "no such file"),
    ("file-conditions-conflict", ["catalogue", "{w}/meta.h5", "--name", "T9", "--torque", "40"], BAD,
     "torque_nm = 30 but --torque gives 40"),
    ("file-materials-conflict", ["catalogue", "{w}/meta.h5", "--name", "T9", "--material", "aluminium"], BAD,
     "materials = steel+tungsten-carbide but --material gives aluminium"),
    ("file-negative-torque", ["catalogue", "{w}/meta-negative.h5", "--name", "T9"], BAD, "torque_nm"),
    ("show-version-missing", ["joints", "show", "T1", "--version", "99"], MISSING, "no version 99"),
    ("show-joint-missing", ["joints", "show", "nope"], MISSING, "no joint named"),
    ("show-at-garbage", ["joints", "show", "T1", "--at", "yesterday"], BAD, "ISO 8601"),
    ("show-label-and-version", ["joints", "show", "T1", "--label", "released", "--version", "1"], BAD, "label"),
    ("show-label-missing", ["joints", "show", "T1", "--label", "gold"], MISSING, "no label 'gold'"),
    ("show-frf-out-missing-dir", ["joints", "show", "T1", "--frf-out", "{w}/nodir/x.h5"], BAD, "does not exist"),
    ("history-missing", ["joints", "history", "nope"], MISSING, "no joint named"),
    ("label-bad-name", ["joints", "label", "T1", "1", "a b"], BAD, "label"),
    ("label-missing-version", ["joints", "label", "T1", "9", "released"], MISSING, "no version 9"),
    ("deprecate-missing-version", ["joints", "deprecate", "T1", "--version", "9"], MISSING, "no version 9"),
    ("diff-missing-version", ["joints", "diff", "T1", "1", "9"], MISSING, "no version 9"),
    ("export-missing-dir", ["joints", "export", "{w}/nodir/b.h5"], BAD, "does not exist"),
    ("export-unknown-joint", ["joints", "export", "{w}/b.h5", "nope"], MISSING, "no joint named"),
    ("export-key-missing", ["joints", "export", "{w}/b.h5", "--sign", "{w}/nokey"], MISSING, "does not exist"),
    ("export-key-garbage", ["joints", "export", "{w}/b.h5", "--sign", "{w}/notes.txt"], BAD, "private key"),
    ("export-key-public", ["joints", "export", "{w}/b.h5", "--sign", "{w}/key.pub"], BAD, "private key"),
    ("query-type-bad", ["query", "--type", "Bad!", "--torque", "3"], BAD, "joint type"),
    ("query-k-zero", ["query", "--type", "tool-holder", "-k", "0"], BAD, "k must be"),
    ("query-type-unknown", ["query", "--type", "no-such-type", "--torque", "3"], MISSING, "no current catalogued"),
    ("query-torque-negative", ["query", "--type", "tool-holder", "--torque", "-1"], BAD, "torque_nm"),
    ("query-geometry-nan", ["query", "--type", "tool-holder", "--geometry", "d=nan"], BAD, "finite"),
    ("query-at-garbage", ["query", "--type", "tool-holder", "--at", "not a time"], BAD, "ISO 8601"),
    ("query-interpolate-missing-dir", ["query", "--type", "tool-holder", "--torque", "30", "--interpolate",
                                       "{w}/nodir/i.h5"], BAD, "does not exist"),
    ("downgrade-no-yes", ["db", "downgrade"], BAD, "add --yes"),
    ("downgrade-base-no-yes", ["db", "downgrade", "--to", "base"], BAD, "every table and all data"),
    ("downgrade-bogus", ["db", "downgrade", "--to", "bogus", "--yes"], BAD, "unknown revision"),
    ("downgrade-too-far", ["db", "downgrade", "--to", "-99", "--yes"], BAD, "cannot go 99 steps"),
    ("upgrade-bogus", ["db", "upgrade", "--to", "bogus"], BAD, "bogus"),
    ("gc-no-yes", ["db", "gc"], BAD, "--yes"),
    ("gc-negative-age", ["db", "gc", "--min-age", "-1", "--dry-run"], BAD, "--min-age"),
    ("audit-limit-zero", ["db", "audit", "--limit", "0"], BAD, "--limit"),
    ("keys-overwrite", ["keys", "create", "{w}/key"], CONFLICT, "already exists"),
    ("keys-missing-dir", ["keys", "create", "{w}/nodir/k"], BAD, "does not exist"),
]


@pytest.mark.parametrize("name, args, code, says", ARGS + BUNDLE_ARGS, ids=[a[0] for a in ARGS + BUNDLE_ARGS])
def test_bad_store_arguments_are_refused(name, args, code, says, world, unchanged, capsys):
    args = _sub(args, world)
    if args[0] != "keys":
        args += ["--db", str(world / "db.sqlite")]
    assert_one_line_error(run_main(capsys, *args), code, says)
    writer = args[:1] == ["catalogue"] or args[:2] == ["joints", "import"]
    if writer and code in (BAD, INTEGRITY):  # refused before a new database path is created
        args[args.index("--db") + 1] = str(world / "fresh.sqlite")
        assert_one_line_error(run_main(capsys, *args), code, says)
        assert not (world / "fresh.sqlite").exists()


def test_corpus_size():
    assert len(BUNDLES) + len(BUNDLE_ARGS) + len(TARGETS) + len(ARGS) >= 100


# ----------------------------------------------------------------------------- property-based
@settings(max_examples=200, deadline=None)
@given(st.text(max_size=60))
def test_any_label_text_is_accepted_exactly_when_it_is_a_label_name(text):
    import re

    from jointdb.store._types import check_label

    ok = re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,99}", text.strip()) is not None
    try:
        assert check_label(text) == text.strip() and ok
    except InputError as exc:
        assert not ok and "\n" not in str(exc)


@settings(max_examples=200, deadline=None)
@given(st.text(max_size=80))
def test_any_database_url_text_resolves_or_is_one_input_error(text):
    from jointdb.store._db import resolve_url

    try:
        url = resolve_url(text or "x")
    except InputError as exc:
        assert "\n" not in str(exc)
    else:
        assert url.startswith(("sqlite:///", "postgresql"))


@settings(max_examples=60, deadline=None)
@given(st.recursive(st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=8),
                    lambda kids: st.lists(kids, max_size=3) | st.dictionaries(st.text(max_size=6), kids, max_size=3),
                    max_leaves=12))
def test_any_json_as_labels_or_states_is_refused_or_valid(value):
    from jointdb.store._bundle_read import _check_labels, _check_states

    for check in (_check_labels, _check_states):
        try:
            check(value, 2, "bundle")
        except InputError as exc:
            assert "\n" not in str(exc)


def test_no_environment_leaks(world):
    assert "JOINTDB_URL" not in os.environ or os.environ["JOINTDB_URL"] != str(world)
