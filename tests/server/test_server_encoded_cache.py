"""The content-addressed cache of encoded FRF downloads (issue 26, item 4)."""

from __future__ import annotations

import hashlib

import pytest

from jointdb.server._encoded import EncodedCache

KEY = "ab" * 32


def counting(data: bytes):
    calls = []

    def encode():
        calls.append(1)
        return data

    return encode, calls


def test_encodes_once_then_memory_then_disk_across_instances(tmp_path):
    encode, calls = counting(b"frf-bytes")
    first = EncodedCache(tmp_path, tag="1.0")
    assert first.get(KEY, "hdf5", encode) == b"frf-bytes"
    assert first.get(KEY, "hdf5", encode) == b"frf-bytes"
    assert first.hits == {"memory": 1, "disk": 0, "encoded": 1}
    second = EncodedCache(tmp_path, tag="1.0")  # another worker process: the shared folder
    assert second.get(KEY, "hdf5", encode) == b"frf-bytes"
    assert second.hits["disk"] == 1 and len(calls) == 1
    other_version = EncodedCache(tmp_path, tag="2.0")  # another encoder version: encoded again
    assert other_version.get(KEY, "hdf5", encode) == b"frf-bytes" and len(calls) == 2
    assert EncodedCache(tmp_path, tag="1.0").get(KEY, "csv", encode) and len(calls) == 3


def test_an_altered_file_is_never_served(tmp_path):
    encode, calls = counting(b"the real bytes")
    EncodedCache(tmp_path, tag="t").get(KEY, "uff58", encode)
    (path,) = [p for p in tmp_path.iterdir() if not p.name.startswith(".")]
    digest = hashlib.sha256(b"forged").hexdigest().encode()
    path.write_bytes(b"0" * 64 + b"\nforged")  # wrong digest
    assert EncodedCache(tmp_path, tag="t").get(KEY, "uff58", encode) == b"the real bytes"
    path.write_bytes(digest + b"\nforgery")  # digest of other bytes
    assert EncodedCache(tmp_path, tag="t").get(KEY, "uff58", encode) == b"the real bytes"
    assert len(calls) == 3
    assert path.read_bytes().endswith(b"\nthe real bytes")  # re-written whole


def test_memory_budget_evicts_least_recently_used(tmp_path):
    cache = EncodedCache(None, memory_bytes=400)
    for i in range(6):
        cache.get(f"{i:02d}" * 16, "json", lambda i=i: bytes(90) + bytes([i]))
    assert sum(len(v) for v in cache._memory.values()) <= 400
    assert list(cache._memory)[0].startswith("02")  # 00 and 01 went first


def test_memory_only_when_the_folder_cannot_be_made(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    cache = EncodedCache(blocker / "sub")
    assert cache.folder is None
    assert cache.get(KEY, "csv", lambda: b"x") == b"x"


@pytest.mark.parametrize("key,fmt", [("../../etc/passwd", "csv"), (KEY, "../x"), ("AB" * 32, "csv")])
def test_refuses_keys_that_are_not_a_hash_and_a_format(tmp_path, key, fmt):
    with pytest.raises(ValueError):
        EncodedCache(tmp_path).get(key, fmt, lambda: b"")


def test_the_download_route_encodes_a_version_once(tmp_path, monkeypatch):
    import sys
    from pathlib import Path

    from fastapi.testclient import TestClient

    from jointdb.server import create_app
    from jointdb.server._settings import Settings
    from jointdb.store import Repository

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "store"))
    from store_helpers import spring_joint

    with Repository(tmp_path / "j.sqlite", blobs=tmp_path / "b") as repo:
        repo.catalogue("TH", "tool-holder", spring_joint(), {"torque_nm": 20.0}, "spring-damper-planar",
                       author="t")
        app = create_app(Settings(bind_host="127.0.0.1", open_reads=True, cache_dir=str(tmp_path / "c")),
                         repo=repo)
        with TestClient(app) as client:
            bodies = [client.get("/api/v1/joints/TH/versions/1/frf", params={"format": "uff58"}).content
                      for _ in range(3)]
        assert bodies[0] == bodies[1] == bodies[2] and len(bodies[0]) > 100
        assert app.state.encoded_cache.hits == {"memory": 2, "disk": 0, "encoded": 1}
        assert len([p for p in (tmp_path / "c").iterdir() if not p.name.startswith(".")]) == 1
