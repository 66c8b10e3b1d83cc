"""A version is the same joint, re-identified: what a new version must share with the previous one.

The conditions that *define* a joint are its materials, preload (drawbar force), tightening
torque, every geometry number (``insertion_m`` included), its model kind and DOFs (the joint
type is fixed by the name). A new version must keep every one the previous version recorded:

- a value the previous version recorded and the new one changes (or leaves out) is a
  contradiction: the write is refused (:class:`ConflictError` naming both values) unless it
  is forced, and a forced write's audit entry lists each change (``from`` -> ``to``);
- a value the previous version did not record (``None``, no materials, a geometry key it
  lacked) and the new one gives is *filled in*: not a contradiction (v2 = "the same FRF with
  one more condition recorded"); the audit entry lists what was filled in.

Free-form ``extra`` conditions and provenance do not define the joint.

A new version with the same content as the latest one (same FRF blob, conditions and model
kind) is *identical*: nothing is written and the latest version is the answer.
"""

from __future__ import annotations

import math
from typing import Any

from jointdb.errors import ConflictError

#: the scalar conditions that define a joint, in the order they are reported
_SCALARS = (("preload_n", "preload_n [N]"), ("torque_nm", "torque_nm [N·m]"))


def _same_number(a: float, b: float) -> bool:
    return math.isclose(float(a), float(b), rel_tol=1e-9, abs_tol=0.0)


def _show(value: Any) -> str:
    if value is None or value == [] or value == ():
        return "none"
    if isinstance(value, (list, tuple)):
        return "+".join(str(x) for x in value)
    if isinstance(value, float):
        return f"{value:g}"
    return str(value)


def identity_changes(prev: Any, new: dict[str, Any]) -> tuple[list[dict[str, Any]], list[str]]:
    """The defining conditions ``new`` contradicts, and those it fills in, against ``prev``.

    Parameters
    ----------
    prev
        The previous version's row (attributes ``materials``, ``preload_n``, ``torque_nm``,
        ``geometry``, ``model_kind``, ``dofs``).
    new
        The same keys for the version about to be written.

    Returns
    -------
    (changes, filled_in)
        ``changes``: ``{"condition", "from", "to"}`` for every contradiction;
        ``filled_in``: names of conditions the previous version did not record.
    """
    changes: list[dict[str, Any]] = []
    filled: list[str] = []

    def changed(what: str, old: Any, to: Any) -> None:
        changes.append({"condition": what, "from": old, "to": to})

    old_m, new_m = list(prev.materials or []), list(new["materials"] or [])
    if old_m and sorted(old_m) != sorted(new_m):
        changed("materials", old_m, new_m)
    elif not old_m and new_m:
        filled.append("materials")
    for key, _ in _SCALARS:
        old, to = getattr(prev, key), new[key]
        if old is not None and (to is None or not _same_number(old, to)):
            changed(key, old, to)
        elif old is None and to is not None:
            filled.append(key)
    old_g, new_g = dict(prev.geometry or {}), dict(new["geometry"] or {})
    for key in sorted(set(old_g) | set(new_g)):
        if key in old_g and (key not in new_g or not _same_number(old_g[key], new_g[key])):
            changed(f"geometry.{key}", old_g[key], new_g.get(key))
        elif key not in old_g:
            filled.append(f"geometry.{key}")
    if prev.model_kind != new["model_kind"]:
        changed("model_kind", prev.model_kind, new["model_kind"])
    if list(prev.dofs) != list(new["dofs"]):
        changed("dofs", list(prev.dofs), list(new["dofs"]))
    return changes, filled


def describe(changes: list[dict[str, Any]], number: int) -> str:
    """``torque_nm 80 (v1) -> 30, materials ...``: each change with both values."""
    return ", ".join(f"{c['condition']} {_show(c['from'])} (v{number}) -> {_show(c['to'])}" for c in changes)


def contradiction(name: str, number: int, changes: list[dict[str, Any]]) -> ConflictError:
    """The one-line refusal of a version that is not the same joint as ``name`` v``number``."""
    return ConflictError(
        f"joint {name!r}: this is not the same joint as v{number} ({describe(changes, number)}); catalogue it "
        "under another name, or force it (--force, API \"force\": true) if the joint really changed")


def same_content(prev: Any, new: dict[str, Any]) -> bool:
    """Whether ``new`` holds exactly what the previous version holds (FRF, conditions, model kind)."""
    return (prev.blob_sha256 == new["blob_sha256"] and prev.model_kind == new["model_kind"]
            and sorted(prev.materials or []) == sorted(new["materials"] or [])
            and prev.preload_n == new["preload_n"] and prev.torque_nm == new["torque_nm"]
            and dict(prev.geometry or {}) == dict(new["geometry"] or {})
            and dict(prev.extra or {}) == dict(new["extra"] or {}))
