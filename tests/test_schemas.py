"""The published JSON Schemas (docs/schemas/) are generated from the pydantic models in
jointdb.schemas, every shipped example file conforms, and a bad field is named."""

from __future__ import annotations

import copy
import json
import subprocess
import sys
from pathlib import Path

import h5py
import pytest

from jointdb.errors import InputError
from jointdb.schemas import SCHEMA_FILES, schema_files, validate

REPO = Path(__file__).resolve().parents[1]
DOCS = REPO / "docs" / "schemas"
DATA = Path(__import__("jointdb").__file__).resolve().parent / "data"


def _examples() -> list[tuple[str, Path]]:
    out = [("model", p) for p in sorted((DATA).rglob("models/*.json"))]
    out += [("stack", DATA / "catalogue" / "demo-stack.json")]
    out += [("campaign", p) for p in sorted((DATA / "catalogue" / "campaigns").glob("*/campaign.json"))]
    fx = REPO / "fixtures"
    if fx.is_dir():
        out += [("model", p) for p in sorted((fx / "models").glob("*.json"))]
        out += [("model", fx / "stacks" / "parts" / "spindle-two-bearings.json")]
        out += [("model", p) for p in sorted((fx / "campaigns").glob("*/tool*.json"))]
        out += [("stack", p) for p in sorted((fx / "stacks").glob("*.json"))]
        out += [("campaign", p) for p in sorted((fx / "campaigns").glob("*/campaign.json"))]
        out += [("optimize", p) for p in sorted((fx / "optimize").glob("*.json"))]
    return out


@pytest.mark.skipif(not DOCS.is_dir(), reason="docs/schemas not next to the tests (installed copy)")
def test_committed_schemas_equal_the_generated_ones():
    generated = schema_files()
    assert set(generated) == set(SCHEMA_FILES.values())
    on_disk = {p.name for p in DOCS.glob("*.schema.json")}
    assert on_disk == set(generated), "regenerate: python -m jointdb.schemas docs/schemas"
    for name, text in generated.items():
        assert (DOCS / name).read_text(encoding="utf-8") == text, (
            f"docs/schemas/{name} is stale; regenerate: python -m jointdb.schemas docs/schemas")


def test_generator_script_writes_the_same_files(tmp_path):
    r = subprocess.run([sys.executable, "-m", "jointdb.schemas", str(tmp_path)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert {p.name: p.read_text(encoding="utf-8") for p in tmp_path.iterdir()} == schema_files()


@pytest.mark.parametrize("kind, path", _examples(), ids=lambda x: x if isinstance(x, str) else x.name)
def test_every_shipped_example_conforms(kind, path):
    validate(kind, json.loads(path.read_text(encoding="utf-8")), str(path))


def _example(kind):
    if kind == "campaign":
        path = REPO / "fixtures" / "campaigns" / "th-steel-30nm" / "campaign.json"
        if not path.is_file():
            pytest.skip("fixtures/ not next to the tests")
        return json.loads(path.read_text(encoding="utf-8"))
    return json.loads(next(p for k, p in _examples() if k == kind).read_text(encoding="utf-8"))


def _set(doc, path, value):
    *head, last = path
    for key in head:
        doc = doc[key]
    doc[last] = value


# (kind, path into the document, bad value, field the message must name) — each also refused by the reader
BAD = [
    ("model", ("segments", 0, "outer_diameter"), -0.012, "segments[0].outer_diameter"),
    ("model", ("segments", 0, "lenght"), 0.01, "segments[0].lenght: unknown field"),
    ("model", ("theory",), "bernoulli", "theory"),
    ("model", ("max_element_length",), "5 mm", "max_element_length"),
    ("stack", ("tool", "segments", 0, "length"), float("nan"), "tool.segments[0].length: must be a finite number"),
    ("stack", ("interfaces", "tool-holder"), "th", "interfaces.tool-holder: fits none of the allowed forms"),
    ("stack", ("format",), "jointdb-stack/9", "format"),
    ("campaign", ("joint_model",), "planer", "joint_model"),
    ("campaign", ("interface", "a_dofs"), ["3q"], "interface.a_dofs[0]: is not in the expected form"),
    ("campaign", ("conditions", "torque_nm"), -30, "conditions.torque_nm"),
]


@pytest.mark.parametrize("kind, path, value, needle", BAD, ids=[f"{b[0]}:{b[3].split(':')[0]}" for b in BAD])
def test_a_bad_field_is_named_in_one_line_and_the_reader_refuses_it_too(kind, path, value, needle, tmp_path):
    doc = copy.deepcopy(_example(kind))
    _set(doc, path, value)
    with pytest.raises(InputError) as exc:
        validate(kind, doc, "f.json")
    text = str(exc.value)
    assert text.startswith("f.json: ") and needle in text and "\n" not in text
    # the schema is not looser than the reader on these fields
    from jointdb.fe import model_from_dict
    from jointdb.stack import stack_from_dict

    if kind == "campaign":
        from jointdb.campaign import load_campaign

        src = REPO / "fixtures" / "campaigns" / "th-steel-30nm"  # self-contained: every file beside it
        if not src.is_dir():
            pytest.skip("fixtures/ not next to the tests")
        for f in src.iterdir():
            (tmp_path / f.name).write_bytes(f.read_bytes())
        (tmp_path / "campaign.json").write_text(json.dumps(doc))
        with pytest.raises(InputError) as by_reader:
            load_campaign(tmp_path / "campaign.json")
    else:
        with pytest.raises(InputError) as by_reader:
            (model_from_dict if kind == "model" else stack_from_dict)(doc)
    field = needle.split(":")[0].split("[")[0]
    assert field in str(by_reader.value), (str(by_reader.value), needle)


def test_bundle_metadata_conforms(tmp_path):
    from jointdb.store import Repository
    from jointdb.store._bundle import export_bundle

    import numpy as np
    from jointdb.frf import FRF

    f = np.linspace(10.0, 2000.0, 32)
    h = np.zeros((32, 2, 2), complex)
    h[:, 0, 0] = 1 / (2e6 + 2j * np.pi * f * 100)
    h[:, 1, 1] = 1 / (8e4 + 2j * np.pi * f * 80)
    frf = FRF(f, h, ("3x", "3ry"), ("3x", "3ry"))
    with Repository(f"sqlite:///{tmp_path / 'j.sqlite'}") as repo:
        repo.catalogue("T1", "tool-holder", frf, {"materials": ["steel"], "torque_nm": 30}, "spring-damper-planar",
                       {"method": "irc-planar", "parameters": {}, "input_files": {}}, {"residual": 0.01})
        repo.catalogue("T1", "tool-holder", frf, {"materials": ["steel"], "torque_nm": 40}, "spring-damper-planar", force=True)
        repo.label("T1", 2, "released")
        repo.deprecate("T1", 1, reason="loose nut")
        export_bundle(repo, ["T1"], tmp_path / "b.h5")
    n = 0
    with h5py.File(tmp_path / "b.h5", "r") as b:
        for jg in b["joints"].values():
            validate("bundle-states", {"labels": json.loads(jg.attrs["labels"]),
                                       "states": json.loads(jg.attrs["states"])}, "b.h5")
            for vg in jg.values():
                validate("bundle-record", json.loads(vg.attrs["record"]), "b.h5")
                n += 1
    assert n == 2


@pytest.mark.parametrize("change, needle", [
    (lambda d: d["options"].update(smoothing="21"), "options.smoothing: must be an integer"),
    (lambda d: d["planar"].update(b_tip="1"), "planar.b_tip: must be an integer"),
    (lambda d: d["substructures"]["holder"].update(model="tool.json"), 'substructures.holder: give exactly one of'),
    (lambda d: d["interface"].update(side="left"), "interface.side: unknown field"),
])
def test_the_campaign_reader_checks_structure_by_the_schema(change, needle, tmp_path):
    from jointdb.campaign import load_campaign

    src = REPO / "fixtures" / "campaigns" / "th-steel-30nm"
    if not src.is_dir():
        pytest.skip("fixtures/ not next to the tests")
    for f in src.iterdir():
        (tmp_path / f.name).write_bytes(f.read_bytes())
    doc = json.loads((src / "campaign.json").read_text())
    change(doc)
    (tmp_path / "campaign.json").write_text(json.dumps(doc))
    with pytest.raises(InputError) as exc:
        load_campaign(tmp_path / "campaign.json")
    assert str(exc.value).startswith("campaign campaign.json: ") and needle in str(exc.value)
