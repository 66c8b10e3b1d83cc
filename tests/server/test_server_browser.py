"""The web catalogue in a real browser: Debian's chromium driven by Playwright against a
running server. Sign in with a token, browse with the facets, open a joint (k, c ± σ, verdict,
conditions in engineering units, interactive plots, versions, downloads), overlay two versions,
label and deprecate through the forms (confirmation, undo, CSRF), run the nearest-joint form.
Every page is loaded at 1400 px width: no horizontal scroll, no "None", and a screenshot in a
folder the test prints."""

from __future__ import annotations

import json

import pytest

from server_helpers import joint_upload
from web_helpers import ARGS, CHROMIUM, WIDTH, Shots

pytestmark = pytest.mark.skipif(CHROMIUM is None, reason="chromium is not installed (apt-get install chromium; "
                                                         ".ci/run installs it)")
sync_api = pytest.importorskip("playwright.sync_api", reason="the playwright package is not installed")


@pytest.fixture(scope="module")
def browser():
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        yield b
        b.close()


def _catalogue(server, tmp_path):
    """Two synthetic versions of HSK63-A and one HSK63-B (API), two identified bundled campaigns."""
    from importlib import resources

    from jointdb import usecases

    with server.client("writer") as c:
        for name, torque, k in (("HSK63-A", 30.0, 1e6), ("HSK63-B", 50.0, 2e6), ("HSK63-A", 30.0, 1.4e6)):
            assert c.post("/api/v1/catalogue", json=joint_upload(tmp_path, name, torque=torque, k=k)).status_code == 201
    camps = resources.files("jointdb").joinpath("data", "catalogue", "campaigns")
    with server.repo() as repo:
        for camp in ("hs-hsk-a63-18kn", "th-er32-carbide-080nm"):
            usecases.catalogue_campaign(repo, camps.joinpath(camp, "campaign.json"), author="writer-owner")


def _rows(page) -> int:
    return page.locator("#joints tr").count() - 1


def _filter(page, server, **fields) -> int:
    page.goto(f"{server.url}/ui/joints")
    for key, value in fields.items():
        if key in ("type", "taper", "label", "state"):
            page.select_option(f"#f-{key}", value)
        elif key == "material":
            page.check(f"#f-materials input[value='{value}']")
        else:
            page.fill(f"#f-{key.replace('_', '-')}", value)
    page.click("#apply")
    page.wait_for_load_state()
    return _rows(page)


@pytest.mark.parametrize("server", ["sqlite"], indirect=True)
def test_catalogue_pages_in_a_browser(server, browser, tmp_path):
    _catalogue(server, tmp_path)
    page = browser.new_page(viewport={"width": WIDTH, "height": 900})
    errors = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" and "status of 422" not in m.text else None)
    shots = Shots(page, tmp_path / "screenshots")
    page.goto(f"{server.url}/")
    assert page.url.endswith("/ui/signin")  # / leads to the catalogue, which needs a token by default
    shots.check("signin")
    page.fill("#token", server.tokens["writer"])
    page.click("#signin")
    page.wait_for_url("**/ui/joints")
    assert server.tokens["writer"] not in page.url
    cookie = [c for c in page.context.cookies() if c["name"] == "jointdb_session"][0]
    assert cookie["httpOnly"] and cookie["sameSite"] == "Strict"
    assert page.evaluate("document.cookie") == ""  # not readable by scripts
    assert _rows(page) == 4
    text = shots.check("catalogue")
    assert "18" in page.inner_text("#joints tr:has-text('hs-hsk-a63-18kn')") and "8000.0" not in text

    # facets: lists built from the data, ranges in engineering units
    assert page.locator("#f-type option").all_inner_texts() == ["any", "holder-spindle", "tool-holder"]
    assert page.locator("#f-taper option").all_inner_texts() == ["any", "HSK-A63"]
    assert _filter(page, server, type="tool-holder", torque_min="40") == 2  # HSK63-B (50), carbide 80 N·m
    assert _filter(page, server, force_min="15", force_max="20") == 1  # the 18 kN drawbar force
    assert _filter(page, server, diameter_min="11", diameter_max="13") == 1  # the 12 mm shank
    assert _filter(page, server, taper="HSK-A63") == 1
    shots.check("catalogue-filtered")
    page.goto(f"{server.url}/ui/joints?material=stell&type=tool-holder")  # a typo: a message, the form kept
    assert "stell" in page.inner_text("#error") and page.locator("#filter").count() == 1
    assert page.locator("#f-type").input_value() == "tool-holder"
    shots.check("catalogue-unknown-material")

    # an identified joint: k, c ± σ with units, the verdict, conditions, interactive plots
    page.goto(f"{server.url}/ui/joints/hs-hsk-a63-18kn")
    page.wait_for_selector(".plot .uplot canvas")
    kc = page.inner_text("#kc")
    assert "N/m" in kc and "N·m/rad" in kc and "N·s/m" in kc and "±" in kc
    assert page.inner_text("#verdict").startswith("Quality verdict")
    cond = page.inner_text("#conditions")
    assert "drawbar force\t18 kN" in cond and "HSK-A63" in cond and "taper diameter\t63 mm" in cond
    specs = [json.loads(t) for t in page.locator("script.plot-data").all_inner_texts()]
    assert {s["id"] for s in specs} >= {"frf-phase", "k-translation", "c-translation", "k-rotation", "c-rotation"}
    for s in specs:  # units on every axis
        assert s["x"] == "frequency [Hz]" and "[" in s["y"], s["y"]
    assert page.locator(".plot .uplot").count() == len(specs)
    _hover_zoom_and_log(page)
    shots.check("joint")

    page.goto(f"{server.url}/ui/joints/HSK63-A")
    page.wait_for_selector(".plot .uplot canvas")
    assert "v2" in page.inner_text("#joint-name") and page.locator("#versions tr").count() == 3
    assert "not recorded" in page.inner_text("#kc")  # no σ without an identification record: said, not faked
    shots.check("joint-uploaded")
    with page.expect_download() as dl:
        page.click("#dl-csv")
    assert dl.value.suggested_filename == "HSK63-A-v2.csv"

    page.click("a.diff-link")
    page.wait_for_selector(".plot .uplot canvas")
    specs = [json.loads(t) for t in page.locator("script.plot-data").all_inner_texts()]
    mag = [s for s in specs if s["id"].startswith("frf-mag")][0]
    assert len({x["colour"] for x in mag["series"]}) == 2  # one colour per version ...
    assert len({json.dumps(x["dash"]) for x in mag["series"]}) == 1  # ... one line style per DOF
    phase = [s for s in specs if s["id"] == "frf-phase"][0]
    assert len({json.dumps(x["dash"]) for x in phase["series"]}) == 2 and len(phase["series"]) == 4
    diff = page.inner_text("#diff")  # the constant k refitted from each stored FRF: the uploads' 1e6 and 1.4e6 N/m
    assert "k 3x\t1 × 10⁶ N/m" in diff and "1.4 × 10⁶ N/m" in diff and page.locator("#provenance tr").count() > 3
    shots.check("overlay")

    _label_and_deprecate(page, server, shots)

    page.goto(f"{server.url}/ui/nearest?joint_type=tool-holder&materials=stel&torque_nm=40")  # a typo: the form stays
    assert "'stel'" in page.inner_text("#error") and page.input_value("#q-torque") == "40"
    shots.check("nearest-unknown-material")
    page.goto(f"{server.url}/ui/nearest")
    shots.check("nearest-form")
    page.select_option("#q-type", "holder-spindle")
    page.select_option("#q-materials", "steel + steel")
    page.fill("#q-force", "20")
    page.select_option("#q-diameter-key", "taper_diameter_m")
    page.fill("#q-diameter", "63")
    page.click("#search")
    page.wait_for_selector("#matches")
    first = page.inner_text("#matches tr:nth-child(2)")
    assert "hs-hsk-a63-18kn" in first and "\t18\t" in first  # the drawbar force in kN, not "torque None"
    assert "taper diameter" in first
    shots.check("nearest")
    assert not errors, errors
    assert len(list(shots.folder.glob("*.png"))) == len(shots.names) >= 10


def _hover_zoom_and_log(page) -> None:
    """The first plot reads out frequency and value under the cursor, zooms on a drag, switches to log x."""
    over = page.locator(".plot .u-over").first
    over.scroll_into_view_if_needed()
    box = over.bounding_box()
    page.mouse.move(box["x"] + box["width"] * 0.4, box["y"] + box["height"] * 0.4)
    page.mouse.move(box["x"] + box["width"] * 0.5, box["y"] + box["height"] * 0.5, steps=4)
    for _ in range(50):  # the legend follows the cursor on the next animation frame
        legend = page.locator(".plot .u-legend").first.inner_text()
        if " Hz" in legend:
            break
        page.wait_for_timeout(100)
    assert " Hz" in legend and "m/N" in legend, legend
    before = page.evaluate("jointdbPlots.instances[0].chart.scales.x.max - jointdbPlots.instances[0].chart.scales.x.min")
    page.mouse.move(box["x"] + box["width"] * 0.3, box["y"] + 20)
    page.mouse.down()
    page.mouse.move(box["x"] + box["width"] * 0.6, box["y"] + 40, steps=5)
    page.mouse.up()
    after = page.evaluate("jointdbPlots.instances[0].chart.scales.x.max - jointdbPlots.instances[0].chart.scales.x.min")
    assert after < 0.5 * before, (before, after)
    holder = page.locator(".plot").first
    assert holder.get_attribute("data-xlog") == "0"
    holder.locator("button.xlog").click()
    assert holder.get_attribute("data-xlog") == "1" and holder.locator(".uplot canvas").count() == 1


def _label_and_deprecate(page, server, shots) -> None:
    """Label and deprecate through a confirmation page, each undone with one click."""
    page.goto(f"{server.url}/ui/joints/th-er32-carbide-080nm")
    page.fill("#label-name", "released")
    page.click("#label")
    assert "a new label" in page.inner_text("#question")
    shots.check("confirm-label")
    assert server.repo().get("th-er32-carbide-080nm").labels == ()  # nothing written before confirming
    page.click("#confirm")
    page.wait_for_selector("#notice")
    assert server.repo().get("th-er32-carbide-080nm").labels == ("released",)
    shots.check("labelled")
    page.click("#undo")
    page.wait_for_selector("#notice")
    assert server.repo().get("th-er32-carbide-080nm").labels == ()
    page.fill("#deprecate-reason", "worn collet")
    page.click("#deprecate")
    page.click("#confirm")
    page.wait_for_selector("#undo")
    assert server.repo().get("th-er32-carbide-080nm").state == "deprecated"
    page.click("#undo")
    page.wait_for_selector("#notice")
    assert server.repo().get("th-er32-carbide-080nm").state == "active"
    audit = page.inner_text("#audit")
    assert "released" in audit and "worn collet" in audit and "undone" in audit and "removed" in audit
    shots.check("after-undo")
    # a forged form (wrong CSRF token) writes nothing, confirmed or not
    status = page.evaluate("""async () => (await fetch('/ui/joints/HSK63-B/deprecate', {method: 'POST',
        headers: {'Content-Type': 'application/x-www-form-urlencoded'}, body: 'csrf=forged&confirm=1&reason=x'})).status""")
    assert status == 422 and server.repo().get("HSK63-B").state == "active"
