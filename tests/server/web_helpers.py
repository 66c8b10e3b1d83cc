"""Helpers of the browser tests (imported by name): chromium for Playwright, and the 1400-px check
of a page (no horizontal scroll, no raw value such as "None", a screenshot in a named folder: under
the test's tmp_path, or under ``$JOINTDB_WEB_SCREENSHOTS`` when set)."""

from __future__ import annotations

import shutil

CHROMIUM = shutil.which("chromium")
ARGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update",
        "--disable-sync", "--no-first-run"]
WIDTH = 1400
#: Raw keys and Python values a page must never show.
RAW = ("None", "NaN", "undefined", "shank_diameter_m", "taper_diameter_m", "preload_n", "torque_nm", "JOINTDB_",
       "register_material")


class Shots:
    """Check a page at 1400 px (no horizontal scroll, no raw values) and keep its screenshot."""

    def __init__(self, page, folder):
        import os
        from pathlib import Path

        if os.environ.get("JOINTDB_WEB_SCREENSHOTS"):  # keep them (e.g. for docs/images/web)
            folder = Path(os.environ["JOINTDB_WEB_SCREENSHOTS"]) / folder.name
        self.page, self.folder, self.names = page, folder, []
        folder.mkdir(parents=True, exist_ok=True)
        print(f"screenshots: {folder}")

    def check(self, name: str) -> str:
        page = self.page
        page.wait_for_load_state("networkidle")
        width = page.evaluate("document.documentElement.scrollWidth")
        assert width <= WIDTH, f"{name}: the page is {width} px wide at a {WIDTH} px window"
        text = page.inner_text("body")
        for raw in RAW:
            assert raw not in text, f"{name}: shows {raw!r}"
        page.screenshot(path=str(self.folder / f"{len(self.names):02d}-{name}.png"), full_page=True)
        self.names.append(name)
        return text


def wait_visible(page, shown: str, error: str, timeout_ms: int = 120_000) -> None:
    """Wait until ``shown`` (or the page's ``error`` box) is visible; fail with the page's message."""
    page.wait_for_selector(f"{shown}:not([hidden]), {error}:not([hidden])", timeout=timeout_ms)
    assert not page.is_visible(error), page.inner_text(error)
