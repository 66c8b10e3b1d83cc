"""Listing through the API against a running server (SQLite and PostgreSQL): hostile records are
refused before the write, a damaged version is reported and the rest of the list still answers,
NUL in a filter is a 422, and the keyset cursor walks the whole catalogue."""

from __future__ import annotations

import pytest
from server_helpers import _load, _STORE, joint_upload

_store_helpers = _load("jointdb_store_helpers", _STORE / "store_helpers.py")
alter_version_row, nested_dict = _store_helpers.alter_version_row, _store_helpers.nested_dict


def _one_line(r, low=400, high=500) -> str:
    assert low <= r.status_code < high, (r.status_code, r.text)
    msg = r.json()["error"]
    assert msg and "\n" not in msg and "Traceback" not in msg
    return msg


@pytest.fixture(scope="module")
def listed(server, tmp_path_factory):
    tmp = tmp_path_factory.mktemp("uploads")
    with server.client("writer") as c:
        for i in range(7):
            r = c.post("/api/v1/catalogue", json=joint_upload(tmp, f"L-{i}", torque=10.0 + i))
            assert r.status_code == 201, r.text
    server.tmp = tmp
    return server


def test_nesting_300_is_a_422_and_commits_nothing(listed):
    with listed.client("writer") as c:
        body = joint_upload(listed.tmp, "L-0", torque=10.0)
        body["conditions"] = {"materials": ["tungsten-carbide", "steel"], "torque_nm": 10.0, "extra": nested_dict(300)}
        msg = _one_line(c.post("/api/v1/catalogue", json=body), 422, 423)
        assert "conditions.extra" in msg and "64" in msg
        assert [v["version"] for v in c.get("/api/v1/joints/L-0/history").json()["items"]] == [1]
        page = c.get("/api/v1/joints", params={"q": "L-"})
        assert page.status_code == 200 and page.json()["total"] == 7


@pytest.mark.parametrize("params", [{"label": "\x00"}, {"q": "a\x00b"}, {"type": "\x00"}, {"material": "\x00"}])
def test_nul_in_a_filter_is_a_422(listed, params):
    with listed.client("reader") as c:
        _one_line(c.get("/api/v1/joints", params=params), 422, 423)
        _one_line(c.get("/api/v1/joints/L-1", params={"label": "\x00"}), 422, 423)


def test_the_cursor_walks_every_joint_once(listed):
    with listed.client("reader") as c:
        seen, cursor, pages = [], None, 0
        while True:
            params = {"limit": 3, "q": "L-", **({"after": cursor} if cursor else {})}
            page = c.get("/api/v1/joints", params=params).json()
            assert page["total"] == 7 and page["damaged"] == []
            seen += [j["name"] for j in page["items"]]
            cursor, pages = page["next"], pages + 1
            if cursor is None:
                break
        assert seen == [f"L-{i}" for i in range(7)] and pages == 3
        assert _one_line(c.get("/api/v1/joints", params={"after": "%%%"}), 422, 423)
        f = c.get("/api/v1/joints", params={"torque_min": 12, "torque_max": 14, "q": "L-"}).json()
        assert [j["name"] for j in f["items"]] == ["L-2", "L-3", "L-4"]


def test_a_damaged_version_is_reported_and_the_rest_answers(listed):
    sql_value = "'{\"broken\": '" if listed.db.startswith("sqlite") else "'[1, 2]'"  # PG's json refuses non-JSON
    alter_version_row(listed.db, f"UPDATE joint_versions SET extra = {sql_value} "
                                 "WHERE joint_id = (SELECT id FROM joints WHERE name = 'L-5')")
    with listed.client("reader") as c:
        r = c.get("/api/v1/joints", params={"q": "L-"})
        assert r.status_code == 200, r.text
        page = r.json()
        assert [j["name"] for j in page["items"]] == [f"L-{i}" for i in range(7) if i != 5]
        assert [(d["name"], d["version"]) for d in page["damaged"]] == [("L-5", 1)]
        assert "L-5 v1" in _one_line(c.get("/api/v1/joints/L-5"), 400, 600)
        assert "L-5 v1" in _one_line(c.get("/api/v1/joints/L-5/versions/1"), 400, 600)
        hist = c.get("/api/v1/joints/L-5/history")
        assert hist.status_code == 200 and hist.json()["damaged"][0]["version"] == 1
        near = c.post("/api/v1/query/nearest", json={"joint_type": "tool-holder", "k": 7,
                                                     "conditions": {"torque_nm": 15.0}})
        assert near.status_code == 200, near.text
        assert "L-5" not in [m["name"] for m in near.json()["matches"]]
        assert any("L-5 v1" in w for w in near.json()["warnings"])
        for other in ("L-4", "L-6"):
            assert c.get(f"/api/v1/joints/{other}").status_code == 200


def test_the_client_reads_the_whole_list_by_cursor(listed, monkeypatch):
    """RemoteRepository.list_joints continues by the keyset cursor (each page costs the same), not
    by an offset that the database must skip."""
    from jointdb.client import RemoteRepository

    asked: list[dict] = []
    with RemoteRepository(listed.url, listed.tokens["reader"]) as remote:
        monkeypatch.setattr(remote, "PAGE", 3)
        call = remote._call

        def spy(method, path, **kw):
            if path == "/joints":
                asked.append(dict(kw.get("params") or {}))
            return call(method, path, **kw)

        monkeypatch.setattr(remote, "_call", spy)
        names = [v.name for v in remote.list_joints("tool-holder")]
    with listed.client("reader") as c:  # the same list in one page (a version damaged by another test is left out)
        whole = c.get("/api/v1/joints", params={"type": "tool-holder", "limit": 500}).json()["items"]
    assert names == [j["name"] for j in whole] and len(names) >= 6
    assert len(asked) >= 3 and "after" not in asked[0]
    assert all("after" in p and "offset" not in p for p in asked[1:]), asked


@pytest.mark.parametrize("params", [{"offset": 1000}, {"offset": 1000, "type": "tool-holder"}, {"offset": 1000, "q": "L-"}])
def test_a_page_past_the_end_is_empty_with_the_listings_total(listed, params):
    """Past the end the total is counted apart (from the maintained counts when no filter needs the
    rows): an integer in the JSON on both backends (PostgreSQL's SUM of a bigint is a numeric)."""
    with listed.client("reader") as c:
        r = c.get("/api/v1/joints", params=params)
        assert r.status_code == 200, r.text
        page = r.json()
        assert page["items"] == [] and page["next"] is None
        assert isinstance(page["total"], int) and page["total"] >= (7 if "q" in params else 0)
