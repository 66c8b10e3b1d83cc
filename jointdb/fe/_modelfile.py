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

import math
from pathlib import Path
from typing import Any

from jointdb._jsonfile import read_json_file
from jointdb._limits import check_model_limits
from jointdb.errors import InputError
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

__all__ = ["load_model", "model_from_dict", "model_to_dict", "FORMAT"]

FORMAT = "jointdb-beam-model/1"

_TOP = {
    "format", "name", "description", "kind", "theory", "max_element_length", "materials", "segments",
    "points", "clamps", "supports", "point_masses", "damping", "source", "joints", "insertions",
}
_DAMPING = {
    "modal": (ModalDamping, {"zeta"}),
    "rayleigh": (RayleighDamping, {"alpha", "beta"}),
    "hysteretic": (HystereticDamping, {"eta"}),
}


def _fail(path: str, reason: str) -> InputError:
    return InputError(f"{path}: {reason}")


def _obj(value: Any, path: str) -> dict:
    if not isinstance(value, dict):
        raise _fail(path, f"must be an object, got {type(value).__name__}")
    return value


def _list(value: Any, path: str) -> list:
    if not isinstance(value, list):
        raise _fail(path, f"must be a list, got {type(value).__name__}")
    return value


def _keys(d: dict, path: str, allowed: set, required: set = frozenset()) -> None:
    for key in d:
        if key not in allowed:
            raise _fail(f"{path}.{key}" if path else key, f"unknown field (expected one of: {', '.join(sorted(allowed))})")
    for key in sorted(required):
        if key not in d:
            raise _fail(f"{path}.{key}" if path else key, "is required")


def _build(cls, path: str, **kwargs):
    try:
        return cls(**kwargs)
    except FieldError as exc:
        raise _fail(f"{path}.{exc.field}", exc.reason) from None
    except InputError as exc:
        raise _fail(path, str(exc)) from None


def _material(value: Any, path: str, named: dict[str, Material], default_name: str = "custom"):
    if isinstance(value, str):
        key = value.strip().lower()
        if key in named:
            return named[key]
        if key in MATERIALS:
            return key
        known = ", ".join(sorted(set(MATERIALS) | set(named)))
        raise _fail(path, f"unknown material {value!r} (known: {known}; or give {{E, nu, rho}})")
    if isinstance(value, dict):
        _keys(value, path, {"name", "E", "nu", "rho"}, {"E", "nu", "rho"})
        for key in ("E", "nu", "rho"):
            v = value[key]
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise _fail(f"{path}.{key}", f"must be a finite number, got {v!r}")
        try:
            return Material(str(value.get("name", default_name)), value["E"], value["nu"], value["rho"])
        except InputError as exc:
            raise _fail(path, str(exc).split(": ", 1)[-1]) from None
    raise _fail(path, f"must be a material name or an object with E, nu, rho, got {value!r}")


def _materials(d: dict) -> dict[str, Material]:
    """The file's ``materials``: a new material {E, nu, rho} (named by its key) or an alias of a library one."""
    named: dict[str, Material] = {}
    for key, spec in _obj(d.get("materials", {}), "materials").items():
        mat = _material(spec, f"materials.{key}", {}, default_name=str(key))
        named[str(key).strip().lower()] = mat if isinstance(mat, Material) else MATERIALS[mat]
    return named


def _segments(d: dict, named: dict[str, Material]) -> list[Segment]:
    segments = []
    for i, s in enumerate(_list(d["segments"], "segments")):
        p = f"segments[{i}]"
        s = _obj(s, p)
        _keys(s, p, {"length", "outer_diameter", "inner_diameter", "material", "label"}, {"length", "outer_diameter"})
        mat = _material(s.get("material", "steel"), f"{p}.material", named)
        segments.append(
            _build(Segment, p, length=s["length"], outer_diameter=s["outer_diameter"],
                   inner_diameter=s.get("inner_diameter", 0.0), material=mat)
        )
    if not segments:
        raise _fail("segments", "needs at least one segment")
    return segments


def _points(d: dict) -> list[NamedPoint]:
    points = []
    for i, pt in enumerate(_list(d.get("points", []), "points")):
        p = f"points[{i}]"
        pt = _obj(pt, p)
        _keys(pt, p, {"name", "position", "node"}, {"name", "position", "node"})
        points.append(_build(NamedPoint, p, name=pt["name"], position=pt["position"], node=pt["node"]))
    return points


def _clamp(c: dict, p: str, named: dict[str, Material]) -> Clamp:
    _keys(c, p, {"position", "directions"}, {"position"})
    dirs = c.get("directions")
    if dirs is not None:
        dirs = tuple(_list(dirs, f"{p}.directions"))
    return _build(Clamp, p, position=c["position"], directions=dirs)


def _support(s: dict, p: str, named: dict[str, Material]) -> Support:
    _keys(s, p, {"position", "stiffness", "damping"}, {"position"})
    return _build(Support, p, position=s["position"], stiffness=s.get("stiffness", {}), damping=s.get("damping", {}))


def _point_mass(m: dict, p: str, named: dict[str, Material]) -> PointMass:
    _keys(m, p, {"position", "mass", "rotary_inertia", "polar_inertia", "label"}, {"position", "mass"})
    return _build(PointMass, p, position=m["position"], mass=m["mass"],
                  rotary_inertia=m.get("rotary_inertia", 0.0), polar_inertia=m.get("polar_inertia", 0.0))


def _joint(j: dict, p: str, named: dict[str, Material]) -> Joint:
    _keys(j, p, {"position", "stiffness", "damping", "loss_factor", "label"}, {"position", "stiffness"})
    return _build(Joint, p, position=j["position"], stiffness=j["stiffness"], damping=j.get("damping", {}),
                  loss_factor=j.get("loss_factor", 0.0), label=str(j.get("label", "")))


def _insertion(s: dict, p: str, named: dict[str, Material]) -> Insertion:
    _keys(s, p, {"start", "end", "outer_diameter", "inner_diameter", "material", "joined_at", "contact", "label"},
          {"start", "end", "outer_diameter"})
    contact = s.get("contact", "rigid")
    if isinstance(contact, dict):
        _keys(contact, f"{p}.contact", {"stiffness_per_length", "loss_factor"}, {"stiffness_per_length"})
        contact = _build(Contact, f"{p}.contact", stiffness_per_length=contact["stiffness_per_length"],
                         loss_factor=contact.get("loss_factor", 0.0))
    return _build(Insertion, p, start=s["start"], end=s["end"], outer_diameter=s["outer_diameter"],
                  inner_diameter=s.get("inner_diameter", 0.0),
                  material=_material(s.get("material", "steel"), f"{p}.material", named),
                  joined_at=s.get("joined_at", "end"), contact=contact, label=str(s.get("label", "")))


def _damping(dm: dict, p: str, named: dict[str, Material]):
    kind = dm.get("type")
    if not isinstance(kind, str) or kind not in _DAMPING:  # a list or object is not a name (and not hashable)
        raise _fail(f"{p}.type", f"must be one of {', '.join(_DAMPING)}, got {kind!r}")
    cls, fields = _DAMPING[kind]
    _keys(dm, p, fields | {"type"}, fields - {"alpha", "beta"})
    kwargs = {k: dm[k] for k in fields if k in dm}
    if "zeta" in kwargs and isinstance(kwargs["zeta"], list):
        kwargs["zeta"] = tuple(kwargs["zeta"])
    return _build(cls, p, **kwargs)


#: The ingredient lists of a model file, in the order they are read, and the reader of one entry.
_INGREDIENTS = (("clamps", _clamp), ("supports", _support), ("point_masses", _point_mass), ("joints", _joint),
                ("insertions", _insertion), ("damping", _damping))


def _ingredients(d: dict, named: dict[str, Material]) -> tuple[list, list[str]]:
    """Every ingredient of the file and the field path of each (``clamps[0]``, ``damping[1]`` ...)."""
    ingredients: list = []
    paths: list[str] = []
    for key, read in _INGREDIENTS:
        entries = d.get(key, [])
        if key == "damping" and isinstance(entries, dict):  # one damping model may stand alone
            entries = [entries]
        for i, entry in enumerate(_list(entries, key)):
            p = f"{key}[{i}]"
            ingredients.append(read(_obj(entry, p), p, named))
            paths.append(p)
    return ingredients, paths


def model_from_dict(data: Any) -> BeamModel:
    """Build a :class:`BeamModel` from a parsed model description (see module docstring).

    Parameters
    ----------
    data : Any
        The parsed JSON of a model file (format ``jointdb-beam-model/1``); lengths in m,
        stiffnesses in N/m and N·m/rad, masses in kg.

    Returns
    -------
    BeamModel

    Raises
    ------
    InputError
        Naming the exact field that is wrong, e.g. ``segments[1].outer_diameter: must be > 0, got 0``,
        or a resource limit exceeded (segments, elements, magnitudes; see :mod:`jointdb._limits`).
    """
    d = _obj(data, "model")
    check_model_limits(d)  # sizes, magnitudes and element count before anything is built
    _keys(d, "", _TOP, {"segments"})
    fmt = d.get("format", FORMAT)
    if fmt != FORMAT:
        raise _fail("format", f"unsupported format {fmt!r} (this jointdb reads {FORMAT!r})")
    named = _materials(d)
    segments = _segments(d, named)
    points = _points(d)
    ingredients, paths = _ingredients(d, named)
    try:
        return BeamModel(
            segments=tuple(segments),
            points=tuple(points),
            ingredients=tuple(ingredients),
            theory=d.get("theory", "timoshenko"),
            kind=d.get("kind", "planar"),
            max_element_length=d.get("max_element_length", 0.005),
            name=str(d.get("name", "")),
        )
    except FieldError as exc:
        field = exc.field
        if field.startswith("ingredients["):
            idx = int(field[len("ingredients["): field.index("]")])
            field = paths[idx] + field[field.index("]") + 1:]
        raise _fail(field, exc.reason) from None


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
        The :class:`BeamModel`.

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
