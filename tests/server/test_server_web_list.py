"""The catalogue page ``/ui/joints`` pages by keyset like the API (one page of the listing per
request, the total shown, a ``next`` link that continues after the last name) and reads its
facets in SQL, equal to the facets of the whole listing; diameter and taper filters still work
(they scan the listing)."""

from __future__ import annotations

import re

import pytest
from server_helpers import _load, _STORE

from jointdb.store import Conditions, Repository

_h = _load("jointdb_store_helpers", _STORE / "store_helpers.py")
KIND = "spring-damper-planar"


@pytest.fixture
def app(tmp_path, monkeypatch):
    from jointdb.server import Settings, create_app, web_catalogue

    monkeypatch.setattr(web_catalogue, "PAGE", 4)
    repo = Repository(tmp_path / "web.sqlite")
    for i in range(10):
        extra = {"taper": "HSK-A63" if i % 2 else "SK40"}
        cond = Conditions(materials=["tungsten-carbide", "steel"] if i % 3 else ["steel", "steel"],
                          torque_nm=10.0 + i, geometry={"shank_diameter_m": 0.01 + 0.001 * i}, extra=extra)
        repo.catalogue(f"W{i}", "tool-holder" if i < 7 else "holder-spindle", _h.spring_joint(), cond, KIND)
    repo.label("W3", 1, "released")
    repo.deprecate("W9", None, reason="test")
    yield create_app(Settings(bind_host="127.0.0.1", open_reads=True), repo=repo), repo
    repo.close()


def _names(html: str) -> list[str]:
    return re.findall(r'<a href="/ui/joints/(W\d)">', html)


def test_the_list_pages_by_keyset_with_the_total(app):
    asgi, repo = app
    from fastapi.testclient import TestClient

    with TestClient(asgi) as c:
        seen, url, pages = [], "/ui/joints", 0
        while url:
            r = c.get(url)
            assert r.status_code == 200, r.text
            assert re.search(r'id="count">10 joints', r.text), r.text[:2000]
            seen += _names(r.text)
            m = re.search(r'href="([^"]+)" id="next"', r.text)
            url = m.group(1).replace("&amp;", "&") if m else None
            pages += 1
        assert seen == [f"W{i}" for i in range(10)] and pages == 3
        assert 'id="first"' in c.get("/ui/joints", params={"offset": 4}).text
        typed = c.get("/ui/joints", params={"type": "holder-spindle"}).text
        assert _names(typed) == ["W7", "W8", "W9"] and 'id="count">3 joints' in typed
        taper = c.get("/ui/joints", params={"taper": "SK40", "diameter_max": "15.5"}).text  # scanned filters
        assert _names(taper) == ["W0", "W2", "W4"]


def test_the_facets_read_in_sql_equal_those_of_the_whole_listing(app):
    asgi, repo = app
    from jointdb.server._deps import version_json
    from jointdb.server.web_catalogue import _catalogue_facets

    versions = [version_json(v) for v in repo.list_page(limit=None).items]
    c = [v["conditions"] for v in versions]
    expected = {"types": sorted({v["joint_type"] for v in versions}),
                "materials": sorted({m for x in c for m in x["materials"]}),
                "tapers": sorted({x["extra"]["taper"] for x in c}),
                "labels": sorted({lab for v in versions for lab in v["labels"]}),
                "combos": sorted({" + ".join(x["materials"]) for x in c})}
    assert _catalogue_facets(repo) == expected
    assert expected["labels"] == ["released"] and len(expected["combos"]) == 2
    repo.label("W4", 1, "golden")  # a write: the cached facets are read again
    assert _catalogue_facets(repo)["labels"] == ["golden", "released"]
