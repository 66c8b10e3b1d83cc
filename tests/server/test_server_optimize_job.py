"""An optimize job through the service (issue 24): the spec sent inline — stack, spindle by machine,
holders by family, joints from the catalogue — gives what `jointdb optimize --json` gives on the same
database; a spec naming server files, unknown fields or absurd sizes is a field-named 422 at submit."""

from __future__ import annotations

import copy
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from server_helpers import migrated_database, one_line_4xx
from test_server_jobs import Deployment, submit, wait

ROOT = Path(__file__).resolve().parents[2]
SPEC = json.loads((ROOT / "fixtures" / "optimize" / "optimize-catalogue.json").read_text())


@pytest.fixture(scope="module", params=["sqlite", "postgresql"])
def served(request, tmp_path_factory):
    """A service whose database holds the bundled catalogue: its joints and its parts."""
    from jointdb.store import Repository
    from jointdb.usecases._catalogue import catalogue_campaign
    from jointdb.usecases._partfiles import catalogue_bundled_parts

    tmp = tmp_path_factory.mktemp(f"optimize-{request.param}")
    cat = ROOT / "fixtures" / "bundled" / "catalogue"
    with migrated_database(request.param, tmp) as db:
        with Repository(db, blobs=tmp / "blobs", auto_create=False) as repo:
            for path in sorted((cat / "campaigns").glob("*/campaign.json")):
                catalogue_campaign(repo, path)
            catalogue_bundled_parts(repo, cat)
        dep = Deployment(request.param, db, tmp)
        yield dep
        dep.stop()


def test_optimize_job_equals_the_cli(served, tmp_path):
    body = {"spec": SPEC, "top": 5, "simulate": False}
    with served.client() as c:
        jid, _ = submit(c, "optimize", body)
        job = wait(c, jid)
    assert job["state"] == "succeeded", job
    got = job["result"]
    spec_file = tmp_path / "spec.json"
    spec_file.write_text(json.dumps(SPEC))
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "JOINTDB_BLOBS": str(served.blobs)}
    out = subprocess.run([sys.executable, "-m", "jointdb", "optimize", str(spec_file), "--db", served.db, "--json",
                          "--no-simulate", "--scheduler", "in-process"], capture_output=True, text=True, cwd=ROOT,
                         env=env)
    assert out.returncode == 0, out.stderr
    cli = json.loads(out.stdout)
    assert got["candidates"] == cli["candidates"] == 36
    assert got["ranked"] == cli["ranked"][:5]
    for key in ("notes", "parts", "holder_parts", "best_lobes", "rate_vs_overhang", "pareto"):
        assert got[key] == cli[key], key
    best = got["ranked"][0]
    assert best["holder"] == "er32-collet-chuck-hsk63@1" and best["removal_rate_m3_s"] > 0
    assert {p["slot"]: p["part"] for p in got["parts"]} == {"spindle": "demo-mill-spindle@1",
                                                            "tool": "carbide-end-mill-12mm-4fl@1"}
    assert got["holder_parts"] == ["er32-collet-chuck-hsk63@1"]


def _deep(n: int) -> dict:
    doc: dict = {}
    for _ in range(n):
        doc = {"a": doc}
    return doc


def _with(**changes) -> dict:
    doc = copy.deepcopy(SPEC)
    doc.update(changes)
    return doc


@pytest.mark.parametrize("body, status, needle", [
    ({"spec": _with(stack="../../../etc/passwd")}, 422, "spec: stack: send the stack document inline"),
    ({"spec": _with(stack={**SPEC["stack"], "spindle": {"model": "/etc/m.json", "point": "nose"}},
                    machine={k: v for k, v in SPEC["machine"].items() if k != "name"})}, 422,
     "stack.spindle: refers to a file"),
    ({"spec": _with(colour="red")}, 422, "spec: colour: unknown field"),
    ({"spec": _with(tool={**SPEC["tool"], "overhang_step_m": 1e-12})}, 422, "overhang grid: more than 1000"),
    ({"spec": SPEC, "top": 0}, 422, "top"),
    ({"spec": _with(holders=[{"family": "no-such-family"}])}, 404, "no catalogued holder of family"),
    ({"spec": _with(holders=[{"name": "mine", "holder": {"segments": "x"}}])}, 422, "holders[0].holder"),
    ({"spec": _with(holders=[{"name": "deep", "holder": _deep(400)}])}, 422, "holders[0].holder"),
])
def test_a_bad_optimize_spec_is_refused_at_submit(served, body, status, needle):
    with served.client() as c:
        r = c.post("/api/v1/jobs/optimize", json=body)
    msg = one_line_4xx(r, status)
    assert needle in msg and "/etc" not in msg, msg  # no server path echoed
