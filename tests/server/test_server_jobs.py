"""Jobs on a real queue against live processes (issue 21): ``jointdb serve`` on the SQLite
default (in-process worker) and on PostgreSQL with a separate ``jointdb worker`` process
(procrastinate). POST answers 202 fast; a job's result equals the use case's / the CLI's on
the same inputs; cancel works; ``kill -9`` of the server or the worker mid-job leaves the job
resumed (run again) or failed with a reason, never lost."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import httpx
import numpy as np
import pytest

from server_helpers import make_tokens, migrated_database, start_server, stop_server

ROOT = Path(__file__).resolve().parents[2]
CUT = {"teeth": 4, "kt": 6e8, "kr": 2e8, "immersion": 0.5, "rpm_min": 2000.0, "rpm_max": 20000.0}


def _stack() -> dict:
    stacks = ROOT / "fixtures" / "stacks"
    stack = json.loads((stacks / "endmill-catalogued-joint.json").read_text())
    stack["spindle"]["model"] = json.loads((stacks / stack["spindle"]["model"]).read_text())  # inline
    stack["interfaces"]["tool-holder"] = "rigid"
    stack["frequency"] = {"min": 100.0, "max": 3000.0, "step": 20.0}
    return stack


def start_worker(db: str, blobs: Path, log: Path) -> subprocess.Popen:
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    with open(log, "ab") as fh:
        return subprocess.Popen([sys.executable, "-m", "jointdb", "worker", "--db", db, "--blobs", str(blobs),
                                 "--heartbeat", "1", "--stalled-after", "3"], stdout=fh, stderr=subprocess.STDOUT,
                                env=env, cwd=ROOT)


class Deployment:
    def __init__(self, backend: str, db: str, tmp: Path):
        self.backend, self.db, self.tmp = backend, db, tmp
        self.blobs = tmp / "blobs"
        self.tokens = make_tokens(db, self.blobs)
        self.server = start_server(db, self.blobs, tmp / "server.log")
        self.worker = start_worker(db, self.blobs, tmp / "worker.log") if backend == "postgresql" else None

    def client(self, role="reader") -> httpx.Client:
        return httpx.Client(base_url=self.server.url, timeout=60,
                            headers={"Authorization": f"Bearer {self.tokens[role]}"})

    def restart_server(self):
        self.server = start_server(self.db, self.blobs, self.tmp / "server.log")

    def restart_worker(self):
        self.worker = start_worker(self.db, self.blobs, self.tmp / "worker.log")

    def stop(self):
        stop_server(self.server)
        if self.worker is not None and self.worker.poll() is None:
            self.worker.send_signal(signal.SIGTERM)
            try:
                self.worker.wait(timeout=30)
            except subprocess.TimeoutExpired:
                self.worker.kill()


@pytest.fixture(scope="module", params=["sqlite", "postgresql"])
def deployment(request, tmp_path_factory):
    tmp = tmp_path_factory.mktemp(f"jobs-{request.param}")
    with migrated_database(request.param, tmp) as db:
        dep = Deployment(request.param, db, tmp)
        yield dep
        dep.stop()


def submit(c: httpx.Client, kind: str, body: dict) -> tuple[str, float]:
    t0 = time.perf_counter()
    r = c.post(f"/api/v1/jobs/{kind}", json=body)
    elapsed = time.perf_counter() - t0
    assert r.status_code == 202, r.text
    out = r.json()
    assert out["state"] == "queued" and r.headers["location"] == out["url"] == f"/api/v1/jobs/{out['id']}"
    return out["id"], elapsed


def wait(c: httpx.Client, job_id: str, until=("succeeded", "failed", "cancelled"), timeout=240.0) -> dict:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            job = c.get(f"/api/v1/jobs/{job_id}").json()
        except httpx.HTTPError:  # a server being restarted
            time.sleep(0.3)
            continue
        if job["state"] in until:
            return job
        time.sleep(0.2)
    raise AssertionError(f"job {job_id} still {job['state']} ({job['message']}) after {timeout} s")


def running(c, job_id) -> dict:
    """Wait until the job is running and has reported progress (it is mid-work)."""
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        job = c.get(f"/api/v1/jobs/{job_id}").json()
        if job["state"] == "running" and job["progress"] > 0.06:
            return job
        assert job["state"] in ("queued", "running"), job
        time.sleep(0.1)
    raise AssertionError(f"job {job_id} never got going: {job}")


def test_predict_and_sd_lobes_jobs_equal_the_cli(deployment, tmp_path):
    from jointdb import usecases
    from jointdb.io import frf_from_json, frf_json, write_frf_hdf5
    from jointdb.stack import stack_from_dict

    stack = _stack()
    with deployment.client() as c:
        warm, _ = submit(c, "predict", {"stack": stack})  # the process's first request opens its connections
        wait(c, warm)
        pid, t_predict = submit(c, "predict", {"stack": stack})
        job = wait(c, pid)
        assert job["state"] == "succeeded", job
        assert job["progress"] == 1.0 and job["error"] is None and job["started"] and job["finished"]
        local = usecases.predict_stack(stack_from_dict(stack), None).prediction
        tip = job["result"]["tip_frf"]
        want = frf_json(local.tip)
        np.testing.assert_allclose(tip["real"], want["real"], rtol=1e-12, atol=0)
        np.testing.assert_allclose(tip["imag"], want["imag"], rtol=1e-12, atol=0)
        assert job["result"]["prediction"] == json.loads(json.dumps(local.summary()))

        body = {"frf": tip, "method": "sd", "n_speeds": 24, "refine": 0, **CUT}
        lid, t_lobes = submit(c, "lobes", body)
        job = wait(c, lid)
        assert job["state"] == "succeeded", job
        print(f"\n{deployment.backend}: POST /jobs/predict {t_predict * 1e3:.1f} ms, POST /jobs/lobes (SD) "
              f"{t_lobes * 1e3:.1f} ms")
        assert t_predict < 0.2 and t_lobes < 0.2, (t_predict, t_lobes)
        path = tmp_path / "tip.h5"
        write_frf_hdf5(path, frf_from_json(tip), {})
        cli = subprocess.run([sys.executable, "-m", "jointdb", "lobes", str(path), "--method", "sd", "--teeth", "4",
                              "--kt", "6e8", "--kr", "2e8", "--immersion", "0.5", "--n-speeds", "24", "--refine", "0",
                              "--json"], capture_output=True, text=True, cwd=ROOT,
                             env={**os.environ, "OPENBLAS_NUM_THREADS": "1"})
        assert cli.returncode == 0, cli.stderr
        want = json.loads(cli.stdout)
        got = job["result"]
        assert got["summary"].keys() == want["summary"].keys()
        for key, value in want["summary"].items():
            assert got["summary"][key] == (pytest.approx(value, rel=1e-9) if isinstance(value, float) else value), key
        np.testing.assert_allclose([r["depth_m"] for r in got["rows"]], [r["depth_m"] for r in want["rows"]],
                                   rtol=1e-9)
        # the listing shows the caller's jobs, newest first; another reader does not see them
        items = c.get("/api/v1/jobs", params={"kind": "lobes"}).json()["items"]
        assert items[0]["id"] == lid and all(j["kind"] == "lobes" for j in items)
    with deployment.client("writer") as other:
        assert other.get(f"/api/v1/jobs/{lid}").status_code == 404
        assert all(j["id"] != lid for j in other.get("/api/v1/jobs").json()["items"])
    with deployment.client("admin") as admin:
        assert admin.get(f"/api/v1/jobs/{lid}").json()["state"] == "succeeded"


def test_cancel_a_running_job(deployment):
    tip = _tip(deployment)
    with deployment.client() as c:
        jid, _ = submit(c, "lobes", {"frf": tip, "method": "sd", "n_speeds": 300, "refine": 0, **CUT})
        running(c, jid)
        r = c.post(f"/api/v1/jobs/{jid}/cancel")
        assert r.status_code == 202
        job = wait(c, jid, timeout=60)
        assert job["state"] == "cancelled" and job["result"] is None, job


def _tip(deployment) -> dict:
    with deployment.client() as c:
        jid, _ = submit(c, "predict", {"stack": _stack()})
        return wait(c, jid)["result"]["tip_frf"]


def test_kill_9_mid_job_resumes_it(deployment):
    """SQLite: the server runs the job, is killed and restarted. PostgreSQL: the worker is killed and
    another started; then the server is killed while a job waits. The job runs again to the end."""
    tip = _tip(deployment)
    with deployment.client() as c:
        jid, _ = submit(c, "lobes", {"frf": tip, "method": "sd", "n_speeds": 60, "refine": 0, **CUT})
        first = running(c, jid)
    victim = deployment.server.proc if deployment.backend == "sqlite" else deployment.worker
    victim.send_signal(signal.SIGKILL)
    victim.wait()
    if deployment.backend == "sqlite":
        deployment.restart_server()
    else:
        deployment.restart_worker()
    with deployment.client() as c:
        job = wait(c, jid)
        assert job["state"] == "succeeded", job
        assert job["attempts"] == first["attempts"] + 1 == 2
        if deployment.backend == "postgresql":  # the server killed: the queue is in the database
            jid2, _ = submit(c, "predict", {"stack": _stack()})
    if deployment.backend == "postgresql":
        deployment.server.proc.send_signal(signal.SIGKILL)
        deployment.server.proc.wait()
        deployment.restart_server()
        with deployment.client() as c:
            assert wait(c, jid2)["state"] == "succeeded"


def test_job_input_errors_are_field_named_422s(deployment):
    tip = _tip(deployment)
    with deployment.client() as c:
        bad = dict(tip, real=[row[:1] for row in tip["real"]])
        r = c.post("/api/v1/jobs/lobes", json={"frf": bad, **CUT})
        assert r.status_code == 422 and r.json()["error"].startswith("frf.real"), r.text
        r = c.post("/api/v1/lobes", json={"joint": "TH-0", "version": 1, **CUT})
        assert r.status_code == 422 and "tool-tip FRF" in r.json()["error"], r.text
        r = c.post("/api/v1/lobes", json={"frf": tip, **dict(CUT, kt=796.0), "n_speeds": 20, "refine": 0})
        assert r.status_code == 200, r.text
        out = r.json()
        assert any("N/mm²" in n and "7.96e+08" in n for n in out["notes"])
        assert out["coefficients_n_per_m2"]["kt"] == 7.96e8 and out["summary"]["speeds"] == 20
        assert c.post("/api/v1/jobs/identify", json={"file_b64": ""}).status_code == 403  # reader
        assert c.get("/api/v1/jobs/" + "0" * 32).status_code == 404


def _campaign_zip(name: str = "th-er32-carbide-080nm") -> bytes:
    """A bundled campaign zipped as it lies: campaigns/<name>/… beside models/ (its ../../models paths
    stay inside the archive)."""
    import io
    import zipfile

    base = ROOT / "fixtures" / "bundled" / "catalogue"
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as zf:
        for path in sorted([*(base / "campaigns" / name).rglob("*"), *(base / "models").rglob("*")]):
            if path.is_file():
                zf.write(path, path.relative_to(base).as_posix())
    return buf.getvalue()


def test_identify_review_catalogue(deployment):
    data = _campaign_zip()
    with deployment.client("reader") as reader:
        r = reader.post("/api/v1/jobs/identify", files={"file": ("c.zip", data, "application/zip")})
        assert r.status_code == 403  # identify needs a writer
    with deployment.client("writer") as c:
        r = c.post("/api/v1/jobs/identify", files={"file": ("bad.zip", b"not a zip", "application/zip")})
        assert r.status_code == 422 and "not a zip" in r.json()["error"]
        t0 = time.perf_counter()
        r = c.post("/api/v1/jobs/identify", files={"file": ("th.zip", data, "application/zip")},
                   data={"conditions": json.dumps({"torque_nm": 75.0})})
        assert r.status_code == 202, r.text
        assert time.perf_counter() - t0 < 2.0
        job = wait(c, r.json()["id"])
        assert job["state"] == "succeeded", job
        review = job["result"]
        assert review["campaign"] == "th-er32-carbide-080nm" and review["conditions"]["torque_nm"] == 80
        assert review["contradictions"] and "75" in review["contradictions"][0]
        units = {p["dof"]: (p["k_unit"], p["c_unit"]) for p in review["parameters"]}
        assert units == {"3x": ("N/m", "N·s/m"), "3ry": ("N·m/rad", "N·m·s/rad")}, units
        # σ from the output-error fit, relative to the value as the verdict's "largest standard error 2.3% (c 3ry)"
        worst = max(p[f"{q}_sigma"] / p[q] for p in review["parameters"] for q in ("k", "c"))
        assert any(f"{100 * worst:.1f}%" in line for line in review["verdict"]), (worst, review["verdict"])
        assert all(p["k"] > 0 for p in review["parameters"])
        assert review["curves"]["assembly"]["entries"] and review["curves"]["joint"]["dofs"]
        r = c.post(f"/api/v1/jobs/{job['id']}/catalogue", json={"name": "TH-job", "label": "reviewed"})
        assert r.status_code == 201, r.text
        v = r.json()
        assert v["name"] == "TH-job" and v["version"] == 1 and "reviewed" in v["labels"]
        assert v["conditions"]["torque_nm"] == 80 and v["provenance"]["author"] == "writer-owner"
        assert v["provenance"]["parameters"]["job"] == job["id"]
        assert c.get("/api/v1/joints/TH-job").json()["version"] == 1
        assert c.post(f"/api/v1/jobs/{job['id']}/catalogue", json={}).status_code == 409
        assert c.post(f"/api/v1/jobs/{job['id']}/discard").status_code == 409


def test_cli_predict_over_server_equals_the_database(deployment, tmp_path):
    """`jointdb --server URL predict` reads the catalogued joints from the server (the joint catalogued
    by the identify job above) and answers what `--db` answers."""
    stack = _stack()
    stack["interfaces"]["tool-holder"] = {"query": {"joint_type": "tool-holder", "torque_nm": 80.0,
                                                    "materials": ["tungsten-carbide", "steel"], "neighbours": 1}}
    path = tmp_path / "stack.json"
    path.write_text(json.dumps(stack))
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "JOINTDB_TOKEN": deployment.tokens["reader"]}
    env.pop("JOINTDB_URL", None)
    runs = {}
    for how, args in (("server", ["--server", deployment.server.url, "predict"]),
                      ("db", ["predict", "--db", deployment.db])):
        out = subprocess.run([sys.executable, "-m", "jointdb", *args, str(path), "--json"], capture_output=True,
                             text=True, cwd=ROOT, env=env if how == "server" else {**env, "JOINTDB_BLOBS": str(
                                 deployment.blobs)})
        assert out.returncode == 0, out.stderr
        runs[how] = json.loads(out.stdout)
    assert runs["server"]["joints"] == runs["db"]["joints"]
    assert any(j.get("joint", "").startswith("TH-job") for j in runs["server"]["joints"]), runs["server"]["joints"]
    assert runs["server"]["prediction"] == runs["db"]["prediction"]
    assert runs["db"]["band"] is not None  # the identified joint carries its covariance
    with deployment.client() as c:  # the predict job gives what the CLI gives: prediction, band, sensitivity
        job = wait(c, submit(c, "predict", {"stack": stack})[0])
    assert job["state"] == "succeeded", job
    assert job["result"]["prediction"] == runs["db"]["prediction"]
    assert job["result"]["band"] == runs["db"]["band"]
    assert job["result"]["joint_choice_sensitivity"] == runs["db"]["joint_choice_sensitivity"]


def test_diagnose_job_equals_the_cli(deployment, tmp_path):
    """A diagnose job on a seeded bench case (a compliant joint hidden in the recording) gives the
    verdict and the fitted values of `jointdb diagnose --json` on the same model and recording."""
    if deployment.backend != "sqlite":
        pytest.skip("one backend is enough for this (about a minute per run); the queue is tested on both")
    from jointdb.diagnose_bench import generate_case
    from jointdb.io import frf_json, write_uff58

    from jointdb.io import read_frf_uff58

    case = generate_case("joint_compliance", 1000)
    write_uff58(tmp_path / "rec.uff", case.recordings[0].frf)
    rec = read_frf_uff58(tmp_path / "rec.uff")  # the job gets exactly what the CLI reads
    with deployment.client() as c:
        jid, elapsed = submit(c, "diagnose", {"model": case.model, "recordings": [frf_json(rec)],
                                              "combinations": False})
        job = wait(c, jid, timeout=400)
    assert job["state"] == "succeeded", job
    (tmp_path / "model.json").write_text(json.dumps(case.model))
    cli = subprocess.run([sys.executable, "-m", "jointdb", "diagnose", str(tmp_path / "model.json"),
                          str(tmp_path / "rec.uff"), "--no-combinations", "--json"], capture_output=True, text=True,
                         cwd=ROOT, env={**os.environ, "OPENBLAS_NUM_THREADS": "1"})
    assert cli.returncode == 0, cli.stderr
    want = json.loads(cli.stdout)
    got = job["result"]
    assert got["verdict"] == want["verdict"] and got["explained"] == want["explained"]
    assert got["best"]["name"] == want["best"]["name"]
    for key, value in want["best"]["values"].items():
        assert got["best"]["values"][key] == pytest.approx(value, rel=1e-6), key


def test_identify_from_individual_files(deployment):
    """The campaign file and the files it names uploaded side by side (no archive): packed and checked
    as an archive, identified; a file name with a folder is refused."""
    folder = ROOT / "fixtures" / "campaigns" / "th-steel-30nm"
    files = [("file", (p.name, p.read_bytes(), "application/octet-stream")) for p in sorted(folder.iterdir())
             if p.is_file()]
    with deployment.client("writer") as c:
        r = c.post("/api/v1/jobs/identify", files=[*files, ("file", ("../x.json", b"{}", "application/json"))])
        assert r.status_code == 422 and "plain file names" in r.json()["error"], r.text
        r = c.post("/api/v1/jobs/identify", files=files)
        assert r.status_code == 202, r.text
        job = wait(c, r.json()["id"])
        assert job["state"] == "succeeded", job
        assert job["result"]["campaign"] == json.loads((folder / "campaign.json").read_text())["name"]
        assert c.post(f"/api/v1/jobs/{job['id']}/discard").json() == {"id": job["id"], "discarded": True}
        assert c.post(f"/api/v1/jobs/{job['id']}/catalogue", json={}).status_code == 409


def test_browser_session_needs_same_origin_and_csrf_header(deployment):
    """A signed-in browser session may use the jobs API: reads with its cookie, POSTs only from this
    site with the page's CSRF token in X-CSRF-Token (a cross-site form cannot set that header)."""
    import re

    csrf_re = re.compile(r'name="csrf" value="([0-9a-f]{64})"')
    with httpx.Client(base_url=deployment.server.url, follow_redirects=False, timeout=60) as web:
        page = web.get("/ui/signin")
        r = web.post("/ui/signin", data={"csrf": csrf_re.search(page.text).group(1),
                                         "token": deployment.tokens["reader"]})
        assert r.status_code == 303
        csrf = csrf_re.search(web.get("/ui/joints").text).group(1)
        cookie = {"Cookie": f"jointdb_session={web.cookies.get('jointdb_session')}"}  # (scoped to / on r3-web)
    body = {"stack": _stack()}
    with httpx.Client(base_url=deployment.server.url, timeout=60, headers=cookie) as api:
        assert api.get("/api/v1/jobs").status_code == 200
        r = api.post("/api/v1/jobs/predict", json=body)
        assert r.status_code == 403 and "X-CSRF-Token" in r.json()["error"]
        r = api.post("/api/v1/jobs/predict", json=body, headers={"X-CSRF-Token": csrf,
                                                                 "Origin": "https://evil.example"})
        assert r.status_code == 403
        r = api.post("/api/v1/jobs/predict", json=body, headers={"X-CSRF-Token": csrf})
        assert r.status_code == 202, r.text
        job = wait(api, r.json()["id"])
        assert job["owner"] == "reader-owner" and job["state"] == "succeeded"
    with httpx.Client(base_url=deployment.server.url, timeout=60) as anonymous:
        assert anonymous.get(f"/api/v1/jobs/{job['id']}").status_code == 401
