"""Content-addressed, durable, verified HDF5 blob store for FRFs.

The blob file is ``<root>/<h[:2]>/<h>.h5``, where ``h`` is the SHA-256 of the FRF's
canonical form; the file format (HDF5 layout, whole-file checksum in a user block)
is described in :mod:`jointdb.store._blobformat`.

A write builds the file's bytes in memory, writes them to a temporary file in
the same directory and fsyncs it while it decodes them again and compares them
with the FRF, then renames the file atomically into place and fsyncs the
directory. Reads always verify the whole-file checksum, the HDF5 chunk
checksums and the content hash. The background durability (temporary file, fsync, rename,
directory fsync on a worker thread) is :mod:`jointdb.store._durable`.
"""

from __future__ import annotations

import os
import time
import uuid
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from jointdb.errors import InputError, IntegrityError, NotFoundError
from jointdb.frf import FRF
from jointdb.io._atomic import fsync_dir as _fsync_dir
from jointdb.store import _durable
from jointdb.store._blobformat import (  # noqa: F401 - re-exported: the blob format's names live here too
    _FILE_MAGIC,
    _HEX64,
    COMPLEX_CONVENTION,
    FORMAT,
    FORMAT_VERSION,
    HARMONIC_CONVENTION,
    USERBLOCK,
    _userblock,
    blob_bytes,
    check_digest,
    check_file_checksum,
    decode_blob_bytes,
    file_sha256,
    frf_sha256,
    read_frf_file,
    read_frf_group,
    verify_blob_bytes,
    write_frf_file,
    write_frf_group,
)
from jointdb.store._durable import PendingPut, make_durable

__all__ = ["BlobStore", "frf_sha256", "file_sha256", "FORMAT_VERSION", "write_frf_file", "read_frf_file", "blob_bytes",
           "decode_blob_bytes"]

_TMP_PREFIX = ".tmp-"
_GC_PREFIX = _TMP_PREFIX + "gc-"  # a blob `gc` moved aside for its last check: ".tmp-gc-<sha>-<uuid>.h5"


@dataclass(frozen=True)
class BlobInfo:
    sha256: str
    path: Path
    size: int
    mtime: float


class VerifyingBlobs:
    """What both blob stores share (:class:`jointdb.store._protocol.BlobStoreProtocol`): ``verify``
    through ``get``. A subclass defines ``get``."""

    def get(self, digest: str) -> FRF:  # pragma: no cover - defined by each store
        raise NotImplementedError

    def verify(self, digest: str) -> str | None:
        """Check one blob.

        Parameters
        ----------
        digest
            The blob's SHA-256 (hex).

        Returns
        -------
        str or None
            None when the blob is present and intact, else a one-line problem description.
        """
        try:
            self.get(digest)
        except (NotFoundError, IntegrityError) as exc:
            return str(exc)
        return None


class BlobStore(VerifyingBlobs):
    """Content-addressed FRF blobs in a directory (module docstring for the format).

    Parameters
    ----------
    root
        Directory holding the blobs (created on first write).
    """

    #: a blob file is durable before the row that references it is committed (not in its transaction)
    writes_in_version_transaction = False

    def __init__(self, root: str | os.PathLike):
        self.root = Path(root)

    def __repr__(self) -> str:
        return f"BlobStore({str(self.root)!r})"

    def path(self, digest: str) -> Path:
        """File of a blob; the digest (often read from the database) must be 64 lower-case hex digits.

        Parameters
        ----------
        digest
            The blob's SHA-256 (hex).

        Returns
        -------
        Path
            ``root/<first two hex digits>/<digest>.h5``; the file may not exist.

        Raises
        ------
        IntegrityError
            ``digest`` is not a SHA-256 hex digest (never used to build a path).
        """
        check_digest(digest)
        return self.root / digest[:2] / f"{digest}.h5"

    def exists(self, digest: str) -> bool:
        """Whether the blob's file exists (not verified).

        Parameters
        ----------
        digest
            As :meth:`path`.

        Returns
        -------
        bool
            True when the file is there (its content is checked on read, not here).
        """
        return self.path(digest).is_file()

    # ------------------------------------------------------------------ write
    def put(self, frf: FRF) -> str:
        """Store an FRF durably. Idempotent (an existing verified blob is kept).

        Parameters
        ----------
        frf
            The FRF.

        Returns
        -------
        str
            Its SHA-256 (:func:`frf_sha256`).

        Raises
        ------
        IntegrityError
            If the read-back does not verify.
        InputError
            The blob directory refuses the write.
        """
        return self.put_pending(frf).wait()

    def put_pending(self, frf: FRF) -> "PendingPut":
        """Start storing an FRF: encoded, written and verified now, made durable in the background.

        Parameters
        ----------
        frf
            The FRF.

        Returns
        -------
        PendingPut
            ``.wait()`` returns the digest once the blob is durable.

        Notes
        -----

        The blob file's bytes are built in memory (:func:`blob_bytes`) and written to a
        temporary file, whose fsync runs on a worker thread while the bytes are decoded
        again and compared with the FRF (:func:`verify_blob_bytes`); only when they
        pass is the file renamed into place and the directory fsynced (on the worker),
        so that a caller can prepare its database transaction meanwhile; when they do
        not, the temporary file is removed and IntegrityError raised.
        :meth:`PendingPut.wait` returns the digest once the blob is durable (and raises
        what the worker met); call it before committing anything that references the
        blob, and always (it also waits for the worker).
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
        _, data = blob_bytes(frf, digest)
        new_dir = not final.parent.is_dir()
        tmp = final.parent / f"{_TMP_PREFIX}{uuid.uuid4().hex}.h5"
        try:
            final.parent.mkdir(parents=True, exist_ok=True)
            fd = _durable.write_tmp(tmp, data)
        except OSError as exc:  # read-only or full blob directory: one line for the user, nothing kept
            tmp.unlink(missing_ok=True)
            raise InputError(f"cannot write to the blob store {self.root}: {exc.strerror or exc}") from None
        except BaseException:
            tmp.unlink(missing_ok=True)
            raise

        def finish(verified) -> None:
            make_durable(fd, tmp, final, self.root, new_dir, verified)

        try:
            pending = PendingPut(digest, finish)  # the fsync runs while the bytes are verified
        except BaseException:  # no worker (e.g. at interpreter shutdown): nothing left behind
            os.close(fd)
            tmp.unlink(missing_ok=True)
            raise
        try:  # decoded again and compared with the FRF: nothing can reference a blob that does not read back
            verify_blob_bytes(data, frf, digest)
        except BaseException:
            pending.cancel()  # removes the temporary file
            raise
        pending.release()
        return pending

    # ------------------------------------------------------------------- read
    def get(self, digest: str) -> FRF:
        """Read and verify a blob.

        Parameters
        ----------
        digest
            The blob's SHA-256 (hex).

        Returns
        -------
        FRF
            The stored FRF, its content hash checked against ``digest``.

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

    # ------------------------------------------------------------------ walk
    def walk(self) -> Iterator[BlobInfo]:
        """All finished blobs in the store.

        Yields
        ------
        BlobInfo
            ``sha256``, ``path``, ``size`` [bytes], ``mtime`` [s since the epoch].
        """
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
        """Left-over temporary files of interrupted writes.

        Returns
        -------
        list of Path
        """
        if not self.root.is_dir():
            return []
        return sorted(self.root.glob(f"*/{_TMP_PREFIX}*"))

    def remove(self, digest: str) -> None:
        """Delete one blob file unconditionally (tests and repairs; ``gc`` uses :meth:`collect`).

        Parameters
        ----------
        digest
            The blob's SHA-256 (hex).
        """
        path = self.path(digest)
        path.unlink(missing_ok=True)
        _fsync_dir(path.parent)

    def collect(self, digest: str, min_age_s: float, still_referenced) -> bool:
        """Delete an unreferenced blob without racing a writer that is about to reference it.

        The blob is first renamed aside (so a concurrent :meth:`put` no longer finds it
        and writes a fresh copy), then ``still_referenced(digest)`` is asked again and
        the age re-read (a :meth:`put` that found the blob just before refreshed it).
        If either says keep, the blob is put back; otherwise it is deleted.

        Parameters
        ----------
        digest
            The blob's SHA-256 (hex).
        min_age_s
            Keep it if it is younger than this [s].
        still_referenced
            ``digest -> bool``: whether a row references it now.

        Returns
        -------
        bool
            True when deleted.
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
        """Put back blobs an interrupted ``gc`` had set aside that a row references.

        Parameters
        ----------
        is_referenced
            ``digest -> bool``: whether a row references the blob.

        Returns
        -------
        list of str
            The digests put back.
        """
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
        """Seconds since a file was last modified (0 when it cannot be read).

        Parameters
        ----------
        path
            A file of the store.

        Returns
        -------
        float
        """
        try:
            return time.time() - path.stat().st_mtime
        except OSError:
            return 0.0
