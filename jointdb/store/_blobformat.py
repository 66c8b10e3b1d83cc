"""The FRF blob format: canonical content hash, HDF5 layout, whole-file checksum; encode and decode.

Canonical form (what the SHA-256 is computed over, format version 1), the
concatenation of:

1. the ASCII bytes ``b"jointdb-frf-v1\\n"``;
2. ``quantity`` (``receptance``/``mobility``/``accelerance``) in UTF-8, then ``b"\\n"``;
3. the output DOF labels as text (``"3x,3ry"``) in UTF-8, then ``b"\\n"``;
4. the input DOF labels likewise, then ``b"\\n"``;
5. ``n_freq, n_out, n_in`` as three little-endian uint64;
6. the frequencies as little-endian float64 (``<f8``), ``n_freq`` values;
7. the values as little-endian complex128 (``<c16``: real then imaginary part
   of each entry), C order of the ``(n_freq, n_out, n_in)`` array.

So two FRFs hash equal exactly when labels, quantity and every bit of the
numbers are equal. The blob file is ``<root>/<h[:2]>/<h>.h5``.

HDF5 layout: dataset ``freq`` (float64, Hz) and dataset ``values`` (float64,
shape ``(n_freq, n_out, n_in, 2)``, last axis = (real, imaginary)), both chunked
along frequency with shuffle + gzip + fletcher32. Root attributes:
``format = "jointdb-frf-blob"``, ``format_version = 1``, ``sha256``,
``quantity``, ``outputs``, ``inputs``, ``complex_convention`` and
``harmonic_convention = "x(t) = X exp(+i omega t)"``.

Whole-file checksum: the file starts with a 512-byte HDF5 *user block*
(ignored by HDF5 readers) holding ``b"jointdb-blob-file-sha256:" + <64 hex> +
b"\n"`` followed by zero bytes; the digest is the SHA-256 of every byte after
the user block. So every single byte of a blob file is covered: the user block
must match exactly, the rest must hash to the recorded digest, the HDF5 chunks
carry fletcher32 and the decoded FRF must hash to the blob's name.

A blob file's bytes are built in memory (:func:`blob_bytes`: HDF5's core driver,
then the user block) and decoded with every check of a read
(:func:`decode_blob_bytes`); :mod:`jointdb.store._blobs` stores them.
"""

from __future__ import annotations

import functools
import hashlib
import os
import re
import uuid

import numpy as np

from jointdb.errors import InputError, IntegrityError
from jointdb.frf import FRF

FORMAT = "jointdb-frf-blob"
FORMAT_VERSION = 1
COMPLEX_CONVENTION = "values[..., 0] = real part, values[..., 1] = imaginary part"
HARMONIC_CONVENTION = "x(t) = X exp(+i omega t)"
USERBLOCK = 512
_FILE_MAGIC = b"jointdb-blob-file-sha256:"
_HEX64 = re.compile(r"[0-9a-f]{64}")


def check_digest(digest: str) -> str:
    """``digest`` when it is 64 lower-case hex digits (what both blob stores key blobs by).

    Raises
    ------
    IntegrityError
        It is not a SHA-256 hex digest (often read from the database: never used to build a
        path or a query).
    """
    if not isinstance(digest, str) or not _HEX64.fullmatch(digest):
        raise IntegrityError(f"blob digest {str(digest)[:80]!r} is not a SHA-256 hex digest; refusing to use it")
    return digest


def frf_sha256(frf: FRF) -> str:
    """SHA-256 (hex) of the canonical form of an FRF (module docstring).

    Parameters
    ----------
    frf
        The FRF (its quantity, labels, shape, lines and values enter the hash).

    Returns
    -------
    str
        64 hex digits.
    """
    h = hashlib.sha256()
    h.update(b"jointdb-frf-v1\n")
    h.update(frf.quantity.value.encode() + b"\n")
    h.update(",".join(map(str, frf.outputs)).encode() + b"\n")
    h.update(",".join(map(str, frf.inputs)).encode() + b"\n")
    h.update(np.asarray(frf.values.shape, dtype="<u8").tobytes())
    h.update(np.ascontiguousarray(frf.freq, dtype="<f8").tobytes())
    h.update(np.ascontiguousarray(frf.values, dtype="<c16").tobytes())
    return h.hexdigest()


def file_sha256(path: str | os.PathLike) -> str:
    """SHA-256 (hex) of a file's bytes (for provenance ``input_files``).

    Parameters
    ----------
    path
        The file.

    Returns
    -------
    str
        64 hex digits.
    """
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def _chunk_rows(n_freq: int, n_entries: int) -> int:
    # about 64 KiB per chunk, along frequency
    return max(1, min(n_freq, (1 << 16) // max(1, 16 * n_entries)))


#: the filters of both datasets, in HDF5's order: shuffle, deflate (gzip) at this level, fletcher32
GZIP_LEVEL = 4


def _new_dataset(gid, name: str, shape: tuple, chunks: tuple):
    """A new float64 dataset (low-level id) as h5py's ``create_dataset(name, shape, "<f8", chunks=chunks,
    shuffle=True, compression="gzip", compression_opts=GZIP_LEVEL, fletcher32=True)`` makes it: the same
    creation properties in the same order (chunks, shuffle, deflate, fletcher32, no times)."""
    from h5py import h5d, h5p, h5s, h5t

    dcpl = h5p.create(h5p.DATASET_CREATE)
    dcpl.set_chunk(chunks)
    dcpl.set_shuffle()
    dcpl.set_deflate(GZIP_LEVEL)
    dcpl.set_fletcher32()
    dcpl.set_obj_track_times(False)
    return h5d.create(gid, name.encode(), h5t.py_create(np.dtype("<f8"), logical=1), h5s.create_simple(shape),
                      dcpl=dcpl)


def write_frf_group(group, frf: FRF, digest: str) -> None:
    """Write an FRF into an open h5py group/file in the blob layout.

    The chunks are filtered here (:func:`_filtered_chunk`: shuffle, deflate, fletcher32, as
    HDF5's own filters do it, byte for byte) and written as they are (``write_direct_chunk``):
    the deflate runs without Python's global lock, so a blob encoded on a worker thread lets
    the caller's thread run meanwhile. (HDF5 keeps a deflated chunk even when it came out larger
    than the raw one, as here; ``tests/store/test_store_blob_encoding.py`` compares the bytes.)
    """
    n_freq, n_out, n_in = frf.values.shape
    rows = _chunk_rows(n_freq, n_out * n_in)
    freq = np.asarray(frf.freq, dtype="<f8")
    packed = np.stack([frf.values.real, frf.values.imag], axis=-1).astype("<f8")
    for name, data in (("freq", freq), ("values", packed)):
        dset = _new_dataset(group.id, name, data.shape, (rows, *data.shape[1:]))
        zeros = (0,) * (data.ndim - 1)
        for i in range(0, n_freq, rows):
            dset.write_direct_chunk((i, *zeros), _filtered_chunk(data[i:i + rows], rows))
    _write_attrs(group.id, (("format", FORMAT), ("format_version", FORMAT_VERSION), ("sha256", digest),
                            ("quantity", frf.quantity.value), ("outputs", ",".join(map(str, frf.outputs))),
                            ("inputs", ",".join(map(str, frf.inputs))), ("complex_convention", COMPLEX_CONVENTION),
                            ("harmonic_convention", HARMONIC_CONVENTION)))


def _filtered_chunk(block: np.ndarray, rows: int) -> bytes:
    """One chunk of ``rows`` rows (an edge chunk padded with HDF5's fill value, zeros) as HDF5's filters
    store it: the bytes shuffled (all first bytes of the float64 values, then all second bytes, ...),
    deflated at :data:`GZIP_LEVEL` (zlib format), then HDF5's Fletcher-32 checksum appended
    (little-endian)."""
    import zlib

    if len(block) < rows:
        full = np.zeros((rows, *block.shape[1:]), dtype="<f8")
        full[:len(block)] = block
        block = full
    raw = np.ascontiguousarray(block, dtype="<f8").view(np.uint8).reshape(-1, 8)
    deflated = zlib.compress(raw.T.tobytes(), GZIP_LEVEL)  # (zlib lets go of the GIL while it deflates)
    return deflated + fletcher32(deflated).to_bytes(4, "little")


def fletcher32(data: bytes) -> int:
    """HDF5's Fletcher-32 checksum (``H5_checksum_fletcher32``) of ``data``.

    Parameters
    ----------
    data
        The bytes (read as big-endian 16-bit words; an odd last byte as the high byte of one more).

    Returns
    -------
    int
        The 32-bit checksum: ``sum2 << 16 | sum1``, both reduced as HDF5 does (end-around carry
        after every 360 words and at the end).
    """
    n = len(data)
    words = np.frombuffer(data, dtype=">u2", count=n // 2).astype(np.int64)
    blocks = max(1, -(-len(words) // 360))
    grid = np.zeros(blocks * 360, np.int64)
    grid[:len(words)] = words
    grid = grid.reshape(blocks, 360)
    lengths = np.full(blocks, 360, np.int64)
    lengths[-1] = len(words) - 360 * (blocks - 1)
    # per block of t words w_k: sum1 grows by sum(w), sum2 by t*sum1 + sum_k (t - k) w_k (no overflow in 64 bits)
    sums = grid.sum(axis=1).tolist()
    weighted = (grid * (lengths[:, None] - np.arange(360))).sum(axis=1).tolist()
    s1 = s2 = 0
    for t, w, v in zip(lengths.tolist(), sums, weighted):
        if t:
            s2 += t * s1 + v
            s1 += w
            s1, s2 = (s1 & 0xFFFF) + (s1 >> 16), (s2 & 0xFFFF) + (s2 >> 16)
    if n % 2:
        s1 += data[-1] << 8
        s2 += s1
        s1, s2 = (s1 & 0xFFFF) + (s1 >> 16), (s2 & 0xFFFF) + (s2 >> 16)
    s1, s2 = (s1 & 0xFFFF) + (s1 >> 16), (s2 & 0xFFFF) + (s2 >> 16)
    return (s2 << 16) | s1


def _write_attrs(gid, items) -> None:
    """Scalar attributes on the object ``gid`` (a low-level h5py id), each as h5py's ``attrs[name] = value``
    writes it on a new object (a ``str`` as a variable-length UTF-8 string, an ``int`` as int64)."""
    import h5py

    types = _attr_types()
    scalar = h5py.h5s.create_simple(())
    for name, value in items:
        kind = "str" if isinstance(value, str) else "int"
        data = np.array(value, dtype=types[kind][0])
        attr = h5py.h5a.create(gid, name.encode(), types[kind][1], scalar)
        try:
            attr.write(data, mtype=types[kind][2])
        finally:
            attr.close()


@functools.cache
def _attr_types() -> dict:
    """``{kind: (numpy dtype, HDF5 type stored, HDF5 type written from)}`` as h5py chooses them for a
    ``str`` and an ``int`` attribute."""
    import h5py
    from h5py import h5t

    out = {}
    for kind, dtype in (("str", h5py.string_dtype()), ("int", np.dtype(np.int64))):
        out[kind] = (dtype, h5t.py_create(dtype, logical=True), h5t.py_create(dtype))
    return out


def read_frf_group(group, where: str) -> tuple[FRF, str]:
    """Read an FRF from a group in the blob layout; returns ``(frf, stored_sha256)``."""
    a = group.attrs
    if str(a.get("format", "")) != FORMAT:
        raise IntegrityError(f"{where}: not a jointdb FRF blob (format attribute {a.get('format')!r})")
    version = int(a.get("format_version", 0))
    if version > FORMAT_VERSION:
        raise IntegrityError(f"{where}: blob format version {version} is newer than this jointdb ({FORMAT_VERSION})")
    freq = np.asarray(group["freq"][...], dtype=np.float64)
    packed = np.asarray(group["values"][...], dtype=np.float64)
    values = np.empty(packed.shape[:-1], dtype=np.complex128)  # not re + 1j·im: that turns a −0.0 part into +0.0,
    values.real, values.imag = packed[..., 0], packed[..., 1]  # and the content would no longer hash to its name
    outputs = [s for s in str(a["outputs"]).split(",") if s]
    inputs = [s for s in str(a["inputs"]).split(",") if s]
    frf = FRF(freq, values, outputs, inputs, str(a["quantity"]))
    return frf, str(a.get("sha256", ""))


def _userblock(file_digest: str) -> bytes:
    head = _FILE_MAGIC + file_digest.encode() + b"\n"
    return head + b"\0" * (USERBLOCK - len(head))


def blob_bytes(frf: FRF, digest: str | None = None) -> tuple[str, bytes]:
    """``(content hash, bytes of the blob file)`` of an FRF, built in memory.

    The HDF5 layout is written once, by HDF5's in-memory (core) driver, and its
    image is hashed for the user block: exactly the bytes :func:`write_frf_file`
    puts in a file, without writing, re-opening and re-reading one.
    """
    import h5py

    digest = digest or frf_sha256(frf)
    # a unique name: HDF5 refuses to create a file (even one without a backing store) that is open
    with h5py.File(f"jointdb-blob-{uuid.uuid4().hex}", "w", driver="core", backing_store=False,
                   userblock_size=USERBLOCK) as f:
        write_frf_group(f, frf, digest)
        f.flush()
        body = f.id.get_file_image()  # the file after its user block
    return digest, _userblock(hashlib.sha256(body).hexdigest()) + body


def _open_image(data: bytes):
    """An HDF5 file opened read-only on the bytes of a blob file, in memory (``with`` it)."""
    import h5py

    fapl = h5py.h5p.create(h5py.h5p.FILE_ACCESS)
    fapl.set_fapl_core(backing_store=False)
    fapl.set_file_image(data)
    name = f"jointdb-blob-{uuid.uuid4().hex}".encode()
    return h5py.File(h5py.h5f.open(name, h5py.h5f.ACC_RDONLY, fapl=fapl))


def decode_blob_bytes(data: bytes, where: str, digest: str | None = None) -> FRF:
    """The FRF in the bytes of a blob file, every check of a read applied (module docstring).

    Raises
    ------
    IntegrityError
        The user block is damaged, a byte differs from the whole-file hash, HDF5 cannot
        read it (a chunk checksum fails) or the decoded FRF does not hash to its
        ``sha256`` attribute (or to ``digest``, when given: the blob's name).
    """
    _check_userblock(data[:USERBLOCK], hashlib.sha256(memoryview(data)[USERBLOCK:]).hexdigest(), f"{where} is corrupt")
    try:
        with _open_image(data) as f:
            frf, stored = read_frf_group(f, where)
    except (OSError, KeyError, ValueError) as exc:  # a stored blob that does not validate is corrupt too
        raise IntegrityError(f"{where} is corrupt: {exc}") from None
    actual = frf_sha256(frf)
    if actual != stored:
        raise IntegrityError(f"{where} is corrupt: content hash does not match the stored sha256 attribute")
    if digest is not None and actual != digest:
        raise IntegrityError(f"{where} is corrupt: its content hashes to {actual}")
    return frf


def verify_blob_bytes(data: bytes, frf: FRF, digest: str) -> None:
    """Check that the bytes :func:`blob_bytes` just built for ``frf`` read back as ``frf``, bit for bit.

    HDF5 decodes them (every chunk's fletcher32 checksum, the filters) and the arrays and
    attributes read are compared with the FRF's own: the same guarantee as decoding them with
    :func:`decode_blob_bytes` and comparing content hashes, without hashing again what was just
    hashed (the content hash and the whole-file hash of these bytes are :func:`blob_bytes`' own).

    Parameters
    ----------
    data
        The blob file's bytes, as :func:`blob_bytes` returned them.
    frf
        The FRF they were built from.
    digest
        Its content hash (the blob's name; also the ``sha256`` attribute written).

    Raises
    ------
    IntegrityError
        The bytes do not read back (HDF5 refuses them) or read back as anything else.
    """
    where = f"blob {digest}"
    try:
        with _open_image(data) as f:  # h5py's low-level calls: the same reads, a third of the time
            fid = f.id
            attrs = [_attr_text(fid, k) for k in ("format", "sha256", "quantity", "outputs", "inputs")]
            version = int(_attr_value(fid, "format_version"))
            freq, packed = _dataset(fid, "freq"), _dataset(fid, "values")
    except (OSError, KeyError, ValueError) as exc:
        raise IntegrityError(f"{where} did not read back: {exc}") from None
    wanted = [FORMAT, digest, frf.quantity.value, ",".join(map(str, frf.outputs)), ",".join(map(str, frf.inputs))]
    values = np.stack([frf.values.real, frf.values.imag], axis=-1).astype("<f8")
    if (attrs != wanted or version != FORMAT_VERSION or len(data) <= USERBLOCK
            or freq.dtype != np.dtype("<f8") or freq.tobytes() != np.asarray(frf.freq, dtype="<f8").tobytes()
            or packed.dtype != np.dtype("<f8") or packed.shape != values.shape or packed.tobytes() != values.tobytes()):
        raise IntegrityError(f"{where} did not read back: the decoded FRF differs from the one encoded")


def _attr_value(oid, name: str):
    """A scalar attribute of the object ``oid`` (low-level h5py id), as HDF5 stores it (KeyError: none)."""
    import h5py

    if not h5py.h5a.exists(oid, name.encode()):
        raise KeyError(f"no attribute {name!r}")
    attr = h5py.h5a.open(oid, name.encode())
    try:
        value = np.empty(attr.shape, dtype=attr.dtype)
        attr.read(value)
    finally:
        attr.close()
    return value[()]


def _attr_text(oid, name: str) -> str:
    """A text attribute as ``str(group.attrs[name])`` gives it (UTF-8 bytes decoded as h5py does)."""
    value = _attr_value(oid, name)
    return value.decode("utf-8", "surrogateescape") if isinstance(value, bytes) else str(value)


def _dataset(fid, name: str) -> np.ndarray:
    """The whole dataset ``name`` of the root group, decoded by HDF5 (filters, checksums)."""
    import h5py

    dset = h5py.h5d.open(fid, name.encode())
    try:
        out = np.empty(dset.shape, dtype=dset.dtype)
        dset.read(h5py.h5s.ALL, h5py.h5s.ALL, out)
    finally:
        dset.close()
    return out


def write_frf_file(path: str | os.PathLike, frf: FRF) -> str:
    """Write one FRF to an HDF5 file in the blob layout (no atomicity).

    Parameters
    ----------
    path
        The file to write.
    frf
        The FRF.

    Returns
    -------
    str
        Its content hash (:func:`frf_sha256`).
    """
    digest, data = blob_bytes(frf)
    with open(path, "wb") as fh:
        fh.write(data)
    return digest


def check_file_checksum(path: str | os.PathLike) -> None:
    """Verify the whole-file checksum in the user block (module docstring).

    Raises
    ------
    IntegrityError
        If the user block is damaged or any later byte changed.
    """
    with open(path, "rb") as raw:
        block = raw.read(USERBLOCK)
        h = hashlib.sha256()
        for chunk in iter(lambda: raw.read(1 << 20), b""):
            h.update(chunk)
    _check_userblock(block, h.hexdigest(), str(path))


def _check_userblock(block: bytes, body_sha256: str, where: str) -> None:
    """The user block is intact and records ``body_sha256``, the hash of the bytes after it (IntegrityError)."""
    recorded = block[len(_FILE_MAGIC):len(_FILE_MAGIC) + 64].decode("ascii", "replace")
    if len(block) != USERBLOCK or not block.startswith(_FILE_MAGIC) or block != _userblock(recorded):
        raise IntegrityError(f"{where}: file checksum header is damaged or missing")
    if body_sha256 != recorded:
        raise IntegrityError(f"{where}: file bytes do not match their recorded SHA-256 (corrupt file)")


def read_frf_file(path: str | os.PathLike, verify: bool = True) -> FRF:
    """Read a file written by :func:`write_frf_file`.

    Parameters
    ----------
    path
        The file.
    verify
        Check the whole-file checksum and the content hash.

    Returns
    -------
    FRF
        The FRF the file holds (with ``verify``, bit for bit the one written).

    Raises
    ------
    IntegrityError
        A damaged file, or a content hash that does not match.
    """
    import h5py

    where = str(path)
    if verify:
        check_file_checksum(path)
    try:
        with h5py.File(path, "r", locking=False) as f:
            frf, stored = read_frf_group(f, where)  # InputError (e.g. NaN values) propagates
    except (OSError, KeyError) as exc:
        raise IntegrityError(f"{where}: cannot read FRF blob ({exc})") from None
    except ValueError as exc:
        if isinstance(exc, InputError):
            raise InputError(f"{where}: {exc}") from None
        raise IntegrityError(f"{where}: cannot read FRF blob ({exc})") from None
    if verify and frf_sha256(frf) != stored:
        raise IntegrityError(f"{where}: content hash does not match the stored sha256 attribute")
    return frf
