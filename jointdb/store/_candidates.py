"""The candidate set of a nearest-joint query as arrays (:mod:`jointdb.store._nearest`), shared
with the on-disk query cache (:mod:`jointdb.store._qcache`), which stores and reloads it."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

def canonical_materials(texts: list[str], index: np.ndarray) -> tuple[list[str], np.ndarray]:
    """The distinct materials texts that ``index`` uses, sorted, and the index into them: one form
    whatever order the rows came in, so that a full fetch and an incremental update give equal arrays.

    Parameters
    ----------
    texts
        Materials texts (a text may occur more than once).
    index
        Per candidate, an index into ``texts``.

    Returns
    -------
    texts : list of str
        The used texts, sorted.
    index : ndarray of intp
        Per candidate, an index into them.
    """
    index = np.asarray(index, dtype=np.intp)
    used = np.flatnonzero(np.bincount(index, minlength=len(texts))).tolist() if index.size else []
    distinct = sorted({texts[i] for i in used})
    position = {t: n for n, t in enumerate(distinct)}
    remap = np.zeros(len(texts), dtype=np.intp)
    remap[used] = [position[texts[i]] for i in used]
    return distinct, remap[index]


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
    #: values derived from the arrays alone, kept by the ranking (:func:`jointdb.store._rank.rank`)
    memo: dict = field(default_factory=dict, repr=False, compare=False)

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

    def replace_joints(self, joint_ids, new: "Candidates | None") -> "Candidates":
        """These candidates with every row of ``joint_ids`` replaced by the rows of ``new``.

        Parameters
        ----------
        joint_ids
            The joints whose rows are dropped.
        new
            Their current rows (None: none), with at least this set's geometry keys.

        Returns
        -------
        Candidates
            Ordered by version id, materials in canonical form (:func:`canonical_materials`).
        """
        keep = ~np.isin(self.joint_id, np.asarray(list(joint_ids), dtype=np.int64))
        parts = [(self, keep)] + ([(new, slice(None))] if new is not None else [])
        vid = np.concatenate([c.version_id[m] for c, m in parts])
        order = np.argsort(vid, kind="stable")

        def col(name):
            return np.concatenate([getattr(c, name)[m] for c, m in parts])[order]
        texts = self.materials + (new.materials if new is not None else [])
        index = np.concatenate([self.materials_index[keep]]
                               + ([new.materials_index + len(self.materials)] if new is not None else []))
        texts, index = canonical_materials(texts, index[order])
        geometry = {g: np.concatenate([c.geometry[g][m] for c, m in parts])[order] for g in self.geometry}
        return Candidates(vid[order], col("joint_id"), col("number"), col("torque"), col("preload"), texts, index,
                          geometry)
