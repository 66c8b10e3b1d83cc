"""One schema per file kind, as pydantic models, and their published JSON Schemas.

=================  ==============================  ==========================================
kind               model                           file
=================  ==============================  ==========================================
``model``          :class:`BeamModelFile`          beam model JSON (``jointdb-beam-model/1``)
``stack``          :class:`StackFile`              stack JSON (``jointdb-stack/1``)
``campaign``       :class:`CampaignFile`           campaign JSON (``jointdb-campaign/1``)
``bundle-record``  :class:`VersionRecord`          a version record inside a joint bundle
``bundle-states``  :class:`JointStates`            a bundled joint's labels and states
``optimize``       :class:`OptimizeSpecFile`       optimize spec JSON (``jointdb-optimize/1``)
=================  ==============================  ==========================================

The schemas are the readers' first step: :func:`jointdb.fe.model_from_dict`,
:func:`jointdb.stack.stack_from_dict`, :func:`jointdb.campaign.load_campaign` and the
bundle reader parse a document with :func:`parse` and then check only what a schema
cannot say (cross references such as an interface naming a substructure, files that
must exist, element counts after meshing, tool lengths against holder bores). The
schemas describe structure, types, units and single-field ranges. :func:`validate`
checks a parsed document and raises one :class:`~jointdb.errors.InputError` line that
names the file and the field; a reader passes its own ``wording`` to keep the messages
its users know. The JSON Schemas under ``docs/schemas/`` are generated from these
models by ``python -m jointdb.schemas DIR`` (a test checks the published files equal
the generated ones) and let an editor complete and check the files (``"$schema"`` is
not needed: map the schema to the file pattern in the editor). The input limits
(:mod:`jointdb.schemas._limits`) and the bounded JSON file reader
(:mod:`jointdb.schemas._jsonfile`) live here too.

Functions
---------
   parse           -- parse a document of a kind with its schema (a reader's own wording kept)
   validate        -- check a parsed document against the schema of its kind (one field-named error)
   describe_error  -- one line ``"<field>: <reason>"`` for a failed validation
   Wording         -- type of a reader's own wording of a schema error
   json_schema     -- the JSON Schema of a file kind
   schema_files    -- file name -> text of every published schema
   SCHEMAS         -- kind -> the pydantic model (``"module:Class"``)
   SCHEMA_FILES    -- kind -> published file name under ``docs/schemas/``

Importing this package does not import pydantic: a kind's model is imported when a
document of that kind is parsed.
"""

from __future__ import annotations

import json
from typing import Any, Callable

from jointdb.schemas._limits import LENGTH_RANGE
from jointdb.errors import InputError

__all__ = ["SCHEMAS", "parse", "validate", "describe_error", "Wording", "json_schema", "schema_files", "SCHEMA_FILES"]

#: kind -> "module:Class"
SCHEMAS: dict[str, str] = {
    "model": "jointdb.schemas.model:BeamModelFile",
    "stack": "jointdb.schemas.stack:StackFile",
    "campaign": "jointdb.schemas.campaign:CampaignFile",
    "bundle-record": "jointdb.schemas.bundle:VersionRecord",
    "bundle-states": "jointdb.schemas.bundle:JointStates",
    "optimize": "jointdb.schemas.optimize:OptimizeSpecFile",
}
#: kind -> published file name under docs/schemas/
SCHEMA_FILES: dict[str, str] = {
    "model": "beam-model.schema.json",
    "stack": "stack.schema.json",
    "campaign": "campaign.schema.json",
    "bundle-record": "bundle-record.schema.json",
    "bundle-states": "bundle-states.schema.json",
    "optimize": "optimize.schema.json",
}
_IDS = {
    "model": "jointdb-beam-model/1",
    "stack": "jointdb-stack/1",
    "campaign": "jointdb-campaign/1",
    "bundle-record": "jointdb-bundle/2 version record",
    "bundle-states": "jointdb-bundle/2 labels and states",
    "optimize": "jointdb-optimize/1",
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
    tag_next = False  # a tagged union names the tag of the branch after its marker: not a field
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        elif tag_next:
            tag_next = False
        elif "tagged-union[" in str(part):
            tag_next = True
        elif not _is_branch(part):
            out += ("." if out else "") + str(part)
    return out or "top level"


def _field(err: dict[str, Any]) -> str:
    """The field an error is about; a tag no branch of a tagged union has is the tag field's fault."""
    loc = _loc(tuple(err.get("loc", ())))
    if err.get("type") == "union_tag_invalid":
        tag = str((err.get("ctx") or {}).get("discriminator", "")).strip("'")
        loc = f"{loc}.{tag}" if loc != "top level" else tag
    return loc


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


def _shown(value: Any) -> str:
    return json.dumps(value)[:60] if isinstance(value, (int, float, str, bool)) or value is None \
        else type(value).__name__


def _message(err: dict[str, Any]) -> str:
    kind = err.get("type", "")
    if kind in ("extra_forbidden", "missing"):
        return _TEXT[kind]
    if kind == "value_error":  # a rule of the model itself, already in words
        return str(err.get("msg", "invalid")).removeprefix("Value error, ")
    shown = _shown(err.get("input"))
    ctx = err.get("ctx") or {}
    if kind == "greater_than_equal" and ctx.get("ge") == LENGTH_RANGE[0] and isinstance(err.get("input"), (int, float)) \
            and err["input"] <= 0:  # a length or diameter; the range above 0 is jointdb.schemas._limits' to report
        return f"must be > 0, got {shown}"
    if kind in _BOUNDS:
        bound = next(iter(ctx.values()), "?")
        text = f"must be {_BOUNDS[kind]} {bound:g}" if isinstance(bound, (int, float)) else f"must be {_BOUNDS[kind]} {bound}"
    elif kind == "literal_error":
        text = f"must be one of {ctx.get('expected', '?')}"
    elif kind == "union_tag_invalid":
        text, shown = f"must be one of {ctx.get('expected_tags', '?')}", _shown(ctx.get("tag"))
    elif kind == "too_short":
        text = f"needs at least {ctx.get('min_length', '?')} item(s)"
    elif kind == "too_long":
        text = f"allows at most {ctx.get('max_length', '?')} item(s)"
    else:
        text = _TEXT.get(kind) or err.get("msg", "invalid").splitlines()[0]
    return f"{text}, got {shown}"


#: A reader's own wording of a schema error: ``(field, error) -> "field: text"`` or None (the
#: default wording). ``error`` is pydantic's error dict; for a value that fits none of the forms
#: of a union its ``type`` is ``"union_none"``.
Wording = Callable[[str, dict[str, Any]], "str | None"]


def _explain(kind: str, errors: list[dict[str, Any]], wording: Wording | None) -> str:
    """The most specific problem of a failed validation as one line ``"<field>: <reason>"``."""
    locs = [_field(e) for e in errors]
    # the most specific problem: the deepest field reached (a union branch that got furthest)
    depth = [loc.count(".") + loc.count("[") if loc != "top level" else -1 for loc in locs]
    specific = [e.get("type") not in ("missing", "extra_forbidden") for e in errors]
    best = max(range(len(errors)), key=lambda k: (depth[k], specific[k], -k))
    # several union branches failing on the value itself: none of the forms fits
    same = [k for k in range(len(errors)) if locs[k] == locs[best] and specific[k]]
    err = dict(errors[best], type="union_none") if len(same) > 1 else errors[best]
    own = wording(locs[best], err) if wording is not None else None
    if own is not None:
        return own
    if len(same) > 1:
        return (f"{locs[best]}: fits none of the allowed forms (see docs/schemas/{SCHEMA_FILES[kind]}), "
                f"got {_shown(err.get('input'))}")
    return f"{locs[best]}: {_message(err)}"


def describe_error(exc: Any, kind: str, wording: Wording | None = None) -> str:
    """One line ``"<field>: <reason>"`` for a pydantic ``ValidationError`` of a model of ``kind``.

    Parameters
    ----------
    exc : pydantic.ValidationError
        The error of validating a document (or a part of one) of that kind.
    kind : str
        A key of :data:`SCHEMAS`; names the published schema where no form of a union fits.
    wording : callable, optional
        A reader's own wording, as for :func:`parse`.

    Returns
    -------
    str
    """
    return _explain(kind, exc.errors(include_url=False), wording)


def parse(kind: str, data: Any, where: str = "", wording: Wording | None = None) -> Any:
    """Validate a parsed JSON document against the schema of ``kind``; return the pydantic model.

    Parameters
    ----------
    kind : str
        A key of :data:`SCHEMAS` (``"model"``, ``"stack"``, ``"campaign"`` ...).
    data : Any
        The parsed JSON document.
    where : str
        Prefix of the error message (the file name), empty for none.
    wording : callable, optional
        The reader's own wording of an error, ``(field, error) -> "field: text"`` or None
        for the default; lets a reader keep the messages its users know.

    Returns
    -------
    pydantic.BaseModel
        The validated document (frozen).

    Raises
    ------
    InputError
        One line ``"<where>: <field>: <reason>"`` for the most specific problem,
        e.g. ``stack.json: tool.segments[0].length: must be >= 1e-06, got -0.01``.
        Where a field may take several forms (a joint choice, a material) and the
        value fits none, the line says so.
    """
    from pydantic import ValidationError

    model = _model(kind)
    try:
        return model.model_validate(data)
    except ValidationError as exc:
        text = describe_error(exc, kind, wording)
        raise InputError(f"{where}: {text}" if where else text) from None


def validate(kind: str, data: Any, where: str = "") -> Any:
    """Validate a parsed JSON document against the schema of ``kind`` in the schema's own words.

    Parameters
    ----------
    kind : str
        A key of :data:`SCHEMAS`.
    data : Any
        The parsed JSON document.
    where : str
        Prefix of the error message (the file name), empty for none.

    Returns
    -------
    pydantic.BaseModel
        The validated document.

    Raises
    ------
    InputError
        As :func:`parse` without a reader's wording.
    """
    return parse(kind, data, where)


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
        File name under ``docs/schemas/`` -> JSON text.
    """
    return {SCHEMA_FILES[k]: json.dumps(json_schema(k), indent=2, sort_keys=True, ensure_ascii=False) + "\n"
            for k in SCHEMAS}
