"""Stack files: round trip, and bad files give a message naming the field."""

from __future__ import annotations

import copy
import json
from pathlib import Path

import pytest

from jointdb.errors import InputError
from jointdb.stack import JointChoice, stack_from_dict, stack_to_dict

STACKS = Path(__file__).resolve().parents[2] / "fixtures" / "stacks"


def _doc() -> dict:
    return json.loads((STACKS / "endmill-modelled-spindle.json").read_text())


def _names_parts(path: Path) -> bool:
    doc = json.loads(path.read_text())
    return any(isinstance(doc.get(k), dict) and "part" in doc[k] for k in ("tool", "holder", "spindle"))


INLINE = [p for p in sorted(STACKS.glob("*.json")) if not _names_parts(p)]
BY_PARTS = [p for p in sorted(STACKS.glob("*.json")) if _names_parts(p)]


@pytest.mark.parametrize("path", INLINE, ids=lambda p: p.name)
def test_example_stack_files_are_valid_and_round_trip(path):
    spec = stack_from_dict(json.loads(path.read_text()))
    assert stack_from_dict(stack_to_dict(spec)) == spec


@pytest.mark.parametrize("path", BY_PARTS, ids=lambda p: p.name)
def test_example_stacks_naming_parts_follow_the_schema_and_need_the_database(path):
    """A stack naming catalogued parts is valid by the schema; the file reader alone refuses it by
    field, pointing to the use case that resolves parts (tests/store/test_store_parts.py predicts it)."""
    from jointdb.schemas import validate

    doc = json.loads(path.read_text())
    validate("stack", doc)
    with pytest.raises(InputError, match=r"\.part: a catalogued part is resolved from the database first"):
        stack_from_dict(doc)


def test_interface_forms():
    doc = _doc()
    doc["interfaces"] = {
        "tool-holder": {"query": {"joint_type": "tool-holder", "materials": ["steel", "carbide"], "torque_nm": 60}},
        "holder-spindle": "hsk-a63@released",
    }
    spec = stack_from_dict(doc)
    th, hs = spec.interfaces["tool-holder"], spec.interfaces["holder-spindle"]
    assert th.kind == "query" and th.conditions == {"materials": ("steel", "carbide"), "torque_nm": 60.0}
    assert (hs.kind, hs.name, hs.version) == ("catalogued", "hsk-a63", "released")
    assert stack_from_dict({**doc, "interfaces": {"tool-holder": "th@3"}}).interfaces["tool-holder"] == JointChoice(
        "catalogued", name="th", version=3
    )
    # an interface left out is rigid
    assert stack_from_dict({**doc, "interfaces": {}}).interfaces["holder-spindle"].kind == "rigid"
    assert spec.insertion_length == pytest.approx(0.03)
    assert stack_from_dict(stack_to_dict(spec)) == spec


def _set(doc, path, value):
    obj = doc
    keys = path.split("/")
    for k in keys[:-1]:
        obj = obj[int(k)] if isinstance(obj, list) else obj[k]
    last = keys[-1]
    if value is KeyError:
        del obj[last]
    elif isinstance(obj, list):
        obj[int(last)] = value
    else:
        obj[last] = value


BAD = [
    ("tool/segments/1/length", -0.01, r"^tool\.segments\[1\]\.length: must be > 0"),
    ("tool/segments/0/diameter", "12mm", r"^tool\.segments\[0\]\.diameter: must be a finite number"),
    ("tool/segments/0/flute", True, r"^tool\.segments\[0\]\.flute: unknown field"),
    ("tool/segments/1/fluted", True, r"^tool\.segments\[1\]\.fluted: a fluted section reaches inside the holder"),
    ("tool/fluted_ratio", 1.5, r"^tool\.fluted_ratio: must be <= 1"),
    ("tool/segments", [], r"^tool\.segments: must be a non-empty list"),
    ("holder/segments/0/inner_diameter", 0.010, r"^holder\.segments\[0\]\.inner_diameter: bore 10 mm is smaller"),
    ("holder/segments/1/inner_diameter", 0.06, r"^holder\.segments\[1\]\.inner_diameter: must be smaller than"),
    ("gauge_length", 0.09, r"^gauge_length: must not exceed the tool length"),
    ("gauge_length", KeyError, r"^gauge_length: required field is missing \(or give insertion_length\)"),
    ("insertion_length", 0.02, r"^insertion_length: 0\.02 m disagrees with tool length 0\.08 m"),
    ("spindle/node", 3, r"^spindle: give either 'file'"),
    ("spindle/model", 12, r"^spindle\.model: must be a beam model object"),
    ("interfaces/tool-holder", "th", r"^interfaces\.tool-holder: 'th' is neither 'rigid' nor a pinned joint"),
    ("interfaces/tool-holder", {"k": [1e7], "c": [1, 1]}, r"^interfaces\.tool-holder\.k: must be a list of two"),
    ("interfaces/tool-holder", {"k": [1e7, -1], "c": [1, 1]}, r"^interfaces\.tool-holder\.k\[1\]: must be > 0"),
    ("interfaces/holder-spindle", {"query": {"torque_nm": 5}},
     r"^interfaces\.holder-spindle\.query\.joint_type: required"),
    ("interfaces/holder-spindle", {"query": {"joint_type": "t", "torque": 5}},
     r"^interfaces\.holder-spindle\.query\.torque: unknown field"),
    ("interfaces/spindle-holder", "rigid", r"^interfaces\.spindle-holder: unknown field; expected one of tool-holder"),
    ("frequency/max", 5, r"^frequency\.max: must exceed frequency\.min"),
    ("format", "jointdb-stack/9", r"^format: unsupported stack format"),
    ("colour", "red", r"^colour: unknown field"),
]


@pytest.mark.parametrize("path,value,pattern", BAD, ids=[b[0] + "=" + repr(b[1])[:12] for b in BAD])
def test_bad_stack_files_name_the_field(path, value, pattern):
    doc = copy.deepcopy(_doc())
    if path == "spindle/node":
        doc["spindle"]["file"] = "s.uff"
    _set(doc, path, value)
    with pytest.raises(InputError, match=pattern):
        stack_from_dict(doc)


def test_insertion_longer_than_the_holder_is_refused():
    doc = _doc()
    doc["gauge_length"] = 0.005
    with pytest.raises(InputError, match=r"^gauge_length: leaves 0\.075 m of tool inside the holder"):
        stack_from_dict(doc)


def test_insertion_length_can_replace_the_gauge_length():
    doc = _doc()
    del doc["gauge_length"]
    doc["insertion_length"] = 0.03
    spec = stack_from_dict(doc)
    assert spec.gauge_length == pytest.approx(0.05) and spec == stack_from_dict(_doc())
