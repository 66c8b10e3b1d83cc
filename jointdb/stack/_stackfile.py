"""Reading and writing stack documents (JSON, format ``jointdb-stack/1``).

The schema :class:`jointdb.schemas.stack.StackFile` (published as
``docs/schemas/stack.schema.json``) reads the document: structure, JSON types and
single-field ranges. ``stack_from_dict`` then checks what a schema cannot say
(the tool fits the holder bore, fluted sections outside it, gauge and insertion
lengths agree, element counts) and builds the dataclasses of
:mod:`jointdb.stack._spec`. Problems are an :class:`~jointdb.errors.InputError`
naming the exact field, e.g. ``tool.segments[1].length: must be > 0, got -0.01``;
``stack_to_dict`` writes the same document back.
"""

from __future__ import annotations

import re
from typing import TYPE_CHECKING, Any

from jointdb.schemas._limits import LENGTH_RANGE, check_elements, check_model_limits
from jointdb.errors import InputError, field_error
from jointdb.stack._spec import FORMAT, INTERFACE_NAMES, FrequencyGrid, Holder, HolderSegment, JointChoice
from jointdb.stack._spec import MeasuredSpindle, ModelledSpindle, StackSpec, Tool, ToolSegment

if TYPE_CHECKING:  # the schema (pydantic) is imported when a stack is read, not with jointdb.stack
    from jointdb.schemas import stack as schema

__all__ = ["stack_from_dict", "stack_to_dict"]

_REF_RE = re.compile(r"^\s*([^@\s]+)\s*@\s*([^@\s]+)\s*$")
_BOUNDS = {"greater_than": ">", "greater_than_equal": ">=", "less_than": "<", "less_than_equal": "<="}
_SPINDLE_FIELDS = ("spindle.file", "spindle.node", "spindle.model", "spindle.point")


def _wording(field: str, err: dict[str, Any]) -> str | None:
    """This reader's words for a schema error (the messages stack files always gave)."""
    kind, value = err.get("type"), err.get("input")
    if field == "format" and kind == "literal_error":
        return f"format: unsupported stack format {value!r}; this jointdb reads {FORMAT!r}"
    if field in _SPINDLE_FIELDS and kind in ("missing", "extra_forbidden"):
        return ("spindle: give either 'file' + 'node' (measured FRF with rotations) or 'model' + 'point' "
                "(beam model), not both")
    if kind == "missing":
        return f"{field}: required field is missing"
    if kind in ("float_type", "float_parsing", "finite_number"):
        return f"{field}: must be a finite number, got {value!r}"
    if kind in _BOUNDS and isinstance(value, (int, float)):
        bound = next(iter((err.get("ctx") or {}).values()))
        op = _BOUNDS[kind]
        if kind == "greater_than_equal" and bound == LENGTH_RANGE[0] and value <= 0:
            op, bound = ">", 0  # a length or diameter; the range above 0 is jointdb.schemas._limits' to report
        return f"{field}: must be {op} {bound:g} (got {value:g})"
    if kind == "too_short" and field.endswith("segments"):
        return f"{field}: must be a non-empty list"
    if re.search(r"\.[kc]$", field) and kind in ("too_short", "too_long", "list_type"):
        return f"{field}: must be a list of two numbers [translational, rotational]"
    if kind == "extra_forbidden" and re.fullmatch(r"interfaces\.[^.]+", field):
        return f"{field}: unknown field; expected one of {', '.join(INTERFACE_NAMES)}"
    if kind == "union_none" and field == "spindle.model":
        return f"{field}: must be a beam model object or the path of a model JSON file"
    if kind == "union_none" and field.startswith("interfaces."):
        if isinstance(value, str):
            return f"{field}: {value!r} is neither 'rigid' nor a pinned joint 'name@version'"
        return f"{field}: give exactly one of 'rigid': true, 'joint': 'name@version', 'query': {{...}} or 'k'+'c'"
    return None


# ------------------------------------------------------------------ substructures
def _tool(t: "schema.Tool", path: str) -> Tool:
    segs = tuple(ToolSegment(s.length, s.diameter, s.fluted) for s in t.segments)
    seen_shank = False
    for i, s in enumerate(segs):
        if s.fluted and seen_shank:
            raise field_error(f"{path}.segments[{i}].fluted",
                        "fluted sections must come first (the tool is described from its tip)")
        seen_shank |= not s.fluted
    return Tool(segs, material=t.material.strip(), fluted_ratio=t.fluted_ratio, loss_factor=t.loss_factor,
                fluted_area_ratio=t.fluted_area_ratio)


def _holder(h: "schema.Holder", path: str) -> Holder:
    segs = []
    for i, s in enumerate(h.segments):
        if s.inner_diameter >= s.outer_diameter:
            raise field_error(f"{path}.segments[{i}].inner_diameter",
                        f"must be smaller than outer_diameter ({s.inner_diameter:g} >= {s.outer_diameter:g})")
        segs.append(HolderSegment(s.length, s.outer_diameter, s.inner_diameter))
    return Holder(tuple(segs), material=h.material.strip(), loss_factor=h.loss_factor)


def _spindle(sp: Any, raw: dict[str, Any], path: str) -> MeasuredSpindle | ModelledSpindle:
    if hasattr(sp, "file"):
        est = raw.get("estimate")  # the description as written: the application layer reads its files
        return MeasuredSpindle(sp.file.strip(), sp.node, estimate=dict(est) if est is not None else None)
    model = raw["model"]  # the description as written: the model reader builds it later
    if isinstance(model, dict):
        try:
            check_model_limits(model)
        except InputError as exc:
            raise field_error(f"{path}.model", str(exc)) from None
    return ModelledSpindle(model, sp.point.strip())


def _pinned(ref: str, path: str) -> JointChoice:
    m = _REF_RE.match(ref)
    if not m:  # pragma: no cover - the schema's pattern is the same
        raise field_error(path, f"{ref!r} is neither 'rigid' nor a pinned joint 'name@version'")
    version: int | str = int(m.group(2)) if m.group(2).isdigit() else m.group(2)
    return JointChoice("catalogued", name=m.group(1), version=version)


def _joint(choice: Any, path: str) -> JointChoice:
    """One interface: rigid, pinned ``name@version``, explicit ``k``/``c`` or a catalogue query."""
    if choice == "rigid" or hasattr(choice, "rigid"):
        return JointChoice("rigid")
    if isinstance(choice, str):
        return _pinned(choice, path)
    if hasattr(choice, "joint"):
        return _pinned(choice.joint, f"{path}.joint")
    if hasattr(choice, "k"):
        return JointChoice("explicit", k=(choice.k[0], choice.k[1]), c=(choice.c[0], choice.c[1]))
    q = choice.query
    conditions: dict[str, Any] = {}
    if q.materials is not None:
        conditions["materials"] = (q.materials,) if isinstance(q.materials, str) else tuple(q.materials)
    for key in ("torque_nm", "preload_n", "geometry", "extra"):
        value = getattr(q, key)
        if value is not None:
            conditions[key] = dict(value) if isinstance(value, dict) else value
    return JointChoice("query", joint_type=q.joint_type.strip(), conditions=conditions, neighbours=q.neighbours,
                       interpolate=q.interpolate)


def _frequency(f: "schema.FrequencyGrid", path: str) -> FrequencyGrid:
    grid = FrequencyGrid(f.min, f.max, f.step)
    if grid.fmax <= grid.fmin:
        raise field_error(f"{path}.max", f"must exceed frequency.min ({grid.fmax:g} <= {grid.fmin:g})")
    if (grid.fmax - grid.fmin) / grid.step > 200_000:
        raise field_error(f"{path}.step", "gives more than 200000 lines; use a coarser step")
    return grid


# ------------------------------------------------------------------ the stack
def _gauge(doc: "schema.StackFile", tool: Tool, holder: Holder) -> float:
    """The gauge length from ``gauge_length`` and/or ``insertion_length``, checked against tool and holder."""
    given = doc.insertion_length
    if doc.gauge_length is None and given is None:
        raise field_error("gauge_length", "required field is missing (or give insertion_length)")
    if doc.gauge_length is not None:
        gauge = doc.gauge_length
    else:
        gauge = tool.length - given
        if gauge <= 0:
            raise field_error("insertion_length", f"must be shorter than the tool ({tool.length:g} m), got {given:g}")
    if gauge > tool.length + 1e-12:
        raise field_error("gauge_length", f"must not exceed the tool length {tool.length:g} m (got {gauge:g})")
    insertion = tool.length - gauge
    if given is not None and abs(given - insertion) > 1e-9:
        raise field_error("insertion_length", f"{given:g} m disagrees with tool length {tool.length:g} m − "
                                        f"gauge_length {gauge:g} m = {insertion:g} m; give one of them")
    if insertion > holder.length + 1e-12:
        raise field_error("gauge_length", f"leaves {insertion:g} m of tool inside the holder, longer than the holder "
                                    f"({holder.length:g} m)")
    return gauge


def _check_insertion(tool: Tool, holder: Holder, gauge: float) -> None:
    """Inside the holder, the tool must be a shank that fits the bore."""
    pos = 0.0
    for i, seg in enumerate(tool.segments):
        start, end = pos, pos + seg.length
        pos = end
        if end <= gauge + 1e-12:
            continue
        if seg.fluted:
            raise field_error(f"tool.segments[{i}].fluted", "a fluted section reaches inside the holder; "
                                                      "increase gauge_length")
        depth_from, depth_to = max(start, gauge) - gauge, end - gauge
        hpos = 0.0
        for j, hseg in enumerate(holder.segments):
            h0, h1 = hpos, hpos + hseg.length
            hpos = h1
            if h1 <= depth_from + 1e-12 or h0 >= depth_to - 1e-12:
                continue
            if hseg.inner_diameter + 1e-12 < seg.diameter:
                raise field_error(f"holder.segments[{j}].inner_diameter",
                            f"bore {hseg.inner_diameter * 1e3:g} mm is smaller than the inserted tool shank "
                            f"(tool.segments[{i}].diameter {seg.diameter * 1e3:g} mm)")


def stack_from_dict(doc: Any) -> StackSpec:
    """Validate a stack document (parsed JSON) and build a :class:`StackSpec`.

    Parameters
    ----------
    doc : Any
        The parsed JSON of a stack file (format ``jointdb-stack/1``); lengths in m.

    Returns
    -------
    StackSpec

    Raises
    ------
    InputError
        Naming the exact field, e.g. ``gauge_length: must not exceed the tool length
        0.08 m``, ``interfaces.tool-holder: 'th' is neither 'rigid' nor ...``.
    """
    from jointdb.schemas import parse

    if not isinstance(doc, dict):
        raise field_error("stack", f"must be an object, got {type(doc).__name__}")
    for key in ("tool", "holder", "spindle"):  # {"part": "name@version"}: resolved by the application layer
        if isinstance(doc.get(key), dict) and "part" in doc[key]:
            raise field_error(f"{key}.part", "a catalogued part is resolved from the database first "
                                       "(jointdb.usecases.stack_from_document; `jointdb predict` does it)")
    parsed = parse("stack", doc, wording=_wording)
    tool = _tool(parsed.tool, "tool")
    holder = _holder(parsed.holder, "holder")
    # the tool and holder are meshed with 5 mm elements (jointdb.stack._parts)
    check_elements([s.length for s in tool.segments], 0.005, "planar", "tool.segments")
    check_elements([s.length for s in holder.segments], 0.005, "planar", "holder.segments")
    spindle = _spindle(parsed.spindle, doc["spindle"], "spindle")
    gauge = _gauge(parsed, tool, holder)
    _check_insertion(tool, holder, gauge)
    interfaces = {"tool-holder": _joint(parsed.interfaces.tool_holder, "interfaces.tool-holder"),
                  "holder-spindle": _joint(parsed.interfaces.holder_spindle, "interfaces.holder-spindle")}
    frequency = _frequency(parsed.frequency, "frequency") if parsed.frequency is not None else None
    return StackSpec(parsed.name.strip() or "stack", tool, holder, spindle, gauge, interfaces, frequency)


def substructure_from_dict(kind: str, obj: Any, path: str) -> Tool | Holder | MeasuredSpindle | ModelledSpindle:
    """One substructure object of a stack file — ``tool``, ``holder`` or ``spindle`` — checked with the
    stack schema and the stack reader's own rules (a catalogued part's payload, :mod:`jointdb.store`).

    Parameters
    ----------
    kind
        ``"tool"``, ``"holder"`` or ``"spindle"``.
    obj
        The object as a stack file would hold it.
    path
        Name of the object in messages (e.g. ``"payload"``).

    Returns
    -------
    Tool, Holder, MeasuredSpindle or ModelledSpindle

    Raises
    ------
    InputError
        Naming the field under ``path``.
    """
    from typing import Union

    from pydantic import TypeAdapter, ValidationError

    from jointdb.schemas import describe_error
    from jointdb.schemas import stack as schema

    types = {"tool": schema.Tool, "holder": schema.Holder,
             "spindle": Union[schema.MeasuredSpindle, schema.ModelledSpindle]}
    if kind not in types:
        raise InputError(f"{path}: kind must be tool, holder or spindle, got {kind!r}")
    if not isinstance(obj, dict):
        raise field_error(path, f"must be an object, got {type(obj).__name__}")
    try:
        parsed = TypeAdapter(types[kind]).validate_python(obj)
    except ValidationError as exc:
        raise InputError(f"{path}.{describe_error(exc, 'stack', _wording)}") from None
    if kind == "tool":
        return _tool(parsed, path)
    if kind == "holder":
        return _holder(parsed, path)
    return _spindle(parsed, obj, path)


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
    """The JSON document of a stack (inverse of :func:`stack_from_dict`).

    Parameters
    ----------
    spec
        A :class:`StackSpec`, built in code or as :func:`stack_from_dict` returns it.

    Returns
    -------
    dict
        The ``jointdb-stack/1`` document (SI units).
    """
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
            {"file": spec.spindle.file, "node": spec.spindle.node,
             **({"estimate": spec.spindle.estimate} if isinstance(spec.spindle.estimate, dict) else {})}
            if isinstance(spec.spindle, MeasuredSpindle)
            else {"model": spec.spindle.model, "point": spec.spindle.point}
        ),
        "interfaces": {name: _joint_to_obj(j) for name, j in spec.interfaces.items()},
    }
    if spec.frequency is not None:
        doc["frequency"] = {"min": spec.frequency.fmin, "max": spec.frequency.fmax, "step": spec.frequency.step}
    return doc
