"""Ranking of the candidate arrays against a request: the distance of :mod:`jointdb.store._query`.

Pure numpy on :class:`~jointdb.store._candidates.Candidates` (no database): each numeric condition the
request names is a term ``|ln c − ln r| / spread`` (spread: the candidates' log range, at least ln 2),
each geometry key ``|c − r| / max(|c|, |r|)``, materials a Jaccard distance of the multisets; a candidate
without the value takes ``MISSING_PENALTY``. The distance is the root of the summed squares; ties are
broken by joint id, then version number. Statistics that depend on the candidates only are kept in the
candidates' ``memo`` and reused by the next request on the same arrays.
"""

from __future__ import annotations

import json
import math
from collections import Counter

import numpy as np

from jointdb.store._candidates import Candidates
from jointdb.store._types import Conditions

MISSING_PENALTY = 1.0
MIN_LOG_SPREAD = math.log(2.0)

def _jaccard(a: tuple[str, ...], b: tuple[str, ...]) -> float:
    ca, cb = Counter(a), Counter(b)
    union = sum((ca | cb).values())
    return 0.0 if union == 0 else 1.0 - sum((ca & cb).values()) / union


def _log_stats(values: np.ndarray, memo: dict, name: str) -> tuple:
    """``(have, delta, logs, spread, lo, hi)`` of a candidate column (``delta`` None: no value at all),
    kept in the candidates' ``memo``: they depend on the candidates only, not on the request."""
    hit = memo.get(name)
    if hit is None:
        have = np.isfinite(values)
        if not have.any():
            hit = (have, None, None, None, None, None)
        else:
            delta = 1e-9 * max(1.0, float(np.nanmax(values)))
            logs = np.log(values[have] + delta)
            spread = max(float(logs.max() - logs.min()), MIN_LOG_SPREAD)
            hit = (have, delta, logs, spread, float(np.nanmin(values)), float(np.nanmax(values)))
        memo[name] = hit
    return hit


def _log_term(values: np.ndarray, request: float, name: str, terms: dict, outside: list, memo: dict) -> None:
    have, delta, logs, spread, lo, hi = _log_stats(values, memo, name)
    if delta is None:
        terms[name] = np.full(values.shape, MISSING_PENALTY)
        outside.append(name)
        return
    d = logs - math.log(request + delta)  # in place from here: |logs - ln(r + delta)| / spread
    np.abs(d, out=d)
    d /= spread
    if d.size == values.size:  # every candidate has the value
        terms[name] = d
    else:
        terms[name] = np.full(values.shape, MISSING_PENALTY)
        terms[name][have] = d
    if request < lo or request > hi:
        outside.append(name)


def _geometry_term(vals: np.ndarray, r_val: float, memo: dict, name: str) -> tuple[np.ndarray, bool]:
    """``(term, outside)`` of one geometry key: ``|c - r| / max(|c|, |r|)``, 1.0 where missing."""
    stats = memo.get(name)
    if stats is None:
        have = np.isfinite(vals)
        stats = memo[name] = (have, bool(have.all()), *((float(np.nanmin(vals)), float(np.nanmax(vals)))
                                                         if have.any() else (None, None)))
    have, everywhere, lo, hi = stats
    outside = lo is None or r_val < lo or r_val > hi
    denom = np.maximum(np.abs(vals), abs(r_val))
    with np.errstate(invalid="ignore"):
        if r_val != 0.0:  # denom > 0 wherever the value is there
            rel = np.abs(vals - r_val)
            rel /= denom
        else:
            rel = np.where(denom > 0, np.abs(vals - r_val) / np.where(denom > 0, denom, 1.0), 0.0)
    return (rel if everywhere else np.where(have, rel, MISSING_PENALTY)), outside


def rank(cand: Candidates, req: Conditions, k: int) -> tuple[np.ndarray, np.ndarray, dict, list[str]]:
    """``(order, total, terms, outside)``: the ``k`` best candidate positions, best first.

    Order: distance rounded to 1e-12, then joint id, then version number.
    """
    n = cand.version_id.size
    terms: dict[str, np.ndarray] = {}
    outside: list[str] = []
    if req.torque_nm is not None:
        _log_term(cand.torque, req.torque_nm, "torque_nm", terms, outside, cand.memo)
    if req.preload_n is not None:
        _log_term(cand.preload, req.preload_n, "preload_n", terms, outside, cand.memo)
    if req.materials:
        want = tuple(sorted(req.materials))
        per_key = np.array([_jaccard(want, tuple(m)) if m else MISSING_PENALTY
                            for m in (json.loads(t) for t in cand.materials)])
        terms["materials"] = per_key[cand.materials_index]
        if not np.any(per_key == 0.0):
            outside.append("materials")
    for key, r_val in req.geometry.items():
        name = f"geometry.{key}"
        terms[name], out = _geometry_term(cand.geometry[key], r_val, cand.memo, name)
        if out:
            outside.append(name)
    total = np.zeros(n)
    for t in terms.values():  # the squares summed in the terms' order, then the root
        total += np.square(t)
    np.sqrt(total, out=total)
    rounded = np.round(total, 12)
    if n > 4 * k:  # the k best by the same key, without sorting all of them
        kth = np.partition(rounded, k - 1)[k - 1]
        pool = np.flatnonzero(rounded <= kth)
    else:
        pool = np.arange(n)
    order = pool[np.lexsort((cand.number[pool], cand.joint_id[pool], rounded[pool]))][:k]
    return order, total, terms, outside
