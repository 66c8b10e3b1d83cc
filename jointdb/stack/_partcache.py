"""A small memo of the parts' free receptances (tool, holder, modelled spindle) on a frequency grid.

A prediction with its band and its joint-choice sensitivity couples the same tool, holder and spindle
many times with different joints (the nominal prediction, each next-nearest joint, the band's
ensembles): their beam-model FRFs, one direct FE solve per line each, are the same every time.
:func:`cached_part` keeps the most recent ones, keyed by *content* (the frozen tool / holder
dataclasses, the spindle model's canonical JSON, the gauge length and the grid's bytes), never by
object identity, so an edited stack never meets a stale FRF (an FRF's values are read-only, so no caller
can change a kept one). A spindle model given as a path or as a ``BeamModel`` is not kept.
"""

from __future__ import annotations

import hashlib
import json
import threading
from collections import OrderedDict
from collections.abc import Callable, Hashable

import numpy as np

from jointdb.frf import FRF

__all__ = ["cached_part", "clear_part_cache", "spindle_key", "MAX_ENTRIES", "MAX_BYTES"]

#: Most part FRFs kept (a prediction uses three; a sensitivity study or an optimisation a few stacks).
MAX_ENTRIES = 24
#: Most bytes of FRF values kept (the oldest are dropped first).
MAX_BYTES = 64 * 2**20

_lock = threading.Lock()
_memo: OrderedDict[Hashable, FRF] = OrderedDict()


def _grid_key(freq: np.ndarray) -> str:
    f = np.ascontiguousarray(freq, dtype=float)
    return hashlib.blake2b(f.tobytes(), digest_size=16).hexdigest() + f":{f.size}"


def spindle_key(model) -> Hashable | None:
    """A content key of a modelled spindle's model given as a dict (its canonical JSON), or None (not kept)."""
    if isinstance(model, dict):
        try:
            return json.dumps(model, sort_keys=True, allow_nan=True)
        except (TypeError, ValueError):
            return None
    return None  # a path (its file may change) or a BeamModel (its supports hold mutable dicts): not kept


def cached_part(kind: str, key: Hashable | None, freq: np.ndarray, build: Callable[[], FRF]) -> FRF:
    """The part FRF for ``(kind, key)`` on ``freq``, built once by ``build()`` and kept (read-only).

    Parameters
    ----------
    kind
        ``"tool"``, ``"holder"`` or ``"spindle"``.
    key
        Hashable content of everything the part's FRF depends on besides the grid; None: not cached.
    freq : ndarray, shape (n_freq,)
        Frequency lines [Hz].
    build
        Computes the FRF when it is not kept.

    Returns
    -------
    FRF
    """
    if key is None:
        return build()
    try:
        full = (kind, key, _grid_key(freq))
        hash(full)
    except TypeError:
        return build()
    with _lock:
        hit = _memo.get(full)
        if hit is not None:
            _memo.move_to_end(full)
            return hit
    frf = build()
    with _lock:
        _memo[full] = frf
        _memo.move_to_end(full)
        while len(_memo) > MAX_ENTRIES or (len(_memo) > 1 and sum(v.values.nbytes for v in _memo.values()) > MAX_BYTES):
            _memo.popitem(last=False)
    return frf


def clear_part_cache() -> None:
    """Forget every kept part FRF."""
    with _lock:
        _memo.clear()
