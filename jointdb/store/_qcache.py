"""On-disk cache of the nearest query's candidate arrays, shared by processes.

A one-shot ``jointdb query`` starts with no arrays in memory; fetching 50,000
candidate rows costs far more than ranking them. The arrays of a selection are
therefore also kept as one ``.npz`` file per (database, selection), named with
the query index's stamp ``(token, generation)`` read in the same snapshot as the
arrays. Every transaction that changes what a query can return increases the
generation (:mod:`jointdb.store._index`), so a file is used only while it is
exactly current; a stale file is never read, only replaced.

Location: ``$JOINTDB_QUERY_CACHE`` if set (``off`` disables the cache), else
``$XDG_CACHE_HOME/jointdb/query`` (``~/.cache/jointdb/query``). Files are written
to a temporary name and renamed (no fsync: losing one costs a refetch). Any
error reading or writing the cache is ignored: the database stays the source.
At most :data:`MAX_FILES` files are kept (oldest removed first).
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import uuid
import zipfile
from pathlib import Path

import numpy as np

from jointdb.store._candidates import Candidates

MAX_FILES = 64
_ARRAYS = ("version_id", "joint_id", "number", "torque", "preload", "materials_index")


def cache_dir() -> Path | None:
    """The cache directory, or None when disabled."""
    env = os.environ.get("JOINTDB_QUERY_CACHE")
    if env is not None:
        return None if env.strip().lower() in ("", "0", "off", "no", "false") else Path(env).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "jointdb" / "query"


def _prefix(db_key: str, sel) -> str:
    text = "\0".join(map(str, (db_key, sel.joint_type, sel.label, sel.all_versions, sel.include_deprecated)))
    return hashlib.sha256(text.encode()).hexdigest()[:32]


def _token(stamp: tuple) -> str:
    return "".join(c for c in str(stamp[0]) if c.isalnum())[:36]


def _path(root: Path, db_key: str, stamp: tuple, sel) -> Path:
    return root / f"{_prefix(db_key, sel)}-{_token(stamp)}-{int(stamp[1])}.npz"


def load(db_key: str, stamp: tuple, sel):
    """The cached candidates for exactly this stamp, or None."""
    root = cache_dir()
    return None if root is None else _read(_path(root, db_key, stamp, sel))


def load_older(db_key: str, stamp: tuple, sel) -> tuple[tuple, Candidates] | None:
    """``(its stamp, candidates)`` of the newest file of this selection with the same token and
    an older generation (to be updated with the changes since: :mod:`jointdb.store._nearest`), or None."""
    root = cache_dir()
    if root is None:
        return None
    head = f"{_prefix(db_key, sel)}-{_token(stamp)}-"
    try:
        names = [p.name for p in root.glob(head + "*.npz")]
    except OSError:
        return None
    older = [int(g) for g in (n[len(head):-4] for n in names) if g.isdigit() and int(g) < int(stamp[1])]
    if not older:
        return None
    old_stamp = (stamp[0], max(older))
    cand = _read(_path(root, db_key, old_stamp, sel))
    return None if cand is None else (old_stamp, cand)


def _read(path: Path) -> Candidates | None:
    try:
        with np.load(path, allow_pickle=False) as z:
            arrays = {k: z[k] for k in _ARRAYS}
            materials = [str(m) for m in z["materials"]]
            geometry = {k[4:]: z[k] for k in z.files if k.startswith("geo:")}
    except (OSError, KeyError, ValueError, EOFError, zipfile.BadZipFile):
        return None
    n = arrays["version_id"].size
    if any(a.shape != (n,) for a in (*arrays.values(), *geometry.values())):
        return None
    index = arrays["materials_index"]
    if n and (index.dtype.kind not in "iu" or index.min() < 0 or index.max() >= len(materials)
              or np.any(np.diff(arrays["version_id"]) <= 0)):
        return None
    return Candidates(arrays["version_id"], arrays["joint_id"], arrays["number"], arrays["torque"],
                      arrays["preload"], materials, arrays["materials_index"].astype(np.intp), geometry)


def save(db_key: str, stamp: tuple, sel, cand) -> None:
    """Write the candidates for this stamp (best effort) and drop older files of the same selection."""
    root = cache_dir()
    if root is None:
        return
    final = _path(root, db_key, stamp, sel)
    tmp = root / f".part-{uuid.uuid4().hex}.npz"
    try:
        root.mkdir(parents=True, exist_ok=True)
        arrays = {k: getattr(cand, k) for k in _ARRAYS}
        arrays["materials"] = np.array(cand.materials, dtype=str)
        arrays.update({f"geo:{k}": v for k, v in cand.geometry.items()})
        with open(tmp, "wb") as fh:
            np.savez(fh, **arrays)
        os.replace(tmp, final)
        prefix = _prefix(db_key, sel)
        files = sorted(root.glob("*.npz"), key=lambda p: p.stat().st_mtime)
        for old in files:
            if (old.name.startswith(prefix) and old != final) or len(files) > MAX_FILES:
                with contextlib.suppress(OSError):
                    old.unlink()
                    files = [f for f in files if f != old]
    except OSError:
        pass
    finally:
        with contextlib.suppress(OSError):
            tmp.unlink(missing_ok=True)
