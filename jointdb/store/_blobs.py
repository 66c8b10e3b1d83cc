"""Content-addressed, durable, verified HDF5 blob store for FRFs.

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

Writes go to a temporary file in the same directory, are fsynced, atomically
renamed, the directory fsynced, then read back and verified. Reads always
verify all of the above.
"""

from __future__ import annotations

import hashlib
import os
import re
import time
import uuid
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from jointdb.errors import InputError, IntegrityError, NotFoundError
from jointdb.io._atomic import fsync_dir as _fsync_dir
from jointdb.frf import FRF

__all__ = ["BlobStore", "frf_sha256", "file_sha256", "FORMAT_VERSION", "write_frf_file", "read_frf_file"]

FORMAT = "jointdb-frf-blob"
FORMAT_VERSION = 1
COMPLEX_CONVENTION = "values[..., 0] = real part, values[..., 1] = imaginary part"
HARMONIC_CONVENTION = "x(t) = X exp(+i omega t)"
_TMP_PREFIX = ".tmp-"
_GC_PREFIX = _TMP_PREFIX + "gc-"  # a blob `gc` moved aside for its last check: ".tmp-gc-<sha>-<uuid>.h5"
USERBLOCK = 512
_FILE_MAGIC = b"jointdb-blob-file-sha256:"
_HEX64 = re.compile(r"[0-9a-f]{64}")


def frf_sha256(frf: FRF) -> str:
    """SHA-256 (hex) of the canonical form of an FRF (module docstring)."""
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
    """SHA-256 (hex) of a file's bytes (for provenance ``input_files``)."""
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


def write_frf_file(path: str | os.PathLike, frf: FRF) -> str:
    """Write one FRF to an HDF5 file in the blob layout (no atomicity); returns its content hash."""
    import h5py

    digest = frf_sha256(frf)
    with h5py.File(path, "w", userblock_size=USERBLOCK, locking=False) as f:
        write_frf_group(f, frf, digest)
    with open(path, "r+b") as raw:
        raw.seek(USERBLOCK)
        h = hashlib.sha256()
        for chunk in iter(lambda: raw.read(1 << 20), b""):
            h.update(chunk)
        raw.seek(0)
        raw.write(_userblock(h.hexdigest()))
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
    if len(block) != USERBLOCK or not block.startswith(_FILE_MAGIC):
        raise IntegrityError(f"{path}: file checksum header is damaged or missing")
    recorded = block[len(_FILE_MAGIC):len(_FILE_MAGIC) + 64].decode("ascii", "replace")
    if block != _userblock(recorded):
        raise IntegrityError(f"{path}: file checksum header is damaged")
    if h.hexdigest() != recorded:
        raise IntegrityError(f"{path}: file bytes do not match their recorded SHA-256 (corrupt file)")


def read_frf_file(path: str | os.PathLike, verify: bool = True) -> FRF:
    """Read a file written by :func:`write_frf_file` (file checksum and content hash verified)."""
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


@dataclass(frozen=True)
class BlobInfo:
    sha256: str
    path: Path
    size: int
    mtime: float


class BlobStore:
    """Content-addressed FRF blobs in a directory (module docstring for the format).

    Parameters
    ----------
    root
        Directory holding the blobs (created on first write).
    """

    def __init__(self, root: str | os.PathLike):
        self.root = Path(root)

    def __repr__(self) -> str:
        return f"BlobStore({str(self.root)!r})"

    def path(self, digest: str) -> Path:
        """File of a blob; the digest (often read from the database) must be 64 lower-case hex digits.

        Raises
        ------
        IntegrityError
            ``digest`` is not a SHA-256 hex digest (never used to build a path).
        """
        if not isinstance(digest, str) or not _HEX64.fullmatch(digest):
            raise IntegrityError(f"blob digest {str(digest)[:80]!r} is not a SHA-256 hex digest; refusing to use it")
        return self.root / digest[:2] / f"{digest}.h5"

    def exists(self, digest: str) -> bool:
        return self.path(digest).is_file()

    # ------------------------------------------------------------------ write
    def put(self, frf: FRF) -> str:
        """Store an FRF durably; return its SHA-256. Idempotent (existing verified blob kept).

        Raises
        ------
        IntegrityError
            If the read-back does not verify.
        InputError
            The blob directory refuses the write.
        """
        return self.put_pending(frf).wait()

    def put_pending(self, frf: FRF) -> "PendingPut":
        """Start storing an FRF: written and verified now, made durable in the background.

        The FRF is written to a temporary file and read back and verified here;
        the flush to disk (fsync), the rename into place and the directory fsync
        run in a thread, so that a caller can prepare its database transaction
        meanwhile. :meth:`PendingPut.wait` returns the digest once the blob is
        durable (and raises what the thread met); call it before committing
        anything that references the blob, and always (it also joins the thread).
        """
        digest = frf_sha256(frf)
        final = self.path(digest)
        try:
            # Refresh the age first: `gc` spares young blobs and re-checks the age after
            # moving a blob aside, so a blob this writer is about to reference survives.
            os.utime(final)
        except FileNotFoundError:
            pass  # not there (or just collected): write it below
        else:
            try:
                self.get(digest)
                return PendingPut(digest)
            except (IntegrityError, NotFoundError):
                pass  # corrupt or collected meanwhile: rewrite it atomically below
        new_dir = not final.parent.is_dir()
        tmp = final.parent / f"{_TMP_PREFIX}{uuid.uuid4().hex}.h5"
        try:
            final.parent.mkdir(parents=True, exist_ok=True)
            write_frf_file(tmp, frf)
            _verify_file(tmp, digest)  # read back and verify before it can be referenced
        except OSError as exc:  # read-only or full blob directory: one line for the user, nothing kept
            tmp.unlink(missing_ok=True)
            raise InputError(f"cannot write to the blob store {self.root}: {exc.strerror or exc}") from None
        except BaseException:
            tmp.unlink(missing_ok=True)
            raise

        def finish() -> None:
            try:
                fd = os.open(tmp, os.O_RDONLY)
                try:
                    os.fsync(fd)
                finally:
                    os.close(fd)
                os.replace(tmp, final)
            except OSError as exc:
                raise InputError(f"cannot write to the blob store {self.root}: {exc.strerror or exc}") from None
            finally:
                if tmp.exists():
                    tmp.unlink()
            _fsync_dir(final.parent)  # the rename is durable
            if new_dir:
                _fsync_dir(self.root)  # and so is the new shard directory

        return PendingPut(digest, finish)

    # ------------------------------------------------------------------- read
    def get(self, digest: str) -> FRF:
        """Read and verify a blob.

        Raises
        ------
        NotFoundError
            If the blob file is missing.
        IntegrityError
            If it cannot be read, a chunk checksum fails, or the hash differs.
        """
        path = self.path(digest)
        if not path.is_file():
            raise NotFoundError(f"blob {digest} is missing (expected at {path})")
        try:
            check_file_checksum(path)
            frf = read_frf_file(path, verify=False)
        except FileNotFoundError:  # collected (set aside by gc) between the check above and the read
            raise NotFoundError(f"blob {digest} is missing (expected at {path})") from None
        except InputError as exc:  # a stored blob that no longer validates is corrupt
            raise IntegrityError(f"blob {digest} is corrupt: {exc}") from None
        actual = frf_sha256(frf)
        if actual != digest:
            raise IntegrityError(f"blob {digest} is corrupt: its content hashes to {actual} ({path})")
        return frf

    def verify(self, digest: str) -> str | None:
        """None when the blob is present and intact, else a one-line problem description."""
        try:
            self.get(digest)
        except (NotFoundError, IntegrityError) as exc:
            return str(exc)
        return None

    # ------------------------------------------------------------------ walk
    def walk(self) -> Iterator[BlobInfo]:
        """All finished blobs in the store."""
        if not self.root.is_dir():
            return
        for sub in sorted(self.root.iterdir()):
            if not sub.is_dir() or len(sub.name) != 2:
                continue
            for p in sorted(sub.glob("*.h5")):
                if p.name.startswith(_TMP_PREFIX) or not _HEX64.fullmatch(p.stem):
                    continue
                st = p.stat()
                yield BlobInfo(p.stem, p, st.st_size, st.st_mtime)

    def temporaries(self) -> list[Path]:
        """Left-over temporary files of interrupted writes."""
        if not self.root.is_dir():
            return []
        return sorted(self.root.glob(f"*/{_TMP_PREFIX}*"))

    def remove(self, digest: str) -> None:
        """Delete one blob file unconditionally (tests and repairs; ``gc`` uses :meth:`collect`)."""
        path = self.path(digest)
        path.unlink(missing_ok=True)
        _fsync_dir(path.parent)

    def collect(self, digest: str, min_age_s: float, still_referenced) -> bool:
        """Delete an unreferenced blob without racing a writer that is about to reference it.

        The blob is first renamed aside (so a concurrent :meth:`put` no longer finds it
        and writes a fresh copy), then ``still_referenced(digest)`` is asked again and
        the age re-read (a :meth:`put` that found the blob just before refreshed it).
        If either says keep, the blob is put back; otherwise it is deleted.
        Returns True when deleted.
        """
        path = self.path(digest)
        aside = path.parent / f"{_GC_PREFIX}{digest}-{uuid.uuid4().hex}.h5"
        try:
            os.replace(path, aside)
        except FileNotFoundError:
            return False
        keep = True
        try:
            keep = self.age_seconds(aside) < min_age_s or bool(still_referenced(digest))
        finally:
            if keep:
                self._restore(aside, digest)
        if keep:
            return False
        aside.unlink(missing_ok=True)
        _fsync_dir(path.parent)
        return True

    def _restore(self, aside: Path, digest: str) -> None:
        path = self.path(digest)
        if path.exists():  # a writer already wrote a fresh copy
            aside.unlink(missing_ok=True)
        else:
            os.replace(aside, path)
        _fsync_dir(path.parent)

    def restore_set_aside(self, is_referenced) -> list[str]:
        """Put back blobs an interrupted ``gc`` had set aside that a row references; returns their hashes."""
        restored = []
        for tmp in self.temporaries():
            if not tmp.name.startswith(_GC_PREFIX):
                continue
            digest = tmp.name[len(_GC_PREFIX):].split("-", 1)[0]
            if is_referenced(digest):
                self._restore(tmp, digest)
                restored.append(digest)
        return restored

    @staticmethod
    def age_seconds(path: Path) -> float:
        try:
            return time.time() - path.stat().st_mtime
        except OSError:
            return 0.0


def _verify_file(path: Path, digest: str) -> None:
    """Refuse a freshly written blob file that does not read back to ``digest``."""
    try:
        check_file_checksum(path)
        frf = read_frf_file(path, verify=False)
    except InputError as exc:
        raise IntegrityError(f"blob {digest} did not read back: {exc}") from None
    actual = frf_sha256(frf)
    if actual != digest:
        raise IntegrityError(f"blob {digest} read back with content hash {actual} ({path})")


class PendingPut:
    """A blob being made durable by a thread (:meth:`BlobStore.put_pending`)."""

    def __init__(self, digest: str, finish=None):
        import threading

        self.digest = digest
        self._error: BaseException | None = None
        self._thread = None
        if finish is not None:
            def run() -> None:
                try:
                    finish()
                except BaseException as exc:  # noqa: BLE001 - handed to wait()
                    self._error = exc

            self._thread = threading.Thread(target=run, name=f"jointdb-blob-{digest[:8]}", daemon=False)
            self._thread.start()

    def join(self) -> None:
        """Wait for the thread, without raising what it met."""
        if self._thread is not None:
            self._thread.join()

    def wait(self) -> str:
        """The digest once the blob is durable in place.

        Raises
        ------
        InputError
            The blob directory refused the write (nothing is left behind).
        """
        self.join()
        if self._error is not None:
            raise self._error
        return self.digest
