"""The catalogue's vocabulary and its checks: interface materials (names, aliases, extension),
joint types, joint names, labels, model kinds with the DOF structure each requires of a joint FRF.

Used by the value types of :mod:`jointdb.store._types` (which re-exports these names) and by
every reader and writer that takes such a name from outside.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Sequence
from typing import Any

from jointdb.schemas import _limits
from jointdb.errors import InputError
from jointdb.frf import FRF, Dof, Quantity


# --------------------------------------------------------------------------- materials
#: Interface materials the catalogue accepts. Extend with :func:`register_material`
#: (for the running process) or the ``JOINTDB_MATERIALS`` environment variable
#: (comma-separated names, e.g. ``JOINTDB_MATERIALS=inconel,cfrp``).
KNOWN_MATERIALS: set[str] = {
    "steel",
    "hardened-steel",
    "stainless-steel",
    "tungsten-carbide",
    "cast-iron",
    "aluminium",
    "titanium",
    "brass",
    "bronze",
    "ceramic",
    "polymer-concrete",
}
#: Spellings that mean the same material.
MATERIAL_ALIASES: dict[str, str] = {
    "carbide": "tungsten-carbide",
    "wc": "tungsten-carbide",
    "aluminum": "aluminium",
    "al": "aluminium",
    "iron": "cast-iron",
    "ti": "titanium",
}


def known_materials() -> set[str]:
    """The accepted material names: built-in list plus ``JOINTDB_MATERIALS``.

    Returns
    -------
    set of str
    """
    extra = {m.strip().lower() for m in os.environ.get("JOINTDB_MATERIALS", "").split(",") if m.strip()}
    return KNOWN_MATERIALS | extra


def register_material(name: str) -> None:
    """Accept a new interface material name for the rest of this process.

    Parameters
    ----------
    name
        Letters, digits and ``-`` (spaces and ``_`` become ``-``; case is ignored).

    Raises
    ------
    InputError
        Any other character.
    """
    slug = str(name).strip().lower().replace(" ", "-").replace("_", "-")
    if not re.fullmatch(r"[a-z0-9][a-z0-9-]*", slug):
        raise InputError(f"material name {name!r} must be letters, digits and '-'")
    KNOWN_MATERIALS.add(slug)


def normalise_material(name: str) -> str:
    """Canonical material name; :class:`InputError` for an unknown one."""
    slug = str(name).strip().lower().replace(" ", "-").replace("_", "-")
    slug = MATERIAL_ALIASES.get(slug, slug)
    known = known_materials()
    if slug not in known:
        raise InputError(
            f"unknown material {name!r}; known: {', '.join(sorted(known))}. "
            "Add one with JOINTDB_MATERIALS=name1,name2 or jointdb.store.register_material()"
        )
    return slug


_SLUG = re.compile(r"[a-z0-9][a-z0-9-]*")


def check_joint_type(joint_type: str) -> str:
    """Joint type as a lower-case slug such as ``tool-holder`` or ``bolted-flange``."""
    jt = str(joint_type or "").strip().lower().replace(" ", "-").replace("_", "-").replace("–", "-")
    if not _SLUG.fullmatch(jt) or len(jt) > 100:
        raise InputError(
            f"joint type {joint_type!r} must be a short name of letters, digits and '-' "
            "(e.g. tool-holder, holder-spindle, bolted-flange, modular-thread)"
        )
    return jt


def check_name(name: str) -> str:
    """Joint name: 1-200 printable characters, no leading/trailing spaces, no '/'."""
    text = name if isinstance(name, str) else ""
    if not text or text != text.strip() or len(text) > 200 or "/" in text or not text.isprintable():
        raise InputError(
            f"joint name {str(name)[:60]!r} must be 1-200 printable characters without '/' or surrounding spaces"
        )
    return text


_LABEL = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,99}")


def check_label(label: str) -> str:
    """Label name: 1-100 letters, digits, '.', '_' or '-', starting with a letter or digit.

    Raises
    ------
    InputError
        Any other text (spaces, '/', quotes, empty, too long).
    """
    text = label.strip() if isinstance(label, str) else ""
    if not isinstance(label, str) or not _LABEL.fullmatch(text):
        raise InputError(f"label {str(label)[:120]!r} must be 1-100 letters, digits, '.', '_' or '-' "
                         "(starting with a letter or digit)")
    return text


def finite_nonneg(value: Any, what: str) -> float | None:
    if value is None:
        return None
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{what} must be a number, got {value!r}") from None
    if not math.isfinite(x) or abs(x) > _limits.MAX_JSON_NUMBER:  # what a stored record may hold
        raise InputError(f"{what} must be finite and of magnitude <= {_limits.MAX_JSON_NUMBER:g}, got {value!r}")
    if x < 0:
        raise InputError(f"{what} must be >= 0, got {x:g}")
    return x


# --------------------------------------------------------------------------- model kinds
#: Joint model kinds (docs/theory.md §1a, §2a-2c) and the
#: DOF structure each requires of the joint FRF (always a square receptance with
#: outputs == inputs):
#:
#: - ``spring-damper-planar``: DOFs with directions ``x`` and ``ry`` only (docs/theory.md §2a);
#: - ``n-point-translational``: translational DOFs only (docs/theory.md §2b, one spring per point);
#: - ``full-matrix``: exactly two nodes with the same direction set each (docs/theory.md §2c).
MODEL_KINDS: tuple[str, ...] = ("spring-damper-planar", "n-point-translational", "full-matrix")


def check_model_kind(model_kind: str, frf: FRF) -> str:
    """Check that the joint FRF has the DOF structure its model kind requires.

    Raises
    ------
    InputError
        Unknown kind, non-receptance, non-square FRF or DOFs that the kind does not allow.
    """
    kind = str(model_kind or "").strip().lower().replace("_", "-")
    if kind not in MODEL_KINDS:
        raise InputError(f"unknown model kind {model_kind!r}; expected one of {', '.join(MODEL_KINDS)}")
    if frf.quantity is not Quantity.RECEPTANCE:
        raise InputError(
            f"joint FRFs are stored as receptance, got {frf.quantity.value}; convert with frf.to('receptance')"
        )
    if frf.outputs != frf.inputs:
        raise InputError(
            "a joint FRF must be square on the same DOFs (outputs == inputs); got outputs "
            f"[{' '.join(map(str, frf.outputs))}] and inputs [{' '.join(map(str, frf.inputs))}]"
        )
    dof_list: tuple[Dof, ...] = frf.outputs
    if kind == "spring-damper-planar":
        bad = [d for d in dof_list if d.direction not in ("x", "ry")]
        if bad:
            raise InputError(
                f"model kind spring-damper-planar allows directions x and ry only; DOF {bad[0]} does not fit "
                "(use full-matrix for 3-D joints)"
            )
    elif kind == "n-point-translational":
        bad = [d for d in dof_list if d.is_rotation]
        if bad:
            raise InputError(
                f"model kind n-point-translational allows translational DOFs only; DOF {bad[0]} is a rotation"
            )
    else:
        nodes: dict[int, set[str]] = {}
        for d in dof_list:
            nodes.setdefault(d.node, set()).add(d.direction)
        if len(nodes) != 2:
            raise InputError(
                f"model kind full-matrix needs DOFs on exactly two joint nodes, got nodes {sorted(nodes)}"
            )
        a, b = nodes.values()
        if a != b:
            raise InputError(
                "model kind full-matrix needs the same directions on both joint nodes, got "
                f"{sorted(a)} and {sorted(b)}"
            )
    return kind


def dof_strings(labels: Sequence[Dof]) -> tuple[str, ...]:
    return tuple(str(d) for d in labels)
