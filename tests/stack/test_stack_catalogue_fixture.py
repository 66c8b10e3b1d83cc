"""The bundled catalogue is exactly what fixtures/make_catalogue.py writes, and its campaigns are valid."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from jointdb.campaign import load_campaign
from jointdb.stack import stack_from_dict

ROOT = Path(__file__).resolve().parents[2]
BUNDLED = ROOT / "jointdb" / "data" / "catalogue"


@pytest.fixture(scope="module")
def generator(load_script):
    return load_script("fixtures/make_catalogue.py")


def test_bundled_campaigns_cover_three_torques_and_two_materials():
    seen = set()
    for path in sorted(BUNDLED.glob("campaigns/th-*/campaign.json")):
        camp = load_campaign(path)
        assert camp.joint_type == "tool-holder" and camp.joint_model == "planar"
        seen.add((tuple(camp.conditions["materials"]), camp.conditions["torque_nm"]))
    assert len(seen) == 6
    assert {t for _, t in seen} == {40.0, 80.0, 120.0}
    assert len({m for m, _ in seen}) == 2
    demo = stack_from_dict(json.loads((BUNDLED / "demo-stack.json").read_text()))
    assert demo.interfaces["tool-holder"].kind == "query"
    assert demo.interfaces["holder-spindle"].kind == "query"


def test_true_joints_follow_the_documented_trend(generator):
    mc = generator
    k40, _ = mc.true_joint(40.0, "carbide")
    k120, c120 = mc.true_joint(120.0, "carbide")
    ks, cs = mc.true_joint(120.0, "steel")
    assert k120[0] > k40[0] and k120[0] > ks[0] and cs[0] > c120[0]


@pytest.mark.slow
def test_make_catalogue_regenerates_the_bundled_files_byte_for_byte(tmp_path, generator):
    # one campaign (each has its own seed) + the models and the demo stack: byte-identical to the bundle
    written = generator.write_catalogue(tmp_path, only=("th-er32-steel-080nm",))
    names = {p.relative_to(tmp_path).as_posix() for p in written}
    assert "campaigns/th-er32-steel-080nm/assembly.uff" in names and "demo-stack.json" in names
    assert len(names) == 8  # 4 models, 3 campaign files, the demo stack
    for rel in sorted(names):
        assert (tmp_path / rel).read_bytes() == (BUNDLED / rel).read_bytes(), rel
    bundled = {p.relative_to(BUNDLED).as_posix() for p in BUNDLED.rglob("*") if p.is_file()}
    assert len(bundled) == 4 + 6 * 3 + 1 + 2 + 6 * 3  # + the holder–spindle models and campaigns
