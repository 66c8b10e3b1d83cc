"""``jointdb couple``: every field of a campaign's ``couple`` section is checked and named in the error
(docs/file-formats.md, *The couple section of a campaign*), and a couple-only campaign (no measurements)
computes the outputs it names, rotations included."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest


ROOT = Path(__file__).resolve().parents[2]
FIXTURE = ROOT / "fixtures" / "campaigns" / "th-steel-30nm"  # A = holder.uff (3x 3ry, 20-5000 Hz by 10), B = tool
GRID = {"min": 20.0, "max": 5000.0, "step": 10.0}
GOOD = {"joint": {"k": [2e7, 3e5], "c": [250.0, 2.0]},
        "outputs": [["tool", "1x"], ["holder", "3ry"]], "inputs": [["tool", "1x"], ["holder", "3ry"]],
        "frequency": GRID}


def couple_only(tmp_path: Path, couple: dict) -> Path:
    d = tmp_path / "camp"
    shutil.copytree(FIXTURE, d)
    doc = json.loads((d / "campaign.json").read_text())
    doc.pop("measurements")
    doc.pop("validation", None)
    doc["couple"] = couple
    (d / "campaign.json").write_text(json.dumps(doc))
    return d / "campaign.json"


def test_couple_only_campaign_gives_the_named_outputs_reciprocal(run_cli, tmp_path):
    path = couple_only(tmp_path, GOOD)
    out_file = tmp_path / "g.h5"
    code, out, err = run_cli("couple", path, "--out", out_file, "--json")
    assert code == 0, err
    summary = json.loads(out)
    assert summary["outputs"] == "1x 3ry" and summary["inputs"] == "1x 3ry" and summary["lines"] == 499
    from jointdb.io import read_frf_hdf5

    g = read_frf_hdf5(out_file).values
    # a passive assembly of reciprocal parts through a symmetric joint is reciprocal: H(1x, 3ry) = H(3ry, 1x)
    # (A's measured block is symmetric to the UFF58 file's 6 digits; the coupling adds round-off only)
    np.testing.assert_allclose(g[:, 0, 1], g[:, 1, 0], rtol=1e-4, atol=1e-6 * np.abs(g[:, 0, 1]).max())


BAD = [
    ({**GOOD, "outputs": [["tool", "1x"], ["holder", "3rz"]]}, "couple.outputs[1]: substructure 'holder' has no DOF 3rz"),
    ({**GOOD, "outputs": [["tol", "1x"]]}, "couple.outputs[0]: unknown substructure 'tol'"),
    ({**GOOD, "inputs": [["tool", "9x"]]}, "couple.inputs[0]: substructure 'tool' has no DOF 9x"),
    ({**GOOD, "outputs": [["tool"]]}, "couple.outputs[0]"),
    ({**GOOD, "joint": {"k": [2e7], "c": [250.0, 2.0]}}, "couple.joint.k: has 1 value(s); give one per interface.a_dofs"),
    ({**GOOD, "joint": {"k": [2e7, -1.0], "c": [250.0, 2.0]}}, "couple.joint"),
    ({**GOOD, "joint": "missing.h5"}, "couple.joint: joint file 'missing.h5' not found"),
    ({**GOOD, "frequency": {**GRID, "step": 0}}, "couple.frequency.step"),
    ({**GOOD, "frequency": {"min": 20.0, "max": 5000.0}}, "couple.frequency.step"),
    ({**GOOD, "frequency": {**GRID, "max": 10.0}}, "couple.frequency"),
    ({k: v for k, v in GOOD.items() if k != "frequency"}, "couple.frequency"),
    ({k: v for k, v in GOOD.items() if k != "outputs"}, "couple.inputs: given without couple.outputs"),
    ({**GOOD, "output": [["tool", "1x"]]}, "couple.output"),
]


@pytest.mark.parametrize("couple, field", BAD, ids=[f"bad{i}" for i in range(len(BAD))])
def test_bad_couple_fields_are_named(run_cli, tmp_path, couple, field):
    path = couple_only(tmp_path, couple)
    code, out, err = run_cli("couple", path, "--out", tmp_path / "g.h5")
    assert code != 0 and field in err, err
    assert "Traceback" not in err and not (tmp_path / "g.h5").exists()


def test_couple_help_points_to_the_field_reference(run_cli):
    code, out, _ = run_cli("couple", "--help")
    assert code == 0 and "docs/file-formats.md" in out and "frequency" in out and "outputs" in out
    text = (ROOT / "docs" / "file-formats.md").read_text(encoding="utf-8")
    for field in ("couple.joint", "couple.outputs", "couple.inputs", "couple.frequency"):
        assert f"`{field}`" in text
