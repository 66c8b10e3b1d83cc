"""A catalogued holder–spindle joint is resolved by a stack exactly like a tool–holder one: pinned version,
label, or the nearest to the stack's conditions (taper, drawbar force), and it changes the predicted tip."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from jointdb import usecases
from jointdb.stack import predict_tool_tip, stack_from_dict
from jointdb.store import Repository

ROOT = Path(__file__).resolve().parents[2]
CAT = ROOT / "jointdb" / "data" / "catalogue"


@pytest.fixture(scope="module")
def repo(tmp_path_factory):
    url = f"sqlite:///{tmp_path_factory.mktemp('hs') / 'j.sqlite'}"
    with Repository(url) as r:
        for name in ("hs-hsk-a63-12kn", "hs-hsk-a63-24kn", "hs-bt40-12kn"):
            usecases.catalogue_campaign(r, CAT / "campaigns" / name / "campaign.json")
        r.label("hs-hsk-a63-24kn", 1, "released")
        yield r


def _spec(holder_spindle):
    doc = json.loads((CAT / "demo-stack.json").read_text())
    doc["interfaces"] = {"tool-holder": "rigid", "holder-spindle": holder_spindle}
    return stack_from_dict(doc)


def test_pinned_version_and_label(repo):
    pinned = usecases.resolve_joints(_spec("hs-hsk-a63-12kn@1"), repo)["holder-spindle"]
    assert (pinned.kind, pinned.name, pinned.version, pinned.distance) == ("catalogued", "hs-hsk-a63-12kn", 1, 0.0)
    labelled = usecases.resolve_joints(_spec("hs-hsk-a63-24kn@released"), repo)["holder-spindle"]
    assert (labelled.name, labelled.version) == ("hs-hsk-a63-24kn", 1)


def test_query_by_taper_and_drawbar_force_picks_the_same_taper_and_changes_the_tip(repo):
    q = {"query": {"joint_type": "holder-spindle", "materials": ["steel", "steel"], "preload_n": 22e3,
                   "geometry": {"taper_diameter_m": 0.063}}}
    spec = _spec(q)
    res = usecases.resolve_joints(spec, repo)["holder-spindle"]
    assert res.kind == "query" and res.name == "hs-hsk-a63-24kn" and not res.extrapolating
    bt = _spec({"query": {**q["query"], "preload_n": 12e3, "geometry": {"taper_diameter_m": 0.04445}}})
    assert usecases.resolve_joints(bt, repo)["holder-spindle"].name == "hs-bt40-12kn"
    # the joint matters: the catalogued taper joint lowers the dominant tip mode compared with a rigid taper
    pred = predict_tool_tip(spec, {"holder-spindle": res.frf})
    rigid = predict_tool_tip(_spec("rigid"))
    f = pred.tip.freq
    assert f[np.argmax(np.abs(pred.tip.values[:, 0, 0]))] < f[np.argmax(np.abs(rigid.tip.values[:, 0, 0]))]
    out = usecases.resolve_joints(_spec({"query": {**q["query"], "preload_n": 40e3}}), repo)["holder-spindle"]
    assert out.extrapolating and "preload_n" in " ".join(out.warnings)
