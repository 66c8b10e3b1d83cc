"""One schema per file kind, as pydantic models, and their published JSON Schemas.

=================  ==============================  ==========================================
kind               model                           file
=================  ==============================  ==========================================
``model``          :class:`BeamModelFile`          beam model JSON (``jointdb-beam-model/1``)
``stack``          :class:`StackFile`              stack JSON (``jointdb-stack/1``)
``campaign``       :class:`CampaignFile`           campaign JSON (``jointdb-campaign/1``)
``bundle-record``  :class:`VersionRecord`          a version record inside a joint bundle
``bundle-states``  :class:`JointStates`            a bundled joint's labels and states
=================  ==============================  ==========================================

The schemas describe structure, types, units and single-field ranges; the
readers add what a schema cannot say (cross references such as an interface
naming a substructure, files that must exist, element counts after meshing,
tool lengths against holder bores). :func:`validate` checks a parsed document
and raises one :class:`~jointdb.errors.InputError` line that names the file
and the field. The JSON Schemas under ``docs/schemas/`` are generated from
these models by ``python -m jointdb.schemas DIR`` and let an editor complete
and check the files (``"$schema"`` is not needed: map the schema to the file
pattern in the editor).

Functions
---------
   validate      -- check a parsed document against the schema of its kind (one field-named error)
   json_schema   -- the JSON Schema of a file kind
   schema_files  -- file name -> text of every published schema
   SCHEMAS       -- kind -> the pydantic model (``"module:Class"``)
   SCHEMA_FILES  -- kind -> published file name under ``docs/schemas/``

Importing this module imports pydantic; the file readers import it only when
they validate.
"""

from __future__ import annotations

import json
from typing import Any

from jointdb.errors import InputError

__all__ = ["SCHEMAS", "validate", "json_schema", "schema_files", "SCHEMA_FILES"]

#: kind -> "module:Class"
SCHEMAS: dict[str, str] = {
    "model": "jointdb.schemas.model:BeamModelFile",
    "stack": "jointdb.schemas.stack:StackFile",
    "campaign": "jointdb.schemas.campaign:CampaignFile",
    "bundle-record": "jointdb.schemas.bundle:VersionRecord",
    "bundle-states": "jointdb.schemas.bundle:JointStates",
}
#: kind -> published file name under docs/schemas/
SCHEMA_FILES: dict[str, str] = {
    "model": "beam-model.schema.json",
    "stack": "stack.schema.json",
    "campaign": "campaign.schema.json",
    "bundle-record": "bundle-record.schema.json",
    "bundle-states": "bundle-states.schema.json",
}
_IDS = {
    "model": "jointdb-beam-model/1",
    "stack": "jointdb-stack/1",
    "campaign": "jointdb-campaign/1",
    "bundle-record": "jointdb-bundle/2 version record",
    "bundle-states": "jointdb-bundle/2 labels and states",
}


def _model(kind: str):
    import importlib

    if kind not in SCHEMAS:
        raise InputError(f"unknown file kind {kind!r}; known: {', '.join(SCHEMAS)}")
    module, cls = SCHEMAS[kind].split(":")
    return getattr(importlib.import_module(module), cls)


_BRANCH_WORDS = {"str", "int", "float", "bool", "dict", "list", "none", "constrained-str", "constrained-int",
                 "constrained-float", "literal"}


def _is_branch(part: Any) -> bool:
    """pydantic's names for union branches and type wrappers, which are not fields of the document."""
    text = str(part)
    return (text in _BRANCH_WORDS or "[" in text or text[:1].isupper()
            or text.startswith(("function-", "tagged-union", "constrained-", "json-or-python")))


def _loc(loc: tuple[Any, ...]) -> str:
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        elif not _is_branch(part):
            out += ("." if out else "") + str(part)
    return out or "top level"


_TEXT = {
    "extra_forbidden": "unknown field",
    "missing": "is required",
    "string_pattern_mismatch": "is not in the expected form",
    "finite_number": "must be a finite number",
    "float_type": "must be a number",
    "float_parsing": "must be a number",
    "int_type": "must be an integer",
    "int_parsing": "must be an integer",
    "int_from_float": "must be an integer",
    "bool_type": "must be true or false",
    "string_type": "must be a string",
    "dict_type": "must be an object",
    "model_type": "must be an object",
    "model_attributes_type": "must be an object",
    "list_type": "must be a list",
}
_BOUNDS = {"greater_than": ">", "greater_than_equal": ">=", "less_than": "<", "less_than_equal": "<="}


def _message(err: dict[str, Any]) -> str:
    kind = err.get("type", "")
    if kind in ("extra_forbidden", "missing"):
        return _TEXT[kind]
    if kind == "value_error":  # a rule of the model itself, already in words
        return str(err.get("msg", "invalid")).removeprefix("Value error, ")
    value = err.get("input")
    shown = json.dumps(value)[:60] if isinstance(value, (int, float, str, bool)) or value is None else type(value).__name__
    ctx = err.get("ctx") or {}
    if kind in _BOUNDS:
        bound = next(iter(ctx.values()), "?")
        text = f"must be {_BOUNDS[kind]} {bound:g}" if isinstance(bound, (int, float)) else f"must be {_BOUNDS[kind]} {bound}"
    elif kind == "literal_error":
        text = f"must be one of {ctx.get('expected', '?')}"
    elif kind == "too_short":
        text = f"needs at least {ctx.get('min_length', '?')} item(s)"
    elif kind == "too_long":
        text = f"allows at most {ctx.get('max_length', '?')} item(s)"
    else:
        text = _TEXT.get(kind) or err.get("msg", "invalid").splitlines()[0]
    return f"{text}, got {shown}"


def validate(kind: str, data: Any, where: str = "") -> Any:
    """Validate a parsed JSON document against the schema of ``kind``.

    Parameters
    ----------
    kind
        A key of :data:`SCHEMAS` (``"model"``, ``"stack"``, ``"campaign"``, ...).
    data
        The parsed JSON document.
    where
        The file name, put in front of the message.

    Returns
    -------
    pydantic.BaseModel
        The validated document.

    Raises
    ------
    InputError
        One line ``"<where>: <field>: <reason>"`` for the most specific problem,
        e.g. ``stack.json: tool.segments[0].length: Input should be greater than
        or equal to 1e-06, got -0.01``. Where a field may take several forms
        (a joint choice, a material) and the value fits none, the line says so.
    """
    from pydantic import ValidationError

    model = _model(kind)
    try:
        return model.model_validate(data)
    except ValidationError as exc:
        errors = exc.errors(include_url=False)
        locs = [_loc(tuple(e.get("loc", ()))) for e in errors]
        # the most specific problem: the deepest field reached (a union branch that got furthest)
        depth = [loc.count(".") + loc.count("[") if loc != "top level" else -1 for loc in locs]
        specific = [e.get("type") not in ("missing", "extra_forbidden") for e in errors]
        best = max(range(len(errors)), key=lambda k: (depth[k], specific[k], -k))
        # several union branches failing on the value itself: none of the forms fits
        same = [k for k in range(len(errors)) if locs[k] == locs[best] and specific[k]]
        prefix = f"{where}: " if where else ""
        if len(same) > 1:
            value = errors[best].get("input")
            shown = json.dumps(value)[:60] if isinstance(value, (int, float, str, bool)) or value is None \
                else type(value).__name__
            raise InputError(f"{prefix}{locs[best]}: fits none of the allowed forms (see docs/schemas/"
                             f"{SCHEMA_FILES[kind]}), got {shown}") from None
        raise InputError(f"{prefix}{locs[best]}: {_message(errors[best])}") from None


def json_schema(kind: str) -> dict[str, Any]:
    """The JSON Schema (draft 2020-12) of a file kind, as published under docs/schemas/.

    Parameters
    ----------
    kind
        A key of :data:`SCHEMAS`.

    Returns
    -------
    dict
    """
    schema = _model(kind).model_json_schema(by_alias=True)
    return {"$schema": "https://json-schema.org/draft/2020-12/schema", "$id": _IDS[kind], **schema}


def schema_files() -> dict[str, str]:
    """Every published schema as text (sorted keys, two-space indent, final newline).

    Returns
    -------
    dict
        File name under ``docs/schemas/`` → JSON text.
    """
    return {SCHEMA_FILES[k]: json.dumps(json_schema(k), indent=2, sort_keys=True, ensure_ascii=False) + "\n"
            for k in SCHEMAS}
