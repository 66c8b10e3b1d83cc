"""The web catalogue in a real browser: Debian's chromium driven by Playwright against a
running server. Sign in with a token, browse and filter, open a joint (plot, versions,
downloads), overlay two versions, label and deprecate through the forms (CSRF), run the
nearest-joint form. Screenshots go to the test's output directory."""

from __future__ import annotations

import shutil

import pytest

from server_helpers import joint_upload

CHROMIUM = shutil.which("chromium")
pytestmark = pytest.mark.skipif(CHROMIUM is None, reason="chromium is not installed (apt-get install chromium; "
                                                         ".ci/run installs it)")
sync_api = pytest.importorskip("playwright.sync_api", reason="the playwright package is not installed")

ARGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update",
        "--disable-sync", "--no-first-run"]


@pytest.fixture(scope="module")
def browser():
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        yield b
        b.close()


@pytest.mark.parametrize("server", ["sqlite"], indirect=True)
def test_catalogue_pages_in_a_browser(server, browser, tmp_path):
    with server.client("writer") as c:
        for name, torque, k in (("HSK63-A", 30.0, 1e6), ("HSK63-B", 50.0, 2e6), ("HSK63-A", 30.0, 1.4e6)):
            assert c.post("/api/v1/catalogue", json=joint_upload(tmp_path, name, torque=torque, k=k)).status_code == 201
    shots = tmp_path / "screenshots"
    shots.mkdir()
    page = browser.new_page(viewport={"width": 1200, "height": 900})
    page.goto(f"{server.url}/ui/joints")
    assert page.url.endswith("/ui/signin")  # reads need a token by default
    page.fill("#token", server.tokens["writer"])
    page.click("#signin")
    page.wait_for_url("**/ui/joints")
    assert server.tokens["writer"] not in page.url
    cookie = [c for c in page.context.cookies() if c["name"] == "jointdb_session"][0]
    assert cookie["httpOnly"] and cookie["sameSite"] == "Strict"
    assert page.evaluate("document.cookie") == ""  # not readable by scripts
    assert page.locator("#joints tr").count() == 3
    page.screenshot(path=str(shots / "catalogue.png"), full_page=True)

    page.fill("input[name=torque_min]", "40")
    page.click("#apply")
    page.wait_for_load_state()
    assert page.locator("#joints tr").count() == 2 and "HSK63-B" in page.inner_text("#joints")

    page.goto(f"{server.url}/ui/joints")
    page.click("text=HSK63-A")
    page.wait_for_selector("#plot svg")
    assert "v2" in page.inner_text("#joint-name")
    assert page.locator("#plot path.curve").count() == 4  # 2 DOFs x (magnitude, phase)
    assert "frequency [Hz]" in page.inner_text("#plot") and "m/N" in page.inner_text("#plot")
    assert page.locator("#versions tr").count() == 3
    page.screenshot(path=str(shots / "joint.png"), full_page=True)
    with page.expect_download() as dl:
        page.click("#dl-csv")
    assert dl.value.suggested_filename == "HSK63-A-v2.csv"

    page.select_option("#overlay-a", "1")
    page.select_option("#overlay-b", "2")
    page.click("#overlay")
    page.wait_for_selector("#plot svg")
    assert page.locator("#plot path.curve").count() == 8 and "v1 (solid) and v2 (dashed)" in page.inner_text("#plot")
    page.screenshot(path=str(shots / "overlay.png"), full_page=True)

    page.goto(f"{server.url}/ui/joints/HSK63-A")
    page.fill("#label-name", "released")
    page.click("#label")
    page.wait_for_selector("#notice")
    page.fill("#deprecate-reason", "worn taper")
    page.click("#deprecate")
    page.wait_for_selector("#notice")
    audit = page.inner_text("#audit")
    assert "released" in audit and "worn taper" in audit and "writer-owner" in audit
    assert [e["actor"] for e in server.repo().audit("HSK63-A")[:2]] == ["writer-owner", "writer-owner"]
    page.screenshot(path=str(shots / "after-writes.png"), full_page=True)

    # a forged form (wrong CSRF token) writes nothing
    status = page.evaluate("""async () => (await fetch('/ui/joints/HSK63-B/deprecate', {method: 'POST',
        headers: {'Content-Type': 'application/x-www-form-urlencoded'}, body: 'csrf=forged&reason=x'})).status""")
    assert status == 422 and server.repo().get("HSK63-B").state == "active"

    page.goto(f"{server.url}/ui/nearest")
    page.fill("#q-type", "tool-holder")
    page.fill("#q-materials", "carbide+steel")
    page.fill("#q-torque", "45")
    page.click("#search")
    page.wait_for_selector("#matches")
    rows = page.locator("#matches tr")
    assert rows.count() == 3 and "HSK63-B" in rows.nth(1).inner_text()  # nearest first
    d = [float(x) for x in page.locator("#matches td.distance").all_inner_texts()]
    assert d == sorted(d)
    page.screenshot(path=str(shots / "nearest.png"), full_page=True)
    assert len(list(shots.glob("*.png"))) == 5
