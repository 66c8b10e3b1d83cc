"""The blob encoder filters its chunks itself (shuffle, deflate, Fletcher-32) and writes them as they are:
the bytes must be exactly those HDF5's own filter pipeline writes (stored blobs are hashed and verified),
for every shape, edge chunks and incompressible data included."""

from __future__ import annotations

import hashlib
import uuid

import h5py
import numpy as np
import pytest

from jointdb.frf import FRF
from jointdb.store import _blobformat as bf


def _reference_group(group, frf: FRF, digest: str) -> None:
    """The blob layout written through h5py's high-level API and HDF5's filters (the encoder before
    chunks were filtered in Python, verbatim)."""
    n_freq, n_out, n_in = frf.values.shape
    rows = bf._chunk_rows(n_freq, n_out * n_in)
    opts = dict(shuffle=True, compression="gzip", compression_opts=4, fletcher32=True)
    group.create_dataset("freq", data=np.asarray(frf.freq, dtype="<f8"), chunks=(rows,), **opts)
    packed = np.stack([frf.values.real, frf.values.imag], axis=-1).astype("<f8")
    group.create_dataset("values", data=packed, chunks=(rows, n_out, n_in, 2), **opts)
    a = group.attrs
    a["format"] = bf.FORMAT
    a["format_version"] = bf.FORMAT_VERSION
    a["sha256"] = digest
    a["quantity"] = frf.quantity.value
    a["outputs"] = ",".join(map(str, frf.outputs))
    a["inputs"] = ",".join(map(str, frf.inputs))
    a["complex_convention"] = bf.COMPLEX_CONVENTION
    a["harmonic_convention"] = bf.HARMONIC_CONVENTION


def _image(write, frf: FRF, digest: str) -> bytes:
    with h5py.File(f"t-{uuid.uuid4().hex}", "w", driver="core", backing_store=False, userblock_size=bf.USERBLOCK) as f:
        write(f, frf, digest)
        f.flush()
        return f.id.get_file_image()


def _frf(rng, n: int, n_out: int, n_in: int, kind: str) -> FRF:
    freq = np.linspace(1.0, 1.0 + n, n) if kind != "random" else np.cumsum(rng.uniform(0.1, 3.0, n))
    if kind == "smooth":  # a spring-damper joint: compresses well
        w = 2 * np.pi * freq[:, None, None]
        k = rng.uniform(1e5, 1e8, (1, n_out, n_in))
        values = 1 / (k - 0.01 * w**2 + 1j * w * 50.0)
    elif kind == "zeros":
        values = np.zeros((n, n_out, n_in), complex)
    else:  # random mantissas: deflate barely helps (or not at all)
        values = rng.normal(size=(n, n_out, n_in)) + 1j * rng.normal(size=(n, n_out, n_in))
    return FRF(freq, values, [f"{i + 1}x" for i in range(n_out)], [f"{i + 1}ry" for i in range(n_in)],
               "mobility" if kind == "random" else "receptance")


SHAPES = [(1, 1, 1), (2, 1, 1), (7, 3, 2), (1000, 2, 2), (1024, 2, 2), (1025, 2, 2), (3001, 2, 2),
          (5000, 4, 4), (777, 6, 6), (20000, 1, 1), (4096, 1, 1), (40, 12, 12)]


@pytest.mark.parametrize("kind", ["smooth", "random", "zeros"])
@pytest.mark.parametrize("shape", SHAPES)
def test_the_encoder_writes_the_bytes_hdf5s_filters_write(shape, kind):
    frf = _frf(np.random.default_rng(hash((shape, kind)) % 2**32), *shape, kind)
    digest = bf.frf_sha256(frf)
    ours = _image(bf.write_frf_group, frf, digest)
    assert ours == _image(_reference_group, frf, digest)
    _, data = bf.blob_bytes(frf, digest)
    assert data[bf.USERBLOCK:] == ours
    back = bf.decode_blob_bytes(data, "test", digest)  # HDF5 reads it: checksums, filters, content hash
    assert back.values.tobytes() == frf.values.tobytes() and back.freq.tobytes() == frf.freq.tobytes()


def test_a_group_inside_a_file_too(tmp_path):
    """Bundles write the layout into groups of an ordinary file."""
    frf = _frf(np.random.default_rng(3), 1500, 2, 2, "smooth")
    digest = bf.frf_sha256(frf)
    files = []
    for write in (bf.write_frf_group, _reference_group):
        path = tmp_path / f"{write.__name__}.h5"
        with h5py.File(path, "w", track_order=True) as f:
            write(f.create_group("v1").create_group("frf"), frf, digest)
        files.append(path.read_bytes())
    assert files[0] == files[1]


def _fletcher32_c(data: bytes) -> int:
    """``H5_checksum_fletcher32`` transcribed word by word from HDF5's C source (H5checksum.c)."""
    length = len(data) // 2
    sum1 = sum2 = 0
    pos = 0
    while length:
        tlen = min(length, 360)
        length -= tlen
        for _ in range(tlen):
            sum1 += (data[pos] << 8) | data[pos + 1]
            pos += 2
            sum2 += sum1
        sum1 = (sum1 & 0xFFFF) + (sum1 >> 16)
        sum2 = (sum2 & 0xFFFF) + (sum2 >> 16)
    if len(data) % 2:
        sum1 += data[pos] << 8
        sum2 += sum1
        sum1 = (sum1 & 0xFFFF) + (sum1 >> 16)
        sum2 = (sum2 & 0xFFFF) + (sum2 >> 16)
    sum1 = (sum1 & 0xFFFF) + (sum1 >> 16)
    sum2 = (sum2 & 0xFFFF) + (sum2 >> 16)
    return (sum2 << 16) | sum1


@pytest.mark.parametrize("n", [0, 1, 2, 3, 719, 720, 721, 1440, 5001])
def test_fletcher32_is_hdf5s(n):
    rng = np.random.default_rng(n)
    for data in (rng.integers(0, 256, n, dtype=np.uint8).tobytes(), b"\xff" * n, b"\x00" * n):
        assert bf.fletcher32(data) == _fletcher32_c(data)


def test_a_changed_byte_of_a_chunk_is_refused_by_hdf5s_checksum():
    """The appended checksum is the one HDF5 checks: a flipped byte inside the values chunk is refused
    on read even when the whole-file hash is made to match."""
    frf = _frf(np.random.default_rng(5), 1000, 2, 2, "smooth")
    _, data = bf.blob_bytes(frf)
    with bf._open_image(data) as f:
        _, chunk = f["values"].id.read_direct_chunk((0, 0, 0, 0))
    at = data.find(chunk)
    assert at > bf.USERBLOCK and data.count(chunk) == 1
    body = bytearray(data)
    body[at + len(chunk) // 2] ^= 0x01
    tail = bytes(body[bf.USERBLOCK:])
    block = bf._userblock(hashlib.sha256(tail).hexdigest())  # a consistent whole-file hash: only HDF5 can tell
    with pytest.raises(bf.IntegrityError):
        bf.decode_blob_bytes(block + tail, "test")


@pytest.mark.parametrize("damage", ["no format_version", "no values", "values as float32", "other outputs",
                                    "other FRF"])
def test_verify_refuses_bytes_that_are_not_this_frf(damage):
    """verify_blob_bytes (low-level reads) refuses a missing attribute or dataset, another type, other
    labels or other numbers, with the message the write paths report."""
    frf = _frf(np.random.default_rng(7), 300, 2, 2, "smooth")
    digest = bf.frf_sha256(frf)

    def write(f, x, d):
        _reference_group(f, x, d)
        if damage == "no format_version":
            del f.attrs["format_version"]
        elif damage == "no values":
            del f["values"]
        elif damage == "values as float32":
            data = f["values"][...]
            del f["values"]
            f.create_dataset("values", data=data.astype("<f4"))
        elif damage == "other outputs":
            f.attrs["outputs"] = "3x,3y"

    other = _frf(np.random.default_rng(8), 300, 2, 2, "smooth") if damage == "other FRF" else frf
    body = _image(write, other, digest)
    data = bf._userblock(hashlib.sha256(body).hexdigest()) + body
    with pytest.raises(bf.IntegrityError, match="did not read back"):
        bf.verify_blob_bytes(data, frf, digest)
    bf.verify_blob_bytes(bf.blob_bytes(frf, digest)[1], frf, digest)  # and the true bytes pass
