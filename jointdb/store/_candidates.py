"""The candidate set of a nearest-joint query as arrays (:mod:`jointdb.store._nearest`), shared
with the on-disk query cache (:mod:`jointdb.store._qcache`), which stores and reloads it."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

#: stands for SQL NULL in fetched numeric columns (every stored condition number is >= 0)
_NULL = -1.0


@dataclass
class Candidates:
    """The ranked set as arrays, ordered by version id (floats: NaN where the value is missing)."""

    version_id: np.ndarray
    joint_id: np.ndarray
    number: np.ndarray
    torque: np.ndarray
    preload: np.ndarray
    materials: list[str]  # distinct JSON texts of sorted material lists
    materials_index: np.ndarray  # per candidate, index into ``materials``
    geometry: dict[str, np.ndarray] = field(default_factory=dict)

    @classmethod
    def from_rows(cls, rows: list[tuple], geometry_keys: list[str] = ()) -> "Candidates":
        """From ``(version_id, joint_id, number, torque, preload, materials, *geometry)`` rows
        (NULL as :data:`_NULL`)."""
        if not rows:
            e = np.zeros(0)
            return cls(e.astype(np.int64), e.astype(np.int64), e.astype(np.int64), e, e, [], e.astype(np.intp),
                       {g: e for g in geometry_keys})
        vid, jid, num, tq, pl, mats, *geo = zip(*rows)
        order = np.argsort(np.array(vid, dtype=np.int64), kind="stable")
        keys: dict[str, int] = {}
        idx = np.array([keys.setdefault(m, len(keys)) for m in mats], dtype=np.intp)

        def nums(col):
            a = np.array(col, dtype=float)[order]
            a[a < 0] = np.nan
            return a
        return cls(np.array(vid, dtype=np.int64)[order], np.array(jid, dtype=np.int64)[order],
                   np.array(num, dtype=np.int64)[order], nums(tq), nums(pl), list(keys), idx[order],
                   {g: nums(col) for g, col in zip(geometry_keys, geo)})

    def align(self, pairs: list[tuple]) -> np.ndarray:
        """A float column from ``(version_id, value)`` pairs (NaN for candidates without one)."""
        out = np.full(self.version_id.size, np.nan)
        if pairs and self.version_id.size:
            ids, vals = zip(*pairs)
            ids = np.array(ids, dtype=np.int64)
            pos = np.searchsorted(self.version_id, ids).clip(0, self.version_id.size - 1)
            hit = self.version_id[pos] == ids
            out[pos[hit]] = np.array(vals, dtype=float)[hit]
        return out
