"""Making a blob file durable off the caller's thread: the temporary file, the fsync, the rename.

:meth:`jointdb.store._blobs.BlobStore.put_pending` writes a blob's bytes to a temporary file
(:func:`write_tmp`) in the blob's shard directory and hands the rest to a worker thread
(:class:`PendingPut`, :func:`make_durable`): fsync the file while the caller verifies the
bytes, then, once the caller says they verified, rename it into place and fsync the
directory (and a new shard directory's parent); when they did not, remove it. The caller
meanwhile prepares its database transaction and commits it only after
:meth:`PendingPut.wait`: a row never names a blob that is not durable.
"""

from __future__ import annotations

import os
from pathlib import Path

from jointdb.errors import InputError
from jointdb.io._atomic import fsync_dir as _fsync_dir


def write_tmp(path: Path, data: bytes) -> int:
    """Create ``path`` (it must not exist) holding ``data``; returns the open descriptor to fsync.

    Raises
    ------
    OSError
        The directory refuses the file (the caller removes a partial one).
    """
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
    try:
        view = memoryview(data)
        while view:
            view = view[os.write(fd, view):]
    except BaseException:
        os.close(fd)
        raise
    return fd


def make_durable(fd: int, tmp: Path, final: Path, root: Path, new_dir: bool, verified) -> None:
    """fsync the temporary file ``tmp`` (open as ``fd``, closed here); once ``verified()`` says so,
    rename it to ``final``, else remove it; fsync the directory (and ``root`` for a new shard
    directory), so that the rename or the removal is durable.

    Raises
    ------
    InputError
        The blob directory refused the fsync or the rename (nothing is left behind).
    """
    try:
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
        if verified():
            os.replace(tmp, final)
    except OSError as exc:
        raise InputError(f"cannot write to the blob store {root}: {exc.strerror or exc}") from None
    finally:
        if tmp.exists():
            tmp.unlink()
    _fsync_dir(final.parent)  # the rename (or the removal) is durable
    if new_dir:
        _fsync_dir(root)  # and so is the new shard directory


_workers = None  # (pid, ThreadPoolExecutor): the threads that make blobs durable, started once per process


def executor():
    """The worker threads of this process that make blob files durable and encode database blobs
    (started on first use; a forked child starts its own).

    Returns
    -------
    concurrent.futures.ThreadPoolExecutor
    """
    global _workers
    if _workers is None or _workers[0] != os.getpid():  # a forked child has none of its parent's threads
        from concurrent.futures import ThreadPoolExecutor

        _workers = (os.getpid(), ThreadPoolExecutor(max_workers=8, thread_name_prefix="jointdb-blob"))
    return _workers[1]


class PendingPut:
    """A blob being made durable by a worker thread (:meth:`jointdb.store._blobs.BlobStore.put_pending`).

    ``finish(verified)`` runs in the worker; ``verified()`` blocks until the creator
    calls :meth:`release` (go on: put the blob in place) or :meth:`cancel` (drop it)
    and returns which. The creator must call one of them (a worker waits for no other
    task, so a queued task always runs once a worker finishes its own).
    """

    def __init__(self, digest: str, finish=None):
        import threading

        self.digest = digest
        self._error: BaseException | None = None
        self._thread = None  # the worker's Future
        self._decided = threading.Event()
        self._go = False
        if finish is not None:
            def run() -> None:
                try:
                    finish(self._verified)
                except BaseException as exc:  # noqa: BLE001 - handed to wait()
                    self._error = exc

            self._thread = executor().submit(run)

    def _verified(self) -> bool:
        self._decided.wait()
        return self._go

    def release(self) -> None:
        """The bytes verified: let the thread put the blob in place."""
        self._go = True
        self._decided.set()

    def cancel(self) -> None:
        """Drop the blob (the thread removes its temporary file) and wait for the thread."""
        self._go = False
        self._decided.set()
        self.join()

    def join(self) -> None:
        """Wait for the worker's task, without raising what it met."""
        if self._thread is not None:
            self._thread.result()  # run() keeps what finish() raised for wait()

    def wait(self, session=None) -> str:
        """The digest once the blob is durable in place (``session``: the version's transaction,
        which a file blob does not take part in; the database store writes into it).

        Raises
        ------
        InputError
            The blob directory refused the write (nothing is left behind).
        """
        self.join()
        if self._error is not None:
            raise self._error
        return self.digest
