"""The JSON model description file: reading, validating and writing.

Format (SI units; every field except ``segments`` optional)::

    {
      "format": "jointdb-beam-model/1",
      "name": "carbide end mill, 12 mm",
      "kind": "planar",                      # or "frame3d"
      "theory": "timoshenko",                # or "euler-bernoulli"
      "max_element_length": 0.004,           # m
      "materials": {"my-wc": {"E": 580e9, "nu": 0.22, "rho": 14500}},
      "segments": [
        {"length": 0.035, "outer_diameter": 0.0108, "material": "carbide"},
        {"length": 0.055, "outer_diameter": 0.012, "inner_diameter": 0.0, "material": "my-wc"}
      ],
      "points": [{"name": "tip", "position": 0.0, "node": 1}],
      "clamps": [{"position": 0.09}],        # optional "directions": ["x"]
      "supports": [{"position": 0.05, "stiffness": {"x": 1e7}, "damping": {"x": 50}}],
      "point_masses": [{"position": 0.0, "mass": 0.002, "rotary_inertia": 1e-8}],
      "joints": [{"position": 0.035, "stiffness": {"x": 2e8, "ry": 4e5}, "loss_factor": 0.05,
                  "label": "flange"}],        # splits the shaft; directions not given stay rigid
      "insertions": [{"start": 0.06, "end": 0.09, "outer_diameter": 0.012, "material": "carbide",
                      "joined_at": "start",   # the end that continues as the main beam (the mouth)
                      "contact": "rigid",     # or {"stiffness_per_length": {"x": 5e11}, "loss_factor": 0.1}
                      "label": "tool shank in holder bore"}],
      "damping": [{"type": "modal", "zeta": 0.01},
                  {"type": "rayleigh", "alpha": 0.0, "beta": 1e-7},
                  {"type": "hysteretic", "eta": 0.002}]
    }

A joint splits the shaft at its position into two sides tied by springs (a
tool–holder face, a bolted flange). An insertion is a concentric part inside the
host segments over ``[start, end]`` (a tool shank in the holder bore) that
continues as the main beam beyond ``joined_at``; it is bonded to the host
(``"rigid"``) or held by a distributed contact layer (N/m² per direction, with a
loss factor). Segment materials are a library name (:data:`MATERIALS`), a name defined in
``materials``, or an inline ``{"E": ..., "nu": ..., "rho": ...}``. Positions
are metres from z = 0 (the start of the first segment). Errors name the exact
field, e.g. ``segments[1].outer_diameter: must be > 0, got -0.01``.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import TYPE_CHECKING, Any

from jointdb.schemas._jsonfile import read_json_file
from jointdb.schemas._limits import check_model_limits
from jointdb.errors import InputError, field_error
from jointdb.fe._ingredients import (
    Clamp,
    FieldError,
    HystereticDamping,
    ModalDamping,
    PointMass,
    RayleighDamping,
    Support,
)
from jointdb.fe._joints import Contact, Insertion, Joint
from jointdb.fe._materials import MATERIALS, Material
from jointdb.fe._model import BeamModel, NamedPoint, Segment

if TYPE_CHECKING:  # the schema (pydantic) is imported when a file is read, not with jointdb.fe
    from jointdb.schemas import model as schema

__all__ = ["load_model", "model_from_dict", "model_to_dict", "FORMAT"]

FORMAT = "jointdb-beam-model/1"

_DAMPING_TYPES = ("modal", "rayleigh", "hysteretic")
_BOUND = {"greater_than": ">", "greater_than_equal": ">="}
_MATERIAL_RANGE = {"E": "must be > 0 Pa", "rho": "must be > 0 kg/m^3", "nu": "must be in (-1, 0.5)"}


def _wording(field: str, err: dict[str, Any]) -> str | None:
    """This reader's words for a schema error (the messages the model file always gave)."""
    kind, value = err.get("type"), err.get("input")
    if field == "format" and kind == "literal_error":
        return f"format: unsupported format {value!r} (this jointdb reads {FORMAT!r})"
    if field == "segments" and kind == "too_short":
        return "segments: needs at least one segment"
    if kind == "union_tag_invalid":
        tag = (err.get("ctx") or {}).get("tag")
        return f"{field}: must be one of {', '.join(_DAMPING_TYPES)}, got {tag!r}"
    if re.fullmatch(r"points\[\d+\]\.node", field) and kind != "missing":
        return f"{field}: must be an integer >= 0, got {value!r}"
    if re.search(r"\.zeta(\[\d+\])?$", field) and kind not in ("missing", "union_none"):
        return f"{field}: must be a number >= 0, got {value!r}"
    if kind == "finite_number":
        return f"{field}: must be finite, got {value!r}"
    material = re.fullmatch(r"(.*)\.(E|nu|rho)", field)
    if material and kind in ("greater_than", "greater_than_equal", "less_than", "less_than_equal"):
        return f"{material.group(1)}: {material.group(2)} {_MATERIAL_RANGE[material.group(2)]}, got {value:g}"
    if kind == "union_none" and field.endswith(".contact"):
        return f'{field}: must be "rigid" or a contact layer {{"stiffness_per_length": ...}}, got {value!r}'
    if kind == "union_none" and field.endswith("material"):
        return f"{field}: must be a material name or an object with E, nu, rho, got {value!r}"
    return None


def _build(cls, path: str, **kwargs):
    try:
        return cls(**kwargs)
    except FieldError as exc:
        raise field_error(f"{path}.{exc.field}", exc.reason) from None
    except InputError as exc:
        raise field_error(path, str(exc)) from None


def _material(value: "str | schema.InlineMaterial", path: str, named: dict[str, Material],
              default_name: str = "custom") -> "str | Material":
    """A library name, a name the file defines, or the constants of an inline material."""
    if isinstance(value, str):
        key = value.strip().lower()
        if key in named:
            return named[key]
        if key in MATERIALS:
            return key
        known = ", ".join(sorted(set(MATERIALS) | set(named)))
        raise field_error(path, f"unknown material {value!r} (known: {known}; or give {{E, nu, rho}})")
    try:
        return Material(value.name or default_name, value.E, value.nu, value.rho)
    except InputError as exc:
        raise field_error(path, str(exc).split(": ", 1)[-1]) from None


def _materials(doc: "schema.BeamModelFile") -> dict[str, Material]:
    """The file's ``materials``: a new material {E, nu, rho} (named by its key) or an alias of a library one."""
    named: dict[str, Material] = {}
    for key, spec in doc.materials.items():
        mat = _material(spec, f"materials.{key}", {}, default_name=str(key))
        named[str(key).strip().lower()] = mat if isinstance(mat, Material) else MATERIALS[mat]
    return named


def _segments(doc: "schema.BeamModelFile", named: dict[str, Material]) -> list[Segment]:
    return [_build(Segment, f"segments[{i}]", length=s.length, outer_diameter=s.outer_diameter,
                   inner_diameter=s.inner_diameter, material=_material(s.material, f"segments[{i}].material", named))
            for i, s in enumerate(doc.segments)]


def _points(doc: "schema.BeamModelFile") -> list[NamedPoint]:
    return [_build(NamedPoint, f"points[{i}]", name=pt.name, position=pt.position, node=pt.node)
            for i, pt in enumerate(doc.points)]


def _clamp(c: "schema.Clamp", p: str, named: dict[str, Material]) -> Clamp:
    return _build(Clamp, p, position=c.position, directions=None if c.directions is None else tuple(c.directions))


def _support(s: "schema.Support", p: str, named: dict[str, Material]) -> Support:
    return _build(Support, p, position=s.position, stiffness=dict(s.stiffness), damping=dict(s.damping))


def _point_mass(m: "schema.PointMass", p: str, named: dict[str, Material]) -> PointMass:
    return _build(PointMass, p, position=m.position, mass=m.mass, rotary_inertia=m.rotary_inertia or 0.0,
                  polar_inertia=m.polar_inertia or 0.0)


def _joint(j: "schema.Joint", p: str, named: dict[str, Material]) -> Joint:
    return _build(Joint, p, position=j.position, stiffness=dict(j.stiffness), damping=dict(j.damping or {}),
                  loss_factor=j.loss_factor or 0.0, label=j.label or "")


def _insertion(s: "schema.Insertion", p: str, named: dict[str, Material]) -> Insertion:
    contact: Any = s.contact
    if not isinstance(contact, str):
        contact = _build(Contact, f"{p}.contact", stiffness_per_length=dict(contact.stiffness_per_length),
                         loss_factor=contact.loss_factor or 0.0)
    return _build(Insertion, p, start=s.start, end=s.end, outer_diameter=s.outer_diameter,
                  inner_diameter=s.inner_diameter, material=_material(s.material, f"{p}.material", named),
                  joined_at=s.joined_at, contact=contact, label=s.label or "")


def _damping(dm: Any, p: str, named: dict[str, Material]):
    if dm.type == "modal":
        return _build(ModalDamping, p, zeta=tuple(dm.zeta) if isinstance(dm.zeta, list) else dm.zeta)
    if dm.type == "rayleigh":
        return _build(RayleighDamping, p, alpha=dm.alpha, beta=dm.beta)
    return _build(HystereticDamping, p, eta=dm.eta)


#: The ingredient lists of a model file, in the order they are read, and the reader of one entry.
_INGREDIENTS = (("clamps", _clamp), ("supports", _support), ("point_masses", _point_mass), ("joints", _joint),
                ("insertions", _insertion), ("damping", _damping))


def _ingredients(doc: "schema.BeamModelFile", named: dict[str, Material]) -> tuple[list, list[str]]:
    """Every ingredient of the file and the field path of each (``clamps[0]``, ``damping[1]`` ...)."""
    ingredients: list = []
    paths: list[str] = []
    for key, read in _INGREDIENTS:
        entries = getattr(doc, key)
        if key == "damping" and not isinstance(entries, list):  # one damping model may stand alone
            entries = [entries]
        for i, entry in enumerate(entries):
            ingredients.append(read(entry, f"{key}[{i}]", named))
            paths.append(f"{key}[{i}]")
    return ingredients, paths


def model_from_dict(data: Any) -> BeamModel:
    """Build a :class:`BeamModel` from a parsed model description (see module docstring).

    The structure, JSON types and single-field ranges are those of the published schema
    (:class:`jointdb.schemas.model.BeamModelFile`, ``docs/schemas/beam-model.schema.json``),
    which reads the document; this function adds what a schema cannot say (materials by
    name, positions inside the model, a damper only where there is a spring).

    Parameters
    ----------
    data : Any
        The parsed JSON of a model file (format ``jointdb-beam-model/1``); lengths in m,
        stiffnesses in N/m and N·m/rad, masses in kg.

    Returns
    -------
    BeamModel
        The model the document describes, every cross-field rule checked.

    Raises
    ------
    InputError
        Naming the exact field that is wrong, e.g. ``segments[1].outer_diameter: must be > 0, got 0``,
        or a resource limit exceeded (segments, elements, magnitudes; see :mod:`jointdb.schemas._limits`).
    """
    from jointdb.schemas import parse

    if not isinstance(data, dict):
        raise field_error("model", f"must be an object, got {type(data).__name__}")
    check_model_limits(data)  # sizes, magnitudes and element count before anything is built
    doc = parse("model", data, wording=_wording)
    named = _materials(doc)
    segments = _segments(doc, named)
    points = _points(doc)
    ingredients, paths = _ingredients(doc, named)
    try:
        return BeamModel(segments=tuple(segments), points=tuple(points), ingredients=tuple(ingredients),
                         theory=doc.theory, kind=doc.kind, max_element_length=doc.max_element_length,
                         name=doc.name or "")
    except FieldError as exc:
        field = exc.field
        if field.startswith("ingredients["):
            idx = int(field[len("ingredients["): field.index("]")])
            field = paths[idx] + field[field.index("]") + 1:]
        raise field_error(field, exc.reason) from None


def load_model(path: "str | Path") -> BeamModel:
    """Read a JSON model description file.

    Parameters
    ----------
    path
        The model file (``jointdb-beam-model/1``, SI units).

    Returns
    -------
    BeamModel

    Raises
    ------
    NotFoundError
        If the file does not exist.
    InputError
        On invalid JSON (with line and column) or an invalid field (with its path).
    """
    p = Path(path)
    data = read_json_file(p, "model file")
    try:
        return model_from_dict(data)
    except InputError as exc:
        raise InputError(f"{p.name}: {exc}") from None


def model_to_dict(model: BeamModel) -> dict:
    """The model as a JSON-ready dict that :func:`model_from_dict` reads back to an equal model.

    Parameters
    ----------
    model
        Any :class:`BeamModel`, built in code or read from a file.

    Returns
    -------
    dict
    """
    out: dict[str, Any] = {"format": FORMAT}
    if model.name:
        out["name"] = model.name
    out.update(kind=model.kind, theory=model.theory, max_element_length=model.max_element_length)
    segs = []
    for s in model.segments:
        mat = s.material
        if isinstance(mat, Material):
            mat = {"name": mat.name, "E": mat.E, "nu": mat.nu, "rho": mat.rho}
        segs.append({"length": s.length, "outer_diameter": s.outer_diameter,
                     "inner_diameter": s.inner_diameter, "material": mat})
    out["segments"] = segs
    out["points"] = [{"name": p.name, "position": p.position, "node": p.node} for p in model.points]
    clamps, supports, masses, damping, joints, insertions = [], [], [], [], [], []
    for ing in model.ingredients:
        if isinstance(ing, Clamp):
            c = {"position": ing.position}
            if ing.directions is not None:
                c["directions"] = list(ing.directions)
            clamps.append(c)
        elif isinstance(ing, Support):
            supports.append({"position": ing.position, "stiffness": dict(ing.stiffness), "damping": dict(ing.damping)})
        elif isinstance(ing, PointMass):
            masses.append({"position": ing.position, "mass": ing.mass, "rotary_inertia": ing.rotary_inertia,
                           "polar_inertia": ing.polar_inertia})
        elif isinstance(ing, ModalDamping):
            z = ing.zeta
            damping.append({"type": "modal", "zeta": list(z) if isinstance(z, tuple) else z})
        elif isinstance(ing, RayleighDamping):
            damping.append({"type": "rayleigh", "alpha": ing.alpha, "beta": ing.beta})
        elif isinstance(ing, HystereticDamping):
            damping.append({"type": "hysteretic", "eta": ing.eta})
        elif isinstance(ing, Joint):
            j = {"position": ing.position, "stiffness": dict(ing.stiffness)}
            if ing.damping:
                j["damping"] = dict(ing.damping)
            if ing.loss_factor:
                j["loss_factor"] = ing.loss_factor
            if ing.label:
                j["label"] = ing.label
            joints.append(j)
        elif isinstance(ing, Insertion):
            mat = ing.material
            if isinstance(mat, Material):
                mat = {"name": mat.name, "E": mat.E, "nu": mat.nu, "rho": mat.rho}
            contact = "rigid" if ing.rigid else {"stiffness_per_length": dict(ing.contact.stiffness_per_length),
                                                 "loss_factor": ing.contact.loss_factor}
            e = {"start": ing.start, "end": ing.end, "outer_diameter": ing.outer_diameter,
                 "inner_diameter": ing.inner_diameter, "material": mat, "joined_at": ing.joined_at,
                 "contact": contact}
            if ing.label:
                e["label"] = ing.label
            insertions.append(e)
        else:  # pragma: no cover - a new ingredient class must be added here
            raise InputError(f"cannot write ingredient {type(ing).__name__} to a model file")
    for key, value in (("clamps", clamps), ("supports", supports), ("point_masses", masses), ("damping", damping),
                       ("joints", joints), ("insertions", insertions)):
        if value:
            out[key] = value
    return out
