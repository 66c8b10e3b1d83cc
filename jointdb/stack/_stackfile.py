"""Reading and writing stack documents (JSON, format ``jointdb-stack/1``).

``stack_from_dict`` checks every field and reports problems as an
:class:`~jointdb.errors.InputError` naming the exact field, e.g.
``tool.segments[1].length: must be > 0 m (got -0.01)``; ``stack_to_dict``
writes the same document back. The dataclasses are in :mod:`jointdb.stack._spec`.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from typing import Any

from jointdb._limits import (
    LENGTH_RANGE,
    MAX_SEGMENTS,
    check_count,
    check_elements,
    check_model_limits,
    check_range,
)
from jointdb.errors import InputError
from jointdb.stack._spec import (
    FORMAT,
    INTERFACE_NAMES,
    KOPS_VO_RATIO,
    FrequencyGrid,
    Holder,
    HolderSegment,
    JointChoice,
    MeasuredSpindle,
    ModelledSpindle,
    StackSpec,
    Tool,
    ToolSegment,
)

__all__ = ["stack_from_dict", "stack_to_dict"]

_REF_RE = re.compile(r"^\s*([^@\s]+)\s*@\s*([^@\s]+)\s*$")


# ------------------------------------------------------------------ helpers
def _fail(path: str, text: str) -> InputError:
    return InputError(f"{path}: {text}")


def _mapping(value: Any, path: str) -> Mapping[str, Any]:
    if not isinstance(value, Mapping):
        raise _fail(path, f"must be an object, got {type(value).__name__}")
    return value


def _known(obj: Mapping[str, Any], path: str, allowed: Sequence[str]) -> None:
    for key in obj:
        if key not in allowed:
            where = f"{path}.{key}" if path else str(key)
            raise _fail(where, f"unknown field; expected one of {', '.join(allowed)}")


def _number(obj: Mapping[str, Any], key: str, path: str, *, default: Any = ..., positive: bool = False,
            nonneg: bool = False, upper: float | None = None) -> float:
    where = f"{path}.{key}" if path else key
    if key not in obj:
        if default is ...:
            raise _fail(where, "required field is missing")
        return default
    value = obj[key]
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise _fail(where, f"must be a finite number, got {value!r}")
    value = float(value)
    if positive and value <= 0:
        raise _fail(where, f"must be > 0 (got {value:g})")
    if nonneg and value < 0:
        raise _fail(where, f"must be >= 0 (got {value:g})")
    if upper is not None and value > upper:
        raise _fail(where, f"must be <= {upper:g} (got {value:g})")
    return value


def _string(obj: Mapping[str, Any], key: str, path: str, default: Any = ...) -> str:
    where = f"{path}.{key}" if path else key
    if key not in obj:
        if default is ...:
            raise _fail(where, "required field is missing")
        return default
    value = obj[key]
    if not isinstance(value, str) or not value.strip():
        raise _fail(where, f"must be a non-empty string, got {value!r}")
    return value.strip()


def _list(obj: Mapping[str, Any], key: str, path: str) -> list:
    where = f"{path}.{key}"
    if key not in obj:
        raise _fail(where, "required field is missing")
    value = obj[key]
    if not isinstance(value, (list, tuple)) or not value:
        raise _fail(where, "must be a non-empty list")
    return list(value)


def _lengths_in_range(obj: Mapping[str, Any], path: str, keys: Sequence[str]) -> None:
    """Lengths and diameters within the physical range of :mod:`jointdb._limits` (1 µm … 100 m)."""
    for key in keys:
        check_range(obj.get(key), f"{path}.{key}", *LENGTH_RANGE)


# ------------------------------------------------------------------ parsing
def _tool(obj: Any, path: str) -> Tool:
    obj = _mapping(obj, path)
    _known(obj, path, ("material", "segments", "fluted_ratio", "fluted_area_ratio", "loss_factor"))
    segs = []
    raws = _list(obj, "segments", path)
    check_count(len(raws), f"{path}.segments", MAX_SEGMENTS, "segments")
    for i, raw in enumerate(raws):
        p = f"{path}.segments[{i}]"
        raw = _mapping(raw, p)
        _known(raw, p, ("length", "diameter", "fluted"))
        _lengths_in_range(raw, p, ("length", "diameter"))
        fluted = raw.get("fluted", False)
        if not isinstance(fluted, bool):
            raise _fail(f"{p}.fluted", f"must be true or false, got {fluted!r}")
        segs.append(ToolSegment(_number(raw, "length", p, positive=True), _number(raw, "diameter", p, positive=True),
                                fluted))
    seen_shank = False
    for i, s in enumerate(segs):
        if s.fluted and seen_shank:
            raise _fail(f"{path}.segments[{i}].fluted",
                        "fluted sections must come first (the tool is described from its tip)")
        seen_shank |= not s.fluted
    return Tool(
        tuple(segs),
        material=_string(obj, "material", path, "carbide"),
        fluted_ratio=_number(obj, "fluted_ratio", path, default=KOPS_VO_RATIO, positive=True, upper=1.0),
        loss_factor=_number(obj, "loss_factor", path, default=0.0, nonneg=True),
        fluted_area_ratio=_number(obj, "fluted_area_ratio", path, default=None, positive=True, upper=1.0),
    )


def _holder(obj: Any, path: str) -> Holder:
    obj = _mapping(obj, path)
    _known(obj, path, ("material", "segments", "loss_factor"))
    segs = []
    raws = _list(obj, "segments", path)
    check_count(len(raws), f"{path}.segments", MAX_SEGMENTS, "segments")
    for i, raw in enumerate(raws):
        p = f"{path}.segments[{i}]"
        raw = _mapping(raw, p)
        _known(raw, p, ("length", "outer_diameter", "inner_diameter"))
        _lengths_in_range(raw, p, ("length", "outer_diameter", "inner_diameter"))
        seg = HolderSegment(
            _number(raw, "length", p, positive=True),
            _number(raw, "outer_diameter", p, positive=True),
            _number(raw, "inner_diameter", p, default=0.0, nonneg=True),
        )
        if seg.inner_diameter >= seg.outer_diameter:
            raise _fail(f"{p}.inner_diameter",
                        f"must be smaller than outer_diameter ({seg.inner_diameter:g} >= {seg.outer_diameter:g})")
        segs.append(seg)
    return Holder(tuple(segs), material=_string(obj, "material", path, "steel"),
                  loss_factor=_number(obj, "loss_factor", path, default=0.0, nonneg=True))


def _spindle(obj: Any, path: str) -> MeasuredSpindle | ModelledSpindle:
    obj = _mapping(obj, path)
    if "file" in obj and "model" in obj:
        raise _fail(path, "give either 'file' (measured FRF) or 'model' (beam model), not both")
    if "file" in obj:
        _known(obj, path, ("file", "node"))
        node = obj.get("node")
        if isinstance(node, bool) or not isinstance(node, int) or node < 0:
            raise _fail(f"{path}.node", f"must be a non-negative integer node number, got {node!r}")
        return MeasuredSpindle(_string(obj, "file", path), node)
    if "model" in obj:
        _known(obj, path, ("model", "point"))
        model = obj["model"]
        if not isinstance(model, (Mapping, str)):
            raise _fail(f"{path}.model", "must be a beam model object or the path of a model JSON file")
        if isinstance(model, Mapping):
            try:
                check_model_limits(dict(model))
            except InputError as exc:
                raise _fail(f"{path}.model", str(exc)) from None
        return ModelledSpindle(model, _string(obj, "point", path))
    raise _fail(path, "needs 'file' + 'node' (measured FRF with rotations) or 'model' + 'point' (beam model)")


def _pair(obj: Mapping[str, Any], key: str, path: str, *, positive: bool) -> tuple[float, float]:
    where = f"{path}.{key}"
    if key not in obj:
        raise _fail(where, "required field is missing")
    value = obj[key]
    if not isinstance(value, (list, tuple)) or len(value) != 2:
        raise _fail(where, "must be a list of two numbers [translational, rotational]")
    out = []
    for i, v in enumerate(value):
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise _fail(f"{where}[{i}]", f"must be a finite number, got {v!r}")
        if (positive and v <= 0) or v < 0:
            raise _fail(f"{where}[{i}]", f"must be {'> 0' if positive else '>= 0'} (got {v:g})")
        out.append(float(v))
    return out[0], out[1]


def _joint(obj: Any, path: str) -> JointChoice:
    if obj == "rigid" or obj is None:
        return JointChoice("rigid")
    if isinstance(obj, str):
        m = _REF_RE.match(obj)
        if not m:
            raise _fail(path, f"{obj!r} is neither 'rigid' nor a pinned joint 'name@version'")
        version: int | str = int(m.group(2)) if m.group(2).isdigit() else m.group(2)
        return JointChoice("catalogued", name=m.group(1), version=version)
    obj = _mapping(obj, path)
    kinds = [k for k in ("rigid", "joint", "query", "k") if k in obj]
    if len(kinds) != 1:
        raise _fail(path, "give exactly one of 'rigid': true, 'joint': 'name@version', 'query': {...} or 'k'+'c'")
    if kinds[0] == "rigid":
        _known(obj, path, ("rigid",))
        if obj["rigid"] is not True:
            raise _fail(f"{path}.rigid", "must be true (omit it for a flexible joint)")
        return JointChoice("rigid")
    if kinds[0] == "joint":
        _known(obj, path, ("joint",))
        return _joint(_string(obj, "joint", path), f"{path}.joint")
    if kinds[0] == "k":
        _known(obj, path, ("k", "c"))
        return JointChoice("explicit", k=_pair(obj, "k", path, positive=True),
                           c=_pair(obj, "c", path, positive=False) if "c" in obj else (0.0, 0.0))
    _known(obj, path, ("query",))
    q = _mapping(obj["query"], f"{path}.query")
    qp = f"{path}.query"
    _known(q, qp, ("joint_type", "materials", "torque_nm", "preload_n", "geometry", "extra", "neighbours",
                   "interpolate"))
    conditions: dict[str, Any] = {}
    if "materials" in q:
        mats = q["materials"]
        if isinstance(mats, str):
            mats = [mats]
        if not isinstance(mats, (list, tuple)) or not all(isinstance(m, str) and m for m in mats):
            raise _fail(f"{qp}.materials", f"must be a list of material names, got {q['materials']!r}")
        conditions["materials"] = tuple(mats)
    for key in ("torque_nm", "preload_n"):
        if key in q:
            conditions[key] = _number(q, key, qp, nonneg=True)
    for key in ("geometry", "extra"):
        if key in q:
            conditions[key] = dict(_mapping(q[key], f"{qp}.{key}"))
    for key, value in conditions.get("geometry", {}).items():
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise _fail(f"{qp}.geometry.{key}", f"must be a finite number, got {value!r}")
    neighbours = q.get("neighbours", 3)
    if isinstance(neighbours, bool) or not isinstance(neighbours, int) or neighbours < 1:
        raise _fail(f"{qp}.neighbours", f"must be a positive integer, got {neighbours!r}")
    interpolate = q.get("interpolate", False)
    if not isinstance(interpolate, bool):
        raise _fail(f"{qp}.interpolate", f"must be true or false, got {interpolate!r}")
    return JointChoice("query", joint_type=_string(q, "joint_type", qp), conditions=conditions,
                       neighbours=neighbours, interpolate=interpolate)


def _frequency(obj: Any, path: str) -> FrequencyGrid:
    obj = _mapping(obj, path)
    _known(obj, path, ("min", "max", "step"))
    grid = FrequencyGrid(_number(obj, "min", path, positive=True), _number(obj, "max", path, positive=True),
                         _number(obj, "step", path, positive=True))
    if grid.fmax <= grid.fmin:
        raise _fail(f"{path}.max", f"must exceed frequency.min ({grid.fmax:g} <= {grid.fmin:g})")
    if (grid.fmax - grid.fmin) / grid.step > 200_000:
        raise _fail(f"{path}.step", "gives more than 200000 lines; use a coarser step")
    return grid


def stack_from_dict(doc: Any) -> StackSpec:
    """Validate a stack document (parsed JSON) and build a :class:`StackSpec`.

    Raises
    ------
    InputError
        Naming the exact field, e.g. ``gauge_length: must be < the tool length
        0.08 m``, ``interfaces.tool-holder: 'th' is neither 'rigid' nor ...``.
    """
    doc = _mapping(doc, "stack")
    _known(doc, "", ("format", "name", "tool", "holder", "spindle", "gauge_length", "insertion_length",
                     "interfaces", "frequency"))
    fmt = doc.get("format", FORMAT)
    if fmt != FORMAT:
        raise _fail("format", f"unsupported stack format {fmt!r}; this jointdb reads {FORMAT!r}")
    for key in ("tool", "holder", "spindle", "interfaces"):
        if key not in doc:
            raise _fail(key, "required field is missing")
    for key in ("tool", "holder", "spindle"):  # {"part": "name@version"}: resolved by the application layer
        if isinstance(doc[key], Mapping) and "part" in doc[key]:
            raise _fail(f"{key}.part", "a catalogued part is resolved from the database first "
                                       "(jointdb.usecases.stack_from_document; `jointdb predict` does it)")
    if "gauge_length" not in doc and "insertion_length" not in doc:
        raise _fail("gauge_length", "required field is missing (or give insertion_length)")
    tool = _tool(doc["tool"], "tool")
    holder = _holder(doc["holder"], "holder")
    # the tool and holder are meshed with 5 mm elements (jointdb.stack._parts)
    check_elements([s.length for s in tool.segments], 0.005, "planar", "tool.segments")
    check_elements([s.length for s in holder.segments], 0.005, "planar", "holder.segments")
    spindle = _spindle(doc["spindle"], "spindle")
    given_insertion = _number(doc, "insertion_length", "", default=None, nonneg=True)
    if "gauge_length" in doc:
        gauge = _number(doc, "gauge_length", "", positive=True)
    else:
        gauge = tool.length - given_insertion
        if gauge <= 0:
            raise _fail("insertion_length", f"must be shorter than the tool ({tool.length:g} m), got "
                                            f"{given_insertion:g}")
    if gauge > tool.length + 1e-12:
        raise _fail("gauge_length", f"must not exceed the tool length {tool.length:g} m (got {gauge:g})")
    insertion = tool.length - gauge
    if given_insertion is not None and abs(given_insertion - insertion) > 1e-9:
        raise _fail("insertion_length", f"{given_insertion:g} m disagrees with tool length {tool.length:g} m − "
                                        f"gauge_length {gauge:g} m = {insertion:g} m; give one of them")
    if insertion > holder.length + 1e-12:
        raise _fail("gauge_length", f"leaves {insertion:g} m of tool inside the holder, longer than the holder "
                                    f"({holder.length:g} m)")
    # Inside the holder, the tool must be a shank that fits the bore.
    pos = 0.0
    for i, seg in enumerate(tool.segments):
        start, end = pos, pos + seg.length
        pos = end
        if end <= gauge + 1e-12:
            continue
        if seg.fluted:
            raise _fail(f"tool.segments[{i}].fluted", "a fluted section reaches inside the holder; "
                                                      "increase gauge_length")
        depth_from, depth_to = max(start, gauge) - gauge, end - gauge
        hpos = 0.0
        for j, hseg in enumerate(holder.segments):
            h0, h1 = hpos, hpos + hseg.length
            hpos = h1
            if h1 <= depth_from + 1e-12 or h0 >= depth_to - 1e-12:
                continue
            if hseg.inner_diameter + 1e-12 < seg.diameter:
                raise _fail(f"holder.segments[{j}].inner_diameter",
                            f"bore {hseg.inner_diameter * 1e3:g} mm is smaller than the inserted tool shank "
                            f"(tool.segments[{i}].diameter {seg.diameter * 1e3:g} mm)")
    interfaces_raw = _mapping(doc["interfaces"], "interfaces")
    _known(interfaces_raw, "interfaces", INTERFACE_NAMES)
    interfaces = {name: _joint(interfaces_raw.get(name, "rigid"), f"interfaces.{name}") for name in INTERFACE_NAMES}
    frequency = _frequency(doc["frequency"], "frequency") if "frequency" in doc else None
    name = _string(doc, "name", "", "stack")
    return StackSpec(name, tool, holder, spindle, gauge, interfaces, frequency)


def _joint_to_obj(j: JointChoice) -> Any:
    if j.kind == "rigid":
        return "rigid"
    if j.kind == "catalogued":
        return f"{j.name}@{j.version}"
    if j.kind == "explicit":
        return {"k": list(j.k or ()), "c": list(j.c or ())}
    q: dict[str, Any] = {"joint_type": j.joint_type}
    for key, value in (j.conditions or {}).items():
        q[key] = list(value) if isinstance(value, tuple) else value
    q["neighbours"] = j.neighbours
    q["interpolate"] = j.interpolate
    return {"query": q}


def stack_to_dict(spec: StackSpec) -> dict[str, Any]:
    """The JSON document of a stack (inverse of :func:`stack_from_dict`)."""
    doc: dict[str, Any] = {
        "format": FORMAT,
        "name": spec.name,
        "tool": {
            "material": spec.tool.material,
            "fluted_ratio": spec.tool.fluted_ratio,
            "loss_factor": spec.tool.loss_factor,
            **({"fluted_area_ratio": spec.tool.fluted_area_ratio} if spec.tool.fluted_area_ratio is not None else {}),
            "segments": [
                {"length": s.length, "diameter": s.diameter, **({"fluted": True} if s.fluted else {})}
                for s in spec.tool.segments
            ],
        },
        "gauge_length": spec.gauge_length,
        "holder": {
            "material": spec.holder.material,
            "loss_factor": spec.holder.loss_factor,
            "segments": [
                {"length": s.length, "outer_diameter": s.outer_diameter, "inner_diameter": s.inner_diameter}
                for s in spec.holder.segments
            ],
        },
        "spindle": (
            {"file": spec.spindle.file, "node": spec.spindle.node}
            if isinstance(spec.spindle, MeasuredSpindle)
            else {"model": spec.spindle.model, "point": spec.spindle.point}
        ),
        "interfaces": {name: _joint_to_obj(j) for name, j in spec.interfaces.items()},
    }
    if spec.frequency is not None:
        doc["frequency"] = {"min": spec.frequency.fmin, "max": spec.frequency.fmax, "step": spec.frequency.step}
    return doc
