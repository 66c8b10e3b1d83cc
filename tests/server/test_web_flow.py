"""The shop flow in a real browser on a live ``jointdb serve`` — on the SQLite default (in-process
job worker) and on PostgreSQL with a separate ``jointdb worker`` process (procrastinate): sign in as a writer → upload a bundled campaign (zipped as it lies) → the identify job
completes → the review shows k, c ± σ with units and the verdict, flags the contradiction of the
upload form → catalogue → design a stack from catalogued parts → the nearest joints (the one just
catalogued among them) → predict as a job → lobes as a job → downloads. Every page is checked at
1400 px (no horizontal scroll, no raw values) and kept as a screenshot in a folder the test prints.
The pages work on the JSON API only: what they show is compared with the API's own answers."""

from __future__ import annotations

import io
import json
import zipfile
from importlib import resources

import pytest

from test_server_jobs import deployment  # noqa: F401 - the live deployment fixture (both backends)
from web_helpers import ARGS, CHROMIUM, WIDTH, Shots, wait_visible

pytestmark = pytest.mark.skipif(CHROMIUM is None, reason="chromium is not installed (apt-get install chromium)")
sync_api = pytest.importorskip("playwright.sync_api", reason="the playwright package is not installed")

UPLOADED = "th-er32-carbide-120nm"


def _campaign_zip(name: str) -> bytes:
    """A bundled campaign zipped as it lies: campaigns/<name>/… beside models/."""
    base = resources.files("jointdb").joinpath("data", "catalogue")
    buf = io.BytesIO()
    with resources.as_file(base) as root, zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as zf:
        for path in sorted([*(root / "campaigns" / name).rglob("*"), *(root / "models").rglob("*")]):
            if path.is_file():
                zf.write(path, path.relative_to(root).as_posix())
    return buf.getvalue()


def _prepare(server) -> None:
    """The shop's catalogue before the flow: the bundled parts, the HSK-A63 taper joints and one
    tool–holder joint (the 120 N·m carbide campaign is what the flow uploads)."""
    from jointdb import usecases

    base = resources.files("jointdb").joinpath("data", "catalogue")
    with resources.as_file(base) as root, server.repo() as repo:
        usecases.catalogue_bundled_parts(repo, root, author="writer-owner")
        for camp in ("hs-hsk-a63-12kn", "hs-hsk-a63-18kn", "hs-hsk-a63-24kn", "th-er32-carbide-080nm"):
            usecases.catalogue_campaign(repo, root / "campaigns" / camp / "campaign.json", author="writer-owner")


@pytest.fixture(scope="module")
def server(deployment):
    """The live deployment of the jobs tests: SQLite with the in-process worker, PostgreSQL with a
    separate ``jointdb worker`` process."""
    deployment.server.tokens = deployment.tokens
    return deployment.server


def test_shop_flow_in_a_browser(server, tmp_path):
    _prepare(server)
    archive = tmp_path / f"{UPLOADED}.zip"
    archive.write_bytes(_campaign_zip(UPLOADED))
    with sync_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        page = browser.new_page(viewport={"width": WIDTH, "height": 900}, accept_downloads=True)
        errors: list[str] = []
        page.on("pageerror", lambda e: errors.append(str(e)))
        page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)  # CSP refusals too
        shots = Shots(page, tmp_path / "shop-flow-screenshots")
        page.goto(f"{server.url}/")
        page.fill("#token", server.tokens["writer"])
        page.click("#signin")
        page.wait_for_url("**/ui/joints")
        job_id = _upload_and_review(page, server, shots, archive)
        _design_predict_lobes(page, server, shots, tmp_path)
        page.goto(f"{server.url}/ui/jobs")
        page.wait_for_selector("#jobs tr:nth-child(4)")  # identify, predict, lobes
        assert job_id[:12] in page.inner_text("#jobs")
        shots.check("my-jobs")
        browser.close()
    assert not errors, errors


def _upload_and_review(page, server, shots, archive) -> str:
    page.click("#nav-upload")
    shots.check("upload")
    page.set_input_files("#u-file", str(archive))
    page.fill("#u-torque", "110")  # the campaign records 120 N·m: the review must flag it
    page.click("#u-submit")
    page.wait_for_url("**/ui/jobs/*")
    wait_visible(page, "#review", "#job-error")
    job_id = page.url.rsplit("/", 1)[1]
    with server.client("writer") as c:
        job = c.get(f"/api/v1/jobs/{job_id}").json()
    assert job["state"] == "succeeded" and job["kind"] == "identify"
    from jointdb.server.web_format import num

    kc = page.inner_text("#review-kc")
    for p in job["result"]["parameters"]:  # the page shows the job's own numbers, with units
        unit = "N·m/rad" if p["dof"].lstrip("0123456789").startswith("r") else "N/m"
        assert f"{p['dof']}\t{num(p['k'])} {unit}\t± {num(p['k_sigma'], 2)} {unit}" in kc, kc
    assert kc.count("±") == 2 + 2 * len(job["result"]["parameters"]) and "N·s/m" in kc
    assert page.inner_text("#review-verdict").startswith("Quality verdict")
    contradiction = page.inner_text("#review-contradictions")
    assert "120" in contradiction and "110" in contradiction and "--force" not in contradiction
    assert page.input_value("#c-torque") == "120" and page.input_value("#c-materials") == "tungsten-carbide + steel"
    assert page.locator("#review-plots .uplot").count() >= 4  # assembly fits, k(ω), c(ω)
    shots.check("review")
    page.fill("#c-name", "th-shop-120nm")
    page.fill("#c-label", "reviewed")
    page.click("#catalogue")
    wait_visible(page, "#done", "#job-error")
    shots.check("catalogued")
    page.click("#done-link")
    page.wait_for_selector(".plot .uplot canvas")
    assert "th-shop-120nm" in page.inner_text("#joint-name") and "reviewed" in page.inner_text("#joint-name")
    assert "clamping torque\t120 N·m" in page.inner_text("#conditions")
    assert server.repo().get("th-shop-120nm").provenance.parameters["job"] == job_id
    assert f"identify job\t{job_id}" in page.inner_text("#provenance")
    shots.check("catalogued-joint")
    return job_id


def _design_predict_lobes(page, server, shots, tmp_path) -> None:
    from jointdb.server.web_format import num

    page.click("#nav-design")
    page.wait_for_selector("#d-holder option[value^='er32-collet-chuck-hsk63@']", state="attached")
    page.select_option("#d-spindle", "demo-mill-spindle@1")
    page.click("#d-nearest")
    wait_visible(page, "#nearest", "#d-error")
    page.wait_for_selector("#nearest-hs table")
    first = page.inner_text("#nearest-th tr:nth-child(2)")
    assert "th-shop-120nm" in first  # 100 N·m: the joint just catalogued is the nearest
    assert "hs-hsk-a63-18kn" in page.inner_text("#nearest-hs tr:nth-child(2)")  # 20 kN drawbar force
    page.check("#d-interpolate")  # the interpolation's weights: 18 and 24 kN bracket 20 kN
    page.click("#d-nearest")
    page.wait_for_selector("#nearest-hs th:has-text('weight')")
    weights = {r.split("\t")[1]: float(r.split("\t")[3]) for r in page.inner_text("#nearest-hs table").splitlines()[1:]}
    assert weights["hs-hsk-a63-12kn v1"] == 0 and 0 < weights["hs-hsk-a63-24kn v1"] < weights["hs-hsk-a63-18kn v1"]
    assert abs(sum(weights.values()) - 1) < 2e-3, weights
    shots.check("design-nearest")
    page.uncheck("#d-interpolate")
    page.click("#d-predict")
    wait_visible(page, "#p-result", "#d-error")
    joints = page.inner_text("#p-joints")
    assert "th-shop-120nm@1" in joints and "hs-hsk-a63-18kn@1" in joints
    assert "er32-collet-chuck-hsk63" in page.inner_text("#p-parts")
    summary = page.inner_text("#p-summary")
    assert summary.count("\n") == 2 and "x\t" in summary and "y\t" in summary  # both planes
    assert page.locator("#p-plots .uplot").count() == 2
    with server.client("writer") as c:  # the band the page shows is the job's
        job = c.get(f"/api/v1/jobs/{page.get_attribute('#p-job', 'href').rsplit('/', 1)[1]}").json()["result"]
    band = page.inner_text("#p-band")
    assert job["band"] and band.count("\n") == len(job["band"]["peaks"]) == 2
    assert F"{num(job['band']['peaks'][0]['peak_m_per_n_p95'])}" in band
    shots.check("design-predicted")
    for link, name in (("#p-csv", "tip-frf.csv"), ("#p-json", "prediction.json"), ("#p-png", "tip-frf.png")):
        _download(page, link, name, tmp_path)
    assert page.input_value("#l-teeth") == "4" and page.input_value("#l-kt") == "796"
    page.click("#l-run")
    wait_visible(page, "#l-result", "#d-error")
    notes = page.inner_text("#l-notes")
    assert "796 N/mm² = 7.96 × 10⁸ N/m²" in notes
    job_link = page.get_attribute("#l-job", "href").rsplit("/", 1)[1]
    with server.client("writer") as c:
        lobes = c.get(f"/api/v1/jobs/{job_link}").json()["result"]
    best = page.inner_text("#l-best")
    assert len(lobes["best_speeds"]) >= 1 and best.count("\n") == len(lobes["best_speeds"])
    floor_mm = 1000 * lobes["summary"]["min_depth_m"]
    assert f"{floor_mm:.3g} mm" in page.inner_text("#l-summary")
    assert page.locator("#l-plots .uplot").count() == 1
    shots.check("lobes")
    path = _download(page, "#l-csv", "lobes.csv", tmp_path)
    rows = path.read_text().splitlines()
    assert rows[0].startswith("spindle_speed_rpm,depth_m") and len(rows) == len(lobes["rows"]) + 1
    assert json.loads(_download(page, "#l-json", "lobes.json", tmp_path).read_text())["summary"] == lobes["summary"]
    assert _download(page, "#l-png", "lobes.png", tmp_path).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def _download(page, link: str, name: str, tmp_path):
    with page.expect_download() as dl:
        page.click(link)
    assert dl.value.suggested_filename == name
    path = tmp_path / "downloads" / name
    path.parent.mkdir(exist_ok=True)
    dl.value.save_as(str(path))
    assert path.stat().st_size > 100, name
    return path


def test_upload_of_the_individual_files(server, tmp_path):
    """The campaign's files chosen one by one (no archive): the page packs them (a stored zip made in
    the browser, the campaign's ../../models paths turned into the files' names) and the identify
    job reads them as the archive would."""
    if server.db.startswith("postgresql"):
        pytest.skip("the packing is the browser's; one backend is enough")
    name = "th-er32-steel-040nm"
    base = resources.files("jointdb").joinpath("data", "catalogue")
    with resources.as_file(base) as root:
        camp = json.loads((root / "campaigns" / name / "campaign.json").read_text())
        models = sorted({s["model"].rsplit("/", 1)[-1] for s in camp["substructures"].values()})
        files = [root / "campaigns" / name / "campaign.json", root / "campaigns" / name / "assembly.uff",
                 *(root / "models" / m for m in models)]
        with sync_api.sync_playwright() as p:
            browser = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
            page = browser.new_page(viewport={"width": WIDTH, "height": 900})
            page.goto(f"{server.url}/ui/signin")
            page.fill("#token", server.tokens["writer"])
            page.click("#signin")
            page.goto(f"{server.url}/ui/upload")
            page.set_input_files("#u-files", [str(f) for f in files])
            page.click("#u-submit")
            page.wait_for_url("**/ui/jobs/*")
            wait_visible(page, "#review", "#job-error")
            assert page.input_value("#c-name") == name and page.input_value("#c-torque") == "40"
            assert page.inner_text("#review-contradictions") == ""
            page.goto(f"{server.url}/ui/upload")  # without the campaign file: said, nothing sent
            page.set_input_files("#u-files", [str(f) for f in files[1:]])
            page.click("#u-submit")
            page.wait_for_selector("#u-error:not([hidden])")
            assert "campaign file" in page.inner_text("#u-error") and page.url.endswith("/ui/upload")
            browser.close()
