"""A content-addressed cache of encoded FRF downloads (issue 26, item 4).

A catalogued version never changes, so its FRF encoded in one format never does: the
bytes are kept under the version's record hash, the format and the jointdb version
that encoded them, first in memory (least recently used out beyond ``memory_bytes``)
and then in a folder every worker process of the server shares (``JOINTDB_CACHE_DIR``;
default ``$XDG_CACHE_HOME/jointdb/frf-downloads`` or ``~/.cache/...``, made with mode
0700). Each file starts with the SHA-256 of the bytes after it, checked on every read:
a damaged or altered file is removed and the bytes are encoded again, never served.
Files are written to a temporary name and renamed, so a reader never sees half a file.
"""

from __future__ import annotations

import hashlib
import logging
import os
import re
import tempfile
import threading
from collections import OrderedDict
from collections.abc import Callable
from pathlib import Path

log = logging.getLogger("jointdb.server")

_KEY = re.compile(r"^[0-9a-f]{16,64}$")


def default_cache_dir() -> Path:
    """``$JOINTDB_CACHE_DIR``, else ``$XDG_CACHE_HOME/jointdb/frf-downloads``, else ``~/.cache/...``."""
    explicit = os.environ.get("JOINTDB_CACHE_DIR")
    if explicit:
        return Path(explicit)
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "jointdb" / "frf-downloads"


class EncodedCache:
    """Encoded files by ``(record_sha256, format)``: memory, then a shared folder, then ``encode()``.

    Parameters
    ----------
    folder
        The shared folder, or None for memory only.
    memory_bytes
        Largest total size kept in memory [bytes].
    tag
        Part of every key that changes when the encoders may (the jointdb version).
    """

    def __init__(self, folder: Path | None, memory_bytes: int = 64 * 2**20, tag: str = ""):
        self.memory_bytes = int(memory_bytes)
        self.tag = re.sub(r"[^0-9A-Za-z.+-]", "_", tag)
        self._memory: OrderedDict[str, bytes] = OrderedDict()
        self._held = 0
        self._lock = threading.Lock()
        self.folder = self._usable(folder)
        self.hits = {"memory": 0, "disk": 0, "encoded": 0}

    @staticmethod
    def _usable(folder: Path | None) -> Path | None:
        if folder is None:
            return None
        try:
            folder.mkdir(parents=True, exist_ok=True, mode=0o700)
            if not os.access(folder, os.W_OK):
                raise PermissionError("not writable")
        except OSError as exc:
            log.warning('{"event": "download-cache", "state": "memory only", "reason": "%s"}',
                        type(exc).__name__)
            return None
        return folder

    def get(self, record_sha256: str, fmt: str, encode: Callable[[], bytes]) -> bytes:
        """The bytes for ``(record_sha256, fmt)``; ``encode()`` runs only on a miss everywhere."""
        if not _KEY.match(record_sha256) or not fmt.isalnum():
            raise ValueError("record hash must be lower-case hex and format alphanumeric")
        key = f"{record_sha256}-{fmt}-{self.tag}"
        with self._lock:
            data = self._memory.get(key)
            if data is not None:
                self._memory.move_to_end(key)
                self.hits["memory"] += 1
                return data
        data = self._read(key)
        if data is None:
            data = encode()
            self._write(key, data)
            self.hits["encoded"] += 1
        else:
            self.hits["disk"] += 1
        self._remember(key, data)
        return data

    def _remember(self, key: str, data: bytes) -> None:
        if len(data) > self.memory_bytes // 4:
            return  # one huge file would flush everything else
        with self._lock:
            if key not in self._memory:
                self._memory[key] = data
                self._held += len(data)
            while self._held > self.memory_bytes:
                _, old = self._memory.popitem(last=False)
                self._held -= len(old)

    def _read(self, key: str) -> bytes | None:
        if self.folder is None:
            return None
        path = self.folder / key
        try:
            raw = path.read_bytes()
        except OSError:
            return None
        digest, _, data = raw.partition(b"\n")
        if digest.decode("ascii", "replace") != hashlib.sha256(data).hexdigest():
            log.warning('{"event": "download-cache", "state": "damaged file removed"}')
            path.unlink(missing_ok=True)
            return None
        return data

    def _write(self, key: str, data: bytes) -> None:
        if self.folder is None:
            return
        try:
            fd, tmp = tempfile.mkstemp(dir=self.folder, prefix=".part-")
        except OSError:  # the folder went away or is full: serve from memory, try again next time
            return
        try:
            with os.fdopen(fd, "wb") as fh:
                fh.write(hashlib.sha256(data).hexdigest().encode() + b"\n" + data)
            os.replace(tmp, self.folder / key)
        except OSError:  # a full disk: no half-written file is left behind
            Path(tmp).unlink(missing_ok=True)
