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


def write_frf_group(group, frf: FRF, digest: str) -> None:
    """Write an FRF into an open h5py group/file in the blob layout."""
    n_freq, n_out, n_in = frf.values.shape
    rows = _chunk_rows(n_freq, n_out * n_in)
    opts = dict(shuffle=True, compression="gzip", compression_opts=4, fletcher32=True)
    group.create_dataset("freq", data=np.asarray(frf.freq, dtype="<f8"), chunks=(rows,), **opts)
    packed = np.stack([frf.values.real, frf.values.imag], axis=-1).astype("<f8")
    group.create_dataset("values", data=packed, chunks=(rows, n_out, n_in, 2), **opts)
    a = group.attrs
    a["format"] = FORMAT
    a["format_version"] = FORMAT_VERSION
    a["sha256"] = digest
    a["quantity"] = frf.quantity.value
    a["outputs"] = ",".join(map(str, frf.outputs))
    a["inputs"] = ",".join(map(str, frf.inputs))
    a["complex_convention"] = COMPLEX_CONVENTION
    a["harmonic_convention"] = HARMONIC_CONVENTION


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
    values = packed[..., 0] + 1j * packed[..., 1]
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
        with _open_image(data) as f:
            a = f.attrs
            attrs = [str(a[k]) for k in ("format", "sha256", "quantity", "outputs", "inputs")]
            version = int(a["format_version"])
            freq, packed = f["freq"][...], f["values"][...]
    except (OSError, KeyError, ValueError) as exc:
        raise IntegrityError(f"{where} did not read back: {exc}") from None
    wanted = [FORMAT, digest, frf.quantity.value, ",".join(map(str, frf.outputs)), ",".join(map(str, frf.inputs))]
    values = np.stack([frf.values.real, frf.values.imag], axis=-1).astype("<f8")
    if (attrs != wanted or version != FORMAT_VERSION or len(data) <= USERBLOCK
            or freq.dtype != np.dtype("<f8") or freq.tobytes() != np.asarray(frf.freq, dtype="<f8").tobytes()
            or packed.dtype != np.dtype("<f8") or packed.shape != values.shape or packed.tobytes() != values.tobytes()):
        raise IntegrityError(f"{where} did not read back: the decoded FRF differs from the one encoded")


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
