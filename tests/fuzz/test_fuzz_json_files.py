"""Fuzz corpus: malformed model, stack and campaign files through ``modes``/``frf``, ``predict``,
``identify`` and ``couple`` (see :mod:`fuzz_helpers` for what is asserted).

The resource-limit cases reproduce the crashes of issue 12: 100 000 segments,
``max_element_length: 1e-9``, a 100 000-deep JSON document and a segment
length of 1e308 each gave a traceback (or ran out of memory) before.
"""

from __future__ import annotations

import json

import pytest
from fuzz_helpers import INPUT, NOT_FOUND, Case, campaign_doc, check_case, edited, model_doc, stack_doc


def _set(path: str, value):
    """A change setting ``doc[a][b]...`` (path ``"a.b.0.c"``) to ``value``."""
    def change(doc):
        keys = [int(k) if k.isdigit() else k for k in path.split(".")]
        target = doc
        for k in keys[:-1]:
            target = target[k]
        target[keys[-1]] = value
    return change


def _pop(path: str):
    def change(doc):
        keys = [int(k) if k.isdigit() else k for k in path.split(".")]
        target = doc
        for k in keys[:-1]:
            target = target[k]
        del target[keys[-1]]
    return change


DEEP = "[" * 100_000 + "]" * 100_000


def _model_cases() -> list[Case]:
    c = []

    def add(cid, content, match=None, codes=(INPUT,), command=("frf", "m.json", "--out", "out.h5")):
        c.append(Case(f"model-{cid}", list(command), {"m.json": content}, codes, match))

    seg = {"length": 0.001, "outer_diameter": 0.01}
    add("100000-segments", edited(model_doc, _set("segments", [seg] * 100_000)), "limit is 1000")
    add("max-element-length-1e-9", edited(model_doc, _set("max_element_length", 1e-9)),
        "max_element_length: 1e-09 m would need")
    add("max-element-length-zero", edited(model_doc, _set("max_element_length", 0)), "max_element_length")
    add("max-element-length-negative", edited(model_doc, _set("max_element_length", -0.01)), "max_element_length")
    add("frame3d-fine-mesh", edited(model_doc, lambda d: d.update(kind="frame3d", max_element_length=1e-4)),
        "frame3d")
    add("deep-json", DEEP, "nested more than 64")
    add("deep-json-in-string-is-fine-but-bad-field", json.dumps({"segments": "[" * 1000}), "segments")
    add("length-1e308", edited(model_doc, _set("segments.0.length", 1e308)), "segments[0].length")
    add("length-1e200", edited(model_doc, _set("segments.0.length", 1e200)), "segments[0].length")
    add("length-1e-300", edited(model_doc, _set("segments.0.length", 1e-300)), "segments[0].length")
    add("length-infinity", '{"segments": [{"length": Infinity, "outer_diameter": 0.01}]}', "segments[0].length")
    add("length-nan", '{"segments": [{"length": NaN, "outer_diameter": 0.01}]}', "segments[0].length")
    add("length-1e400", '{"segments": [{"length": 1e400, "outer_diameter": 0.01}]}', "segments[0].length")
    add("length-5000-digits", '{"segments": [{"length": ' + "9" * 5000 + ', "outer_diameter": 0.01}]}', "4300 digits")
    add("length-string", edited(model_doc, _set("segments.0.length", "long")), "segments[0].length")
    add("length-bool", edited(model_doc, _set("segments.0.length", True)), "segments[0].length")
    add("diameter-1e9", edited(model_doc, _set("segments.0.outer_diameter", 1e9)), "outer_diameter")
    add("modulus-1e30", edited(model_doc, _set("segments.0.material", {"E": 1e30, "nu": 0.3, "rho": 7800})),
        "material.E")
    add("density-1e-12", edited(model_doc, _set("segments.0.material", {"E": 2e11, "nu": 0.3, "rho": 1e-12})),
        "material.rho")
    add("poisson-2", edited(model_doc, _set("segments.0.material", {"E": 2e11, "nu": 2, "rho": 7800})), "nu")
    add("point-position-1e12", edited(model_doc, _set("points.0.position", 1e12)), "points[0].position")
    add("point-node-huge", edited(model_doc, _set("points.0.node", 10**30)), "points[0].node")
    add("10000-points", edited(model_doc, _set("points", [{"name": f"p{i}", "position": 0.0, "node": i}
                                                          for i in range(10_000)])), "points")
    add("support-stiffness-1e300", edited(model_doc, _set("supports", [{"position": 0.0, "stiffness": {"x": 1e300}}])),
        "supports[0].stiffness.x")
    add("mass-1e30", edited(model_doc, _set("point_masses", [{"position": 0.0, "mass": 1e30}])), "point_masses[0].mass")
    add("top-level-list", "[1, 2, 3]", "model")
    add("top-level-null", "null", "model")
    add("not-json", "{segments: [}", "not valid JSON")
    add("binary", bytes(range(256)) * 4, "UTF-8")
    add("empty", "", "not valid JSON")
    add("kind-number", edited(model_doc, _set("kind", 3)), "kind")
    add("segments-object", edited(model_doc, _set("segments", {"length": 1})), "segments")
    add("missing", None, "nothere.json", (NOT_FOUND,), ("modes", "nothere.json"))
    c[-1].files = {}
    add("modes-deep-json", DEEP, "nested", command=("modes", "m.json"))
    return c


def _stack_cases() -> list[Case]:
    c = []

    def add(cid, content, match=None, codes=(INPUT,)):
        c.append(Case(f"stack-{cid}", ["predict", "s.json", "--out", "tip.h5"], {"s.json": content}, codes, match))

    add("tool-length-1e308", edited(stack_doc, _set("tool.segments.1.length", 1e308)), "tool.segments[1].length")
    add("tool-length-1e50", edited(stack_doc, _set("tool.segments.1.length", 1e50)), "tool.segments[1].length")
    add("tool-100000-segments", edited(stack_doc, _set("tool.segments", [{"length": 0.001, "diameter": 0.01}] * 100_000)),
        "tool.segments")
    add("holder-long", edited(stack_doc, lambda d: d["holder"]["segments"].extend(
        [{"length": 50.0, "outer_diameter": 0.05}] * 2)), "holder.segments")
    add("holder-diameter-nan", '{"format": "jointdb-stack/1", "tool": {"segments": [{"length": 0.1, "diameter": 0.01}]},'
        ' "holder": {"segments": [{"length": 0.05, "outer_diameter": NaN}]}, "spindle": {"file": "s.uff", "node": 1},'
        ' "interfaces": {}, "gauge_length": 0.05}', "outer_diameter")
    add("gauge-negative", edited(stack_doc, _set("gauge_length", -0.05)), "gauge_length")
    add("frequency-step-tiny", edited(stack_doc, _set("frequency", {"min": 1, "max": 5000, "step": 1e-9})),
        "frequency.step")
    add("spindle-model-deep", edited(stack_doc, _set("spindle.model", {"segments": [{"length": 1e308,
                                                                                        "outer_diameter": 0.07}]})),
        "length")
    add("spindle-model-huge-mesh", edited(stack_doc, _set("spindle.model.max_element_length", 1e-9)),
        "max_element_length")
    add("spindle-file-missing", edited(stack_doc, _set("spindle", {"file": "nothere.uff", "node": 7})), "nothere.uff",
        (NOT_FOUND,))
    add("spindle-file-garbage", edited(stack_doc, _set("spindle", {"file": "sp.uff", "node": 7})), "sp.uff")
    c[-1].files["sp.uff"] = b"    -1\n    58\ngarbage\n    -1\n"
    add("joint-k-negative", edited(stack_doc, _set("interfaces", {"tool-holder": {"k": [-1, 1], "c": [0, 0]}})),
        "interfaces.tool-holder.k")
    add("joint-query-negative-torque", edited(stack_doc, _set("interfaces", {"tool-holder": {"query": {
        "joint_type": "tool-holder", "torque_nm": -40}}})), "torque_nm")
    add("joint-bad-reference", edited(stack_doc, _set("interfaces", {"tool-holder": "th@@1"})), "tool-holder")
    add("deep-json", DEEP, "nested")
    add("not-an-object", "42", "stack")
    add("unknown-field", edited(stack_doc, _set("colour", "red")), "colour")
    return c


def _campaign_cases() -> list[Case]:
    c = []

    def add(cid, change, match=None, codes=(INPUT,), command="identify", extra=None):
        files = {"__campaign__": True, "campaign.json": edited(campaign_doc, change)}
        files.update(extra or {})
        args = (["identify", "campaign.json", "--out", "joint.h5", "--report", "r.json"] if command == "identify"
                else ["couple", "campaign.json", "--out", "a.h5"])
        c.append(Case(f"campaign-{cid}", args, files, codes, match))

    add("negative-torque", _set("conditions.torque_nm", -30), "conditions.torque_nm")
    add("negative-preload", _set("conditions", {"preload_n": -1e3}), "conditions.preload_n")
    add("torque-string", _set("conditions.torque_nm", "tight"), "conditions.torque_nm")
    add("conditions-list", _set("conditions", [1, 2]), "conditions")
    add("materials-number", _set("conditions.materials", 7), "conditions.materials")
    add("band-nan", _set("band", [float("nan"), 100]), "band")
    add("format-missing", _pop("format"), "format")
    add("joint-model-unknown", _set("joint_model", "glue"), "joint_model")
    add("substructure-missing-file", _set("substructures.tool", {"model": "nothere.json"}), "nothere.json")
    add("measurement-missing-file", _set("measurements", ["nothere.uff"]), "nothere.uff")
    add("interface-dof-bad", _set("interface.a_dofs", ["3q", "3ry"]), "interface.a_dofs")
    add("matrix-measured-numbers", lambda d: d.update(joint_model="matrix", matrix={"measured": [[1, 2]]}),
        "matrix.measured")
    add("options-unknown", _set("options", {"colour": 1}), "options")
    add("tool-model-huge-mesh", lambda d: None, "max_element_length",
        extra={"tool.json": edited(lambda: json.loads(
            (__import__("fuzz_helpers").CAMPAIGN_FIXTURE / "tool.json").read_text()),
            _set("max_element_length", 1e-9))})
    add("tool-model-deep", lambda d: None, "nested", extra={"tool.json": DEEP})
    add("holder-uff-truncated", lambda d: None, "holder.uff",
        extra={"holder.uff": (__import__("fuzz_helpers").CAMPAIGN_FIXTURE / "holder.uff").read_bytes()[:3000]})
    add("couple-frequency-tiny-step", _set("couple", {"frequency": {"min": 1, "max": 5000, "step": 1e-9}}),
        "couple.frequency", command="couple")
    add("couple-frequency-text", _set("couple", {"frequency": {"min": "a", "max": 5000, "step": 1}}),
        "couple.frequency", command="couple")
    c.append(Case("campaign-deep-json", ["identify", "campaign.json", "--out", "joint.h5"],
                  {"campaign.json": DEEP}, (INPUT,), "nested"))
    c.append(Case("campaign-missing", ["couple", "nothere.json"], {}, (NOT_FOUND,), "nothere.json"))
    return c


CASES = _model_cases() + _stack_cases() + _campaign_cases()


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_malformed_description_file_gives_one_line_and_writes_nothing(case, tmp_path, monkeypatch, capsys):
    check_case(case, tmp_path, monkeypatch, capsys)
