"""One store protocol (issue 23): Repository and RemoteRepository implement JointStore, both blob
stores implement BlobStoreProtocol, method by method, so a signature that drifts fails here;
open_store opens either; the client imports no server code."""

from __future__ import annotations

import ast
import inspect
import subprocess
import sys
from pathlib import Path

import pytest

import jointdb
from jointdb.client import RemoteRepository
from jointdb.errors import InputError
from jointdb.store import (
    BlobStore,
    BlobStoreProtocol,
    JointStore,
    LocalJointStore,
    Repository,
    open_store,
    owned_store,
)
from jointdb.store._dbblobs import DatabaseBlobStore
from jointdb.store._protocol import protocol_methods


def _params(signature: inspect.Signature, drop_self: bool) -> list[tuple]:
    params = list(signature.parameters.values())[1 if drop_self else 0:]
    return [(p.name, p.kind, p.default) for p in params]


def signature_drift(protocol: type, implementation: object) -> list[str]:
    """Each method of ``protocol`` that ``implementation`` lacks or declares with other parameters
    (names, kinds, defaults, in order). An implementation may add keyword-only parameters with a
    default at the end (the repository's ``idempotency``): a caller of the protocol never passes them."""
    drift = []
    for name in protocol_methods(protocol):
        method = getattr(implementation, name, None)
        if not callable(method):
            drift.append(f"{name}: missing")
            continue
        want = _params(inspect.signature(getattr(protocol, name)), drop_self=True)
        have = _params(inspect.signature(method), drop_self=False)  # bound: no self
        extra = have[len(want):]
        if have[:len(want)] != want or any(k != inspect.Parameter.KEYWORD_ONLY or d is inspect.Parameter.empty
                                           for _, k, d in extra):
            drift.append(f"{name}: {have} != {want}")
    return drift


@pytest.fixture
def remote():
    r = RemoteRepository("http://127.0.0.1:9")  # never contacted
    yield r
    r.close()


def test_repository_implements_the_local_store_protocol(repo):
    assert isinstance(repo, JointStore) and isinstance(repo, LocalJointStore)
    assert signature_drift(LocalJointStore, repo) == []


def test_remote_repository_implements_the_store_protocol(remote):
    assert isinstance(remote, JointStore)
    assert not isinstance(remote, LocalJointStore)  # no paging, raw measurements, check or bundles over HTTP
    assert signature_drift(JointStore, remote) == []


def test_both_blob_stores_implement_the_blob_protocol(repo, tmp_path):
    for store in (BlobStore(tmp_path / "blobs"), DatabaseBlobStore(repo.write_engine)):
        assert isinstance(store, BlobStoreProtocol)
        assert signature_drift(BlobStoreProtocol, store) == []
    assert isinstance(repo.blobs, BlobStoreProtocol)


def test_a_drifted_signature_is_caught(remote):
    """The comparison can fail: a renamed, a re-defaulted or a missing parameter each show."""

    class Drifted(RemoteRepository):
        def get(self, joint, version=None, at=None, label=None):  # renamed first parameter
            raise NotImplementedError

        def audit(self, name=None, limit=50):  # another default
            raise NotImplementedError

        def interpolate(self, matches, conditions=None):  # method= dropped
            raise NotImplementedError

    drifted = Drifted("http://127.0.0.1:9")
    try:
        found = {d.split(":")[0] for d in signature_drift(JointStore, drifted)}
    finally:
        drifted.close()
    assert found == {"get", "audit", "interpolate"}
    assert signature_drift(LocalJointStore, remote)  # list_page, load_raw, check, ... missing


def test_open_store_opens_what_it_is_given(tmp_path, remote):
    db = tmp_path / "j.sqlite"
    with owned_store(db) as store:
        assert isinstance(store, Repository) and isinstance(store, JointStore)
    with owned_store(str(db)) as store:
        assert isinstance(store, Repository)
    assert open_store(remote) is remote
    with owned_store(remote) as store:  # not opened here: not closed here
        assert store is remote
    assert not remote._http.is_closed
    opened = open_store("https://jointdb.example", token="t")
    try:
        assert isinstance(opened, RemoteRepository) and opened.url == "https://jointdb.example"
    finally:
        opened.close()
    with pytest.raises(InputError, match="token is for a jointdb server"):
        open_store(db, token="t")
    with pytest.raises(InputError, match="not int"):
        open_store(3)


def test_open_store_reads_the_token_from_the_environment(monkeypatch):
    monkeypatch.setenv("JOINTDB_TOKEN", "secret-token")
    with owned_store("http://127.0.0.1:9") as store:
        assert store._http.headers["Authorization"] == "Bearer secret-token"


def test_the_client_imports_no_server_code():
    """Neither by its source (any import, anywhere in the file) nor at run time (no FastAPI)."""
    root = Path(jointdb.__file__).parent
    for path in (root / "client.py", root / "store" / "_remote.py", root / "io" / "_frfjson.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                     else [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
            assert not [n for n in names if n.split(".")[:2] in (["jointdb", "server"], ["jointdb", "cli"]) or n.startswith("fastapi")], path
    code = ("import sys, jointdb.client; jointdb.client.RemoteRepository('http://127.0.0.1:9').close(); "
            "bad = sorted(m for m in sys.modules if m.split('.')[:2] in (['jointdb', 'server'], ['jointdb', 'cli']) "
            "or m.startswith('fastapi')); "
            "print(bad); sys.exit(1 if bad else 0)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stdout + done.stderr


@pytest.mark.parametrize("module", ["_query", "_bundle", "_maintenance"])
def test_the_helpers_use_no_private_of_the_repository(module):
    """The query, bundle and maintenance helpers take narrow interfaces (ReadAccess, WriteAccess, a
    load_frf function), never the Repository facade or its private _read, _retrying, _joint."""
    path = Path(jointdb.__file__).parent / "store" / f"{module}.py"
    tree = ast.parse(path.read_text(encoding="utf-8"))
    privates = {n.attr for n in ast.walk(tree) if isinstance(n, ast.Attribute)} & {"_read", "_write", "_retrying",
                                                                                   "_joint", "_blob"}
    imported = {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)}
    assert not privates and "jointdb.store._repository" not in imported
