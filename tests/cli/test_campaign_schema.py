"""docs/schemas/campaign-i15.json describes the campaign files the reader accepts (fields kept in step with
jointdb.campaign._file, and every bundled or scaffolded campaign validates against it)."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from jointdb.campaign import _file

ROOT = Path(__file__).resolve().parents[2]
SCHEMA = json.loads((ROOT / "docs" / "schemas" / "campaign-i15.json").read_text())
_TYPES = {"object": dict, "array": list, "string": str, "integer": int, "number": (int, float), "boolean": bool,
          "null": type(None)}


def _errors(value, schema, where="$"):
    """The subset of JSON Schema the file uses: $ref, type, const, enum, required, properties,
    additionalProperties, items, min/maxItems, minProperties, pattern, minimum, oneOf."""
    if "$ref" in schema:
        schema = SCHEMA["$defs"][schema["$ref"].rsplit("/", 1)[1]]
    out = []
    if "type" in schema:
        types = schema["type"] if isinstance(schema["type"], list) else [schema["type"]]
        ok = any(isinstance(value, _TYPES[t]) and not (t in ("integer", "number") and isinstance(value, bool))
                 for t in types)
        if not ok:
            return [f"{where}: not {types}"]
    if "const" in schema and value != schema["const"]:
        out.append(f"{where}: != {schema['const']!r}")
    if "enum" in schema and value not in schema["enum"]:
        out.append(f"{where}: not in {schema['enum']}")
    if isinstance(value, str) and "pattern" in schema and not re.search(schema["pattern"], value):
        out.append(f"{where}: does not match {schema['pattern']}")
    if isinstance(value, (int, float)) and "minimum" in schema and value < schema["minimum"]:
        out.append(f"{where}: < {schema['minimum']}")
    if isinstance(value, dict):
        out += [f"{where}: missing {k}" for k in schema.get("required", []) if k not in value]
        if len(value) < schema.get("minProperties", 0):
            out.append(f"{where}: too few properties")
        props = schema.get("properties", {})
        for k, v in value.items():
            if k in props:
                out += _errors(v, props[k], f"{where}.{k}")
            elif schema.get("additionalProperties") is False:
                out.append(f"{where}: unknown {k}")
            elif isinstance(schema.get("additionalProperties"), dict):
                out += _errors(v, schema["additionalProperties"], f"{where}.{k}")
        if "oneOf" in schema and sum(not _errors(value, s, where) for s in schema["oneOf"]) != 1:
            out.append(f"{where}: must match exactly one of {schema['oneOf']}")
    if isinstance(value, list):
        if len(value) < schema.get("minItems", 0) or len(value) > schema.get("maxItems", len(value)):
            out.append(f"{where}: wrong length")
        for i, v in enumerate(value):
            out += _errors(v, schema.get("items", {}), f"{where}[{i}]")
    return out


def test_schema_fields_are_the_readers_fields():
    assert set(SCHEMA["properties"]) == _file._TOP_KEYS
    assert set(SCHEMA["properties"]["options"]["properties"]) == _file._OPTION_KEYS
    assert SCHEMA["properties"]["joint_model"]["enum"] == list(_file.JOINT_MODELS)
    assert SCHEMA["properties"]["format"]["const"] == _file.FORMAT


@pytest.mark.parametrize("path", sorted((ROOT / "jointdb" / "data" / "catalogue").glob("campaigns/*/campaign.json"))
                         + sorted((ROOT / "fixtures" / "campaigns").glob("*/campaign.json")), ids=lambda p: p.parent.name)
def test_every_shipped_campaign_validates(path):
    assert _errors(json.loads(path.read_text()), SCHEMA) == []


def test_the_validator_rejects_what_the_reader_rejects():
    doc = json.loads((ROOT / "fixtures" / "campaigns" / "th-steel-30nm" / "campaign.json").read_text())
    bad = {**doc, "substructures": {"tool": {"model": "t.json", "uff58": "t.uff"}}, "colour": "red"}
    errs = _errors(bad, SCHEMA)
    assert any("unknown colour" in e for e in errs) and any("exactly one" in e for e in errs)
    assert _errors({**doc, "interface": {**doc["interface"], "a_dofs": ["3q"]}}, SCHEMA)
