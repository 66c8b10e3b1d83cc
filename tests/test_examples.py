"""`jointdb examples DIR`: the bundled models, campaigns and stacks, copied out of the package."""

import filecmp
import json
import os
import subprocess
import sys
from pathlib import Path

import jointdb

DATA = Path(jointdb.__file__).resolve().parent / "data"
REPO = Path(__file__).resolve().parents[1]


def jointdb_cli(*args, cwd):
    return subprocess.run([sys.executable, "-m", "jointdb", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, timeout=300, env={**os.environ, "OPENBLAS_NUM_THREADS": "1"})


def test_examples_copies_every_bundled_file_and_the_campaigns_run(tmp_path):
    r = jointdb_cli("examples", "ex", "--json", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    listed = {Path(row["file"]) for row in json.loads(r.stdout)}
    on_disk = {p.relative_to(tmp_path) for p in (tmp_path / "ex").rglob("*") if p.is_file()}
    assert listed == on_disk and len(on_disk) >= 20
    campaigns = sorted((tmp_path / "ex" / "campaigns").glob("*/campaign.json"))
    assert len(campaigns) == len(list((DATA / "catalogue" / "campaigns").glob("*/campaign.json"))) >= 6
    # every bundled file arrives unchanged, in the documented place
    pairs = [(DATA / "models" / "end-mill-in-holder.json", "models/end-mill-in-holder.json"),
             (DATA / "catalogue" / "demo-stack.json", "stacks/demo-stack.json")]
    pairs += [(p, f"models/{p.name}") for p in (DATA / "catalogue" / "models").glob("*.json")]
    pairs += [(p, f"campaigns/{p.relative_to(DATA / 'catalogue' / 'campaigns')}")
              for p in (DATA / "catalogue" / "campaigns").rglob("*") if p.is_file()]
    assert len(pairs) == len(on_disk)
    for src, dst in pairs:
        assert filecmp.cmp(src, tmp_path / "ex" / dst, shallow=False), dst
    # a copied campaign finds its models (../../models/...) and identifies
    r = jointdb_cli("identify", campaigns[0], "--out", "joint.h5", "--json", cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "joint.h5").is_file()


def test_examples_refuses_a_non_empty_directory_and_writes_nothing(tmp_path):
    (tmp_path / "ex").mkdir()
    (tmp_path / "ex" / "mine.txt").write_text("keep")
    r = jointdb_cli("examples", "ex", cwd=tmp_path)
    assert r.returncode == 2 and r.stderr.startswith("error: ex already exists and is not an empty directory")
    assert [p.name for p in (tmp_path / "ex").iterdir()] == ["mine.txt"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ex"]  # no temporary left behind
    r = jointdb_cli("examples", "no/such/dir", cwd=tmp_path)
    assert r.returncode == 2 and "does not exist" in r.stderr


def test_the_bundled_data_is_reachable_from_the_repository():
    link = REPO / "fixtures" / "bundled"
    if not link.exists():  # running against an installed copy without the clone
        return
    assert (link / "catalogue" / "demo-stack.json").is_file()
    assert len(list((link / "catalogue" / "campaigns").glob("*/campaign.json"))) == len(
        list((DATA / "catalogue" / "campaigns").glob("*/campaign.json")))
