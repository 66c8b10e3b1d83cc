"""The bundled holder–spindle campaigns: conditions, the true-joint trend, byte-for-byte regeneration."""

from __future__ import annotations

from pathlib import Path

import pytest

from jointdb.campaign import load_campaign

ROOT = Path(__file__).resolve().parents[2]
BUNDLED = ROOT / "jointdb" / "data" / "catalogue"


@pytest.fixture(scope="module")
def generator(load_script):
    return load_script("fixtures/make_hs_catalogue.py")


def test_bundled_hs_campaigns_cover_two_tapers_and_three_drawbar_forces_each():
    seen = set()
    for path in sorted(BUNDLED.glob("campaigns/hs-*/campaign.json")):
        camp = load_campaign(path)
        assert camp.joint_type == "holder-spindle" and camp.joint_model == "planar"
        cond = camp.conditions
        assert cond["preload_n"] > 0 and cond["extra"]["holder_family"] == "er32-collet"
        seen.add((cond["extra"]["taper"], cond["geometry"]["taper_diameter_m"], cond["preload_n"]))
    assert len(seen) == 6
    assert {(t, d) for t, d, _ in seen} == {("HSK-A63", 0.063), ("BT40", 0.04445)}


def test_true_hs_joints_stiffen_with_drawbar_force_and_hsk_is_stiffer_than_bt40(generator):
    mc = generator
    k12, _ = mc.true_joint(12e3, "HSK-A63")
    k24, _ = mc.true_joint(24e3, "HSK-A63")
    kb, cb = mc.true_joint(12e3, "BT40")
    _, ch = mc.true_joint(12e3, "HSK-A63")
    assert k24[0] > k12[0] and k24[1] > k12[1]
    assert kb[0] < k12[0] and kb[1] < k12[1] and cb[0] > ch[0]
    with pytest.raises(ValueError, match="unknown taper"):
        mc.true_joint(12e3, "CAT50")


@pytest.mark.slow
def test_make_hs_catalogue_regenerates_the_bundled_files_byte_for_byte(tmp_path, generator):
    written = generator.write_hs_catalogue(tmp_path, only=("hs-bt40-12kn",))
    names = {p.relative_to(tmp_path).as_posix() for p in written}
    assert "campaigns/hs-bt40-12kn/assembly.uff" in names and len(names) == 5  # 2 models, 3 campaign files
    for rel in sorted(names):
        assert (tmp_path / rel).read_bytes() == (BUNDLED / rel).read_bytes(), rel
