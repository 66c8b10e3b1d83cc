"""Blob store: canonical hash, HDF5 layout, corruption detection, check and gc."""

from __future__ import annotations

import hashlib
import os

import h5py
import numpy as np
import pytest
from store_helpers import planar_conditions, reseal, spring_joint

from jointdb.errors import IntegrityError, NotFoundError
from jointdb.frf import FRF
from jointdb.store import BlobStore, frf_sha256


def test_hash_is_the_documented_canonical_form():
    frf = spring_joint(n=5)
    expected = hashlib.sha256(
        b"jointdb-frf-v1\n"
        + b"receptance\n"
        + b"3x,3ry\n"
        + b"3x,3ry\n"
        + np.array([5, 2, 2], "<u8").tobytes()
        + frf.freq.astype("<f8").tobytes()
        + frf.values.astype("<c16").tobytes()
    ).hexdigest()
    assert frf_sha256(frf) == expected


def test_hash_sees_every_bit_and_label():
    frf = spring_joint(n=8)
    base = frf_sha256(frf)
    v = frf.values.copy()
    v[3, 0, 0] = np.nextafter(v[3, 0, 0].real, 1) + 1j * v[3, 0, 0].imag
    assert frf_sha256(frf.replace(values=v)) != base
    assert frf_sha256(frf.replace(outputs=["4x", "3ry"], inputs=["4x", "3ry"])) != base
    assert frf_sha256(FRF(frf.freq, frf.values, frf.outputs, frf.inputs, "receptance")) == base


def test_blob_layout_and_attributes(tmp_path):
    store = BlobStore(tmp_path / "b")
    frf = spring_joint(n=3000)
    digest = store.put(frf)
    path = store.path(digest)
    assert path == tmp_path / "b" / digest[:2] / f"{digest}.h5"
    with h5py.File(path, "r") as f:
        assert f.attrs["format"] == "jointdb-frf-blob" and f.attrs["format_version"] == 1
        assert f.attrs["sha256"] == digest
        assert "real" in f.attrs["complex_convention"]
        assert "exp(+i omega t)" in f.attrs["harmonic_convention"]
        ds = f["values"]
        assert ds.shuffle and ds.fletcher32 and ds.compression == "gzip"
        assert ds.chunks[0] < 3000 and ds.chunks[1:] == (2, 2, 2)  # chunked along frequency
    assert store.get(digest).allclose(frf, rtol=0)
    assert store.put(frf) == digest  # idempotent
    assert not store.temporaries()


def _flip_byte(path, where):
    data = bytearray(path.read_bytes())
    pos = int(len(data) * where)
    data[pos] ^= 0xFF
    path.write_bytes(bytes(data))


@pytest.mark.parametrize("where", [0.35, 0.6, 0.9])
def test_flipped_byte_is_detected_on_read_and_by_check(repo, where):
    jv = repo.catalogue("T1", "tool-holder", spring_joint(n=2000), planar_conditions(), "spring-damper-planar")
    repo.catalogue("T2", "tool-holder", spring_joint(k=(3e6, 9e4)), planar_conditions(), "spring-damper-planar")
    _flip_byte(repo.blobs.path(jv.blob_sha256), where)
    with pytest.raises(IntegrityError, match=jv.blob_sha256):
        repo.load_frf(jv)
    report = repo.check()
    assert not report.ok
    assert len(report.problems) == 1 and "T1 v1" in report.problems[0]


def test_value_rewritten_with_valid_checksums_is_caught_by_the_hash(tmp_path):
    """A value changed through HDF5 (chunk checksums recomputed) is caught by the file and content hashes."""
    store = BlobStore(tmp_path)
    frf = spring_joint(n=50)
    digest = store.put(frf)
    path = store.path(digest)
    os.chmod(path, 0o644)
    with h5py.File(path, "r+") as f:  # rewrite one value in place, HDF5 recomputes checksums
        v = f["values"][...]
        v[10, 0, 0, 0] *= 1.0000001
        f["values"][...] = v
    with pytest.raises(IntegrityError, match="file bytes do not match"):
        store.get(digest)
    # even with the whole-file checksum forged as well, the content hash catches it
    reseal(path)
    with pytest.raises(IntegrityError, match="hashes to"):
        store.get(digest)


def test_missing_blob_is_reported(repo):
    jv = repo.catalogue("T1", "tool-holder", spring_joint(), planar_conditions(), "spring-damper-planar")
    repo.blobs.path(jv.blob_sha256).unlink()
    with pytest.raises(NotFoundError, match="missing"):
        repo.load_frf(jv)
    report = repo.check()
    assert not report.ok and "missing" in report.problems[0]


def test_gc_removes_only_unreferenced_blobs(repo):
    jv = repo.catalogue("T1", "tool-holder", spring_joint(), planar_conditions(), "spring-damper-planar")
    orphan = repo.blobs.put(spring_joint(k=(9e6, 9e4)))
    tmp = repo.blobs.root / "ab" / ".tmp-deadbeef.h5"
    tmp.parent.mkdir(parents=True, exist_ok=True)
    tmp.write_bytes(b"half")
    report = repo.check()
    assert report.ok and report.orphan_blobs == (orphan,) and len(report.temporaries) == 1
    assert repo.gc(min_age_s=3600) == []  # too young: a catalogue may be about to commit its row
    assert set(repo.gc(min_age_s=0, dry_run=True)) == {orphan, str(tmp)}
    assert repo.blobs.exists(orphan)
    removed = repo.gc(min_age_s=0)
    assert set(removed) == {orphan, str(tmp)}
    assert not repo.blobs.exists(orphan) and not tmp.exists()
    assert repo.load_frf(jv).allclose(spring_joint(), rtol=0)
    assert repo.check().ok and not repo.check().orphan_blobs


def test_raw_measurements_are_stored_as_blobs(repo):
    raw = spring_joint(k=(1e7, 1e5), dofs=("1x", "1ry"))
    jv = repo.catalogue("T1", "tool-holder", spring_joint(), planar_conditions(), "spring-damper-planar",
                        raw_frfs={"tip": raw})
    assert set(jv.raw_blobs) == {"tip"}
    assert repo.load_raw(jv, "tip").allclose(raw, rtol=0)
    assert repo.check().blobs_checked == 2
    assert repo.gc(min_age_s=0) == []


def test_every_byte_of_a_blob_file_is_covered(tmp_path):
    """Flip one bit at every 37th byte of a blob file: each flip is detected (user-block checksum)."""
    store = BlobStore(tmp_path)
    digest = store.put(spring_joint(n=16))
    path = store.path(digest)
    data = path.read_bytes()
    missed = []
    for pos in range(0, len(data), 37):
        flipped = bytearray(data)
        flipped[pos] ^= 0x01
        path.write_bytes(bytes(flipped))
        if store.verify(digest) is None:
            missed.append(pos)
    path.write_bytes(data)
    assert store.verify(digest) is None
    assert missed == []


def _age(path, seconds=7200):
    import os
    import time

    t = time.time() - seconds
    os.utime(path, (t, t))


def test_put_of_an_old_orphan_refreshes_it_so_gc_spares_it(repo):
    frf = spring_joint(k=(9e6, 9e4))
    digest = repo.blobs.put(frf)
    _age(repo.blobs.path(digest))
    assert repo.gc(min_age_s=3600, dry_run=True) == [digest]
    assert repo.blobs.put(frf) == digest  # a catalogue found it stored ... and is about to commit its row
    assert repo.gc(min_age_s=3600) == []
    assert repo.blobs.exists(digest)


def test_gc_puts_a_blob_back_when_a_writer_references_it_meanwhile(repo):
    frf = spring_joint(k=(9e6, 9e4))
    digest = repo.blobs.put(frf)
    _age(repo.blobs.path(digest))

    def committed_meanwhile(d):  # the final check sees the writer's row
        return True

    assert repo.blobs.collect(digest, 3600, committed_meanwhile) is False
    assert repo.blobs.get(digest).allclose(frf, rtol=0)

    def writer_put_while_aside(d):  # the blob is set aside: put() must write a fresh copy
        assert not repo.blobs.exists(d)
        assert repo.blobs.put(frf) == d
        return False  # its row is not committed yet

    assert repo.blobs.collect(digest, 3600, writer_put_while_aside) is True  # the old copy is deleted ...
    assert repo.blobs.get(digest).allclose(frf, rtol=0)  # ... the writer's fresh copy stays
    assert not repo.blobs.temporaries()


def test_gc_restores_a_referenced_blob_an_interrupted_gc_set_aside(repo):
    jv = repo.catalogue("T1", "tool-holder", spring_joint(), planar_conditions(), "spring-damper-planar")
    path = repo.blobs.path(jv.blob_sha256)
    aside = path.parent / f".tmp-gc-{jv.blob_sha256}-0123.h5"
    path.rename(aside)
    _age(aside)
    assert not repo.check().ok
    repo.gc(min_age_s=0)
    assert repo.check().ok and not aside.exists()
    assert repo.load_frf(jv).allclose(spring_joint(), rtol=0)


def test_gc_racing_catalogues_of_an_old_stored_blob_never_loses_it(repo):
    """Writers re-catalogue an FRF whose blob is old and unreferenced while gc runs; no row may lose its blob."""
    import threading

    stop = threading.Event()
    errors: list[BaseException] = []

    def collector():
        try:
            while not stop.is_set():
                repo.gc(min_age_s=3600)
        except BaseException as exc:  # noqa: BLE001 - reported below
            errors.append(exc)

    t = threading.Thread(target=collector)
    t.start()
    try:
        for i in range(40):
            frf = spring_joint(k=(5e6 + 1e3 * i, 5e4))
            _age(repo.blobs.path(repo.blobs.put(frf)))  # stored earlier, now an old orphan: a gc candidate
            repo.catalogue(f"R{i}", "tool-holder", frf, planar_conditions(), "spring-damper-planar")
    finally:
        stop.set()
        t.join()
    assert not errors
    report = repo.check()
    assert report.ok, report.problems


def test_unwritable_blob_store_is_one_line_and_writes_no_row(repo, monkeypatch):
    import errno

    import jointdb.store._durable as durable_mod
    from jointdb.errors import InputError

    def refuse(path, data):  # the blob directory refuses the temporary file (as a read-only one would)
        open(path, "wb").close()  # even after creating it: nothing may be left behind
        raise PermissionError(errno.EACCES, "Permission denied")

    monkeypatch.setattr(durable_mod, "write_tmp", refuse)
    with pytest.raises(InputError, match="cannot write to the blob store .*Permission denied"):
        repo.catalogue("T1", "tool-holder", spring_joint(), planar_conditions(), "spring-damper-planar")
    monkeypatch.undo()
    assert repo.list_joints() == [] and not repo.blobs.temporaries()


def test_a_blob_collected_between_the_check_and_the_read_is_missing_and_put_rewrites_it(tmp_path, monkeypatch):
    """The race a fresh-clone run once hit: gc sets the blob aside after ``put`` found it but before it
    was read back. ``get`` must say NotFound (not leak FileNotFoundError) and ``put`` write a fresh copy."""
    import jointdb.store._blobs as blobs_mod

    store = BlobStore(tmp_path / "blobs")
    frf = spring_joint()
    digest = store.put(frf)
    real = blobs_mod.check_file_checksum
    calls = {"n": 0}

    def vanishing(path):
        calls["n"] += 1
        if calls["n"] == 1:                 # gc moves it aside just now
            os.replace(path, str(path) + ".aside")
        return real(path)

    monkeypatch.setattr(blobs_mod, "check_file_checksum", vanishing)
    with pytest.raises(NotFoundError):
        store.get(digest)
    calls["n"] = 0
    os.replace(str(store.path(digest)) + ".aside", store.path(digest))
    assert store.put(frf) == digest          # found, vanished while verified, rewritten
    monkeypatch.setattr(blobs_mod, "check_file_checksum", real)
    assert store.get(digest).allclose(frf, rtol=0)


def test_a_blob_that_does_not_read_back_is_never_put_in_place(repo, monkeypatch):
    """The bytes are verified while their temporary file is fsynced: bytes that do not decode to the
    FRF (a byte of the values' first HDF5 chunk flipped after encoding) drop the file."""
    import jointdb.store._blobs as blobs_mod

    real = blobs_mod.blob_bytes

    def garbled(frf, digest=None):
        digest, data = real(frf, digest)
        return digest, flip_in_values_chunk(data)

    monkeypatch.setattr(blobs_mod, "blob_bytes", garbled)
    frf = spring_joint()
    with pytest.raises(IntegrityError, match="did not read back"):
        repo.catalogue("T1", "tool-holder", frf, planar_conditions(), "spring-damper-planar")
    monkeypatch.undo()
    assert repo.list_joints() == [] and not repo.blobs.temporaries()
    assert not repo.blobs.exists(frf_sha256(frf)) and not list(repo.blobs.walk())


def flip_in_values_chunk(data: bytes) -> bytes:
    """The bytes of a blob file with one byte of the ``values`` dataset's first chunk flipped."""
    import io

    import h5py

    from jointdb.store._blobformat import USERBLOCK

    with h5py.File(io.BytesIO(data), "r") as f:
        chunk = f["values"].id.get_chunk_info(0)
    at = USERBLOCK + chunk.byte_offset + chunk.size // 2  # HDF5 addresses start after the user block
    return data[:at] + bytes([data[at] ^ 0x55]) + data[at + 1:]
