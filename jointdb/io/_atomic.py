"""Atomic file writing: temp file in the target directory, fsync, ``os.replace``.

A write either leaves the complete new file at ``path`` or leaves ``path`` as it
was (absent or the previous version); never a half-written file, and no stray
temporary file after an exception.
"""

from __future__ import annotations

import contextlib
import functools
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

from jointdb.errors import InputError


def fsync_dir(directory: Path) -> None:
    """Make a rename in ``directory`` durable (a no-op where directories cannot be opened)."""
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


#: OSError subclasses that mean "the system refused the write" (not a bug in the caller).
_SYSTEM_WRITE_ERRORS = (OSError, PermissionError, IsADirectoryError, FileExistsError)


@functools.cache
def _umask() -> int:
    # Read once per process (os.umask can only be read by setting it).
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path next to ``path``; on success fsync it and rename it over ``path``.

    The caller writes the complete file to the yielded path (closing it before
    the ``with`` block ends). On any exception the temporary file is removed
    and the exception propagates; ``path`` is untouched.

    Raises
    ------
    InputError
        If the target directory does not exist, ``path`` is a directory, or the
        system refuses the write (permissions, disk full).
    """
    target = Path(path)
    directory = target.parent if str(target.parent) else Path(".")
    if not directory.is_dir():
        raise InputError(f"cannot write {target}: directory {directory} does not exist")
    if target.is_dir():
        raise InputError(f"cannot write {target}: it is a directory")
    try:
        fd, tmp_name = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=directory)
    except OSError as exc:  # read-only or full directory: a user-facing error, not a traceback
        raise InputError(f"cannot write {target}: {exc.strerror or exc}") from None
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        yield tmp
        with open(tmp, "rb+") as fh:
            fh.flush()
            os.fsync(fh.fileno())
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600; give the usual permissions
        os.replace(tmp, target)
    except BaseException as exc:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()
        if isinstance(exc, OSError) and type(exc) in _SYSTEM_WRITE_ERRORS:  # disk full, permissions, ...
            raise InputError(f"cannot write {target}: {exc.strerror or exc}") from None
        raise
    fsync_dir(directory)
