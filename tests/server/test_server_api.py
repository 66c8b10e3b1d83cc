"""The API against a running server: reads, downloads with ETags, nearest/interpolate,
pagination, OpenAPI, and bad requests (4xx with a one-line reason, never a 500)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from server_helpers import joint_upload
from server_helpers import one_line_4xx as _one_line_4xx


@pytest.fixture(scope="module")
def catalogued(server, tmp_path_factory):
    tmp = tmp_path_factory.mktemp("uploads")
    with server.client("writer") as c:
        for i, torque in enumerate((20.0, 40.0, 60.0)):
            r = c.post("/api/v1/catalogue", json=joint_upload(tmp, f"TH-{i}", torque=torque, k=1e6 * (i + 1)))
            assert r.status_code == 201, r.text
        r = c.post("/api/v1/catalogue", json=joint_upload(tmp, "TH-0", torque=20.0, k=1.5e6))
        assert r.status_code == 201 and r.json()["version"] == 2
    return server


def test_reads_and_pagination(catalogued):
    with catalogued.client("reader") as c:
        page = c.get("/api/v1/joints", params={"limit": 2}).json()
        assert page["total"] == 3 and len(page["items"]) == 2 and page["next_offset"] == 2
        rest = c.get("/api/v1/joints", params={"limit": 2, "offset": 2}).json()
        assert [j["name"] for j in page["items"] + rest["items"]] == ["TH-0", "TH-1", "TH-2"]
        # after a cursor only the cursor continues: an offset would count from the start of the list
        one = c.get("/api/v1/joints", params={"limit": 1}).json()
        two = c.get("/api/v1/joints", params={"limit": 1, "after": one["next"]}).json()
        assert [j["name"] for j in two["items"]] == ["TH-1"] and two["next"] and two["next_offset"] is None
        f = c.get("/api/v1/joints", params={"torque_min": 30, "torque_max": 70, "material": "carbide"}).json()
        assert [j["name"] for j in f["items"]] == ["TH-1", "TH-2"]
        assert c.get("/api/v1/joints/TH-0").json()["version"] == 2
        v1 = c.get("/api/v1/joints/TH-0/versions/1").json()
        assert v1["conditions"]["torque_nm"] == 20.0 and v1["provenance"]["author"] == "writer-owner"
        hist = c.get("/api/v1/joints/TH-0/history").json()
        assert [v["version"] for v in hist["items"]] == [1, 2]
        d = c.get("/api/v1/joints/TH-0/diff", params={"a": 1, "b": 2}).json()
        assert d["same_blob"] is False and d["max_relative_difference"] > 0
        assert "/api/v1/joints" in c.get("/openapi.json").json()["paths"]


def test_download_formats_and_etags(catalogued):
    repo = catalogued.repo()
    frf = repo.load_frf(repo.get("TH-0", 1))
    with catalogued.client("reader") as c:
        for fmt in ("uff58", "hdf5", "csv", "json"):
            r = c.get("/api/v1/joints/TH-0/versions/1/frf", params={"format": fmt})
            assert r.status_code == 200, r.text
            tag = r.headers["etag"]
            assert tag.startswith('"') and not tag.startswith('W/')
            assert "immutable" in r.headers["cache-control"] and "max-age=31536000" in r.headers["cache-control"]
            again = c.get("/api/v1/joints/TH-0/versions/1/frf", params={"format": fmt},
                          headers={"If-None-Match": tag})
            assert again.status_code == 304 and again.content == b""
        body = c.get("/api/v1/joints/TH-0/versions/1/frf", params={"format": "json"}).json()
        values = np.asarray(body["real"]) + 1j * np.asarray(body["imag"])
        assert np.array_equal(values, frf.values) and np.array_equal(body["freq_hz"], frf.freq)
        assert body["units"][0][0] == "m/N"
        other = c.get("/api/v1/joints/TH-0/versions/2/frf", params={"format": "json"})
        assert other.headers["etag"] != c.get("/api/v1/joints/TH-0/versions/1/frf",
                                              params={"format": "json"}).headers["etag"]


def test_nearest_and_interpolate(catalogued):
    with catalogued.client("reader") as c:
        body = {"joint_type": "tool-holder", "conditions": {"materials": ["carbide", "steel"], "torque_nm": 45},
                "k": 3}
        r = c.post("/api/v1/query/nearest", json=body).json()
        names = [m["name"] for m in r["matches"]]
        assert names[0] == "TH-1" and len(names) == 3
        d = [m["distance"] for m in r["matches"]]
        assert d == sorted(d) and "torque_nm" in r["matches"][0]["per_condition"]
        ij = c.post("/api/v1/query/interpolate", json={**body, "k": 2}).json()
        assert ij["label"] == "interpolated" and {n["name"] for n in ij["neighbours"]} == {"TH-1", "TH-2"}
        assert abs(sum(n["weight"] for n in ij["neighbours"]) - 1) < 1e-12
        assert ij["passivity_moved"] == []  # spring-dampers are passive on every line: no weight moved


def test_bad_requests_are_4xx_with_one_line(catalogued, tmp_path):
    with catalogued.client("writer") as c:
        h = {"Content-Type": "application/json"}
        assert "malformed JSON" in _one_line_4xx(c.post("/api/v1/catalogue", content=b"{not json", headers=h), 422)
        assert "malformed JSON" in _one_line_4xx(c.post("/api/v1/query/nearest", content=b"[1,", headers=h), 422)
        _one_line_4xx(c.post("/api/v1/query/nearest", json={"joint_type": "tool-holder", "k": "many"}), 422)
        _one_line_4xx(c.post("/api/v1/query/nearest", json={"joint_type": "tool-holder",
                                                            "conditions": {"torque_nm": "tight"}}), 422)
        _one_line_4xx(c.post("/api/v1/query/nearest", json={"joint_type": "tool-holder",
                                                            "conditions": {"materials": ["unobtainium"]}}), 422)
        _one_line_4xx(c.post("/api/v1/query/nearest", json=[1, 2]), 422)
        _one_line_4xx(c.post("/api/v1/joints/TH-0/labels", json={"version": "two", "label": "x"}), 422)
        _one_line_4xx(c.post("/api/v1/joints/TH-0/labels", json={"version": 1, "label": "has space"}), 422)
        assert "no joint named" in _one_line_4xx(c.get("/api/v1/joints/NOPE"), 404)
        _one_line_4xx(c.get("/api/v1/joints/TH-0/versions/99"), 404)
        _one_line_4xx(c.get("/api/v1/joints/TH-0/versions/1/frf", params={"format": "xlsx"}), 422)
        _one_line_4xx(c.post("/api/v1/joints/NOPE/deprecate", json={}), 404)
        for bad in ("../etc/passwd", "a/b.h5", "..", ".hidden.h5", "C:\\x.h5", "joint.json", "x.tar"):
            body = joint_upload(tmp_path, "PATHY", filename=bad)
            assert "file" in _one_line_4xx(c.post("/api/v1/catalogue", json=body), 422)
        _one_line_4xx(c.get("/api/v1/joints/..%5C..%5Cx"))
        _one_line_4xx(c.post("/api/v1/catalogue", json={**joint_upload(tmp_path, "B64"), "file_b64": "@@@"}), 422)
        _one_line_4xx(c.post("/api/v1/catalogue", json={**joint_upload(tmp_path, "B64"),
                                                       "file_b64": "aGVsbG8="}), 422)  # not HDF5
        big = b'{"name": "' + b"x" * (65 * 2**20) + b'"}'
        assert "limit" in _one_line_4xx(c.post("/api/v1/catalogue", content=big, headers=h), 413)
    text = catalogued.log_text()
    assert "Traceback" not in text
    assert all(json.loads(line)["status"] < 500 for line in text.splitlines() if line.startswith('{"event": "request"'))


def test_campaign_archive_is_identified_by_the_server(catalogued, tmp_path):
    import base64
    import io as bytesio
    import zipfile
    from pathlib import Path

    root = Path(__file__).resolve().parents[2] / "fixtures" / "campaigns" / "th-steel-30nm"
    buf = bytesio.BytesIO()
    with zipfile.ZipFile(buf, "w") as zf:
        for p in sorted(root.iterdir()):
            zf.write(p, p.name)
    body = {"name": "CAMP-1", "filename": "th-steel-30nm.zip", "file_b64": base64.b64encode(buf.getvalue()).decode()}
    with catalogued.client("writer") as c:
        r = c.post("/api/v1/catalogue", json=body)
        assert r.status_code == 201, r.text
        v = r.json()
        assert v["conditions"]["torque_nm"] == 30.0 and v["provenance"]["method"].startswith(("irc", "output-error"))
        assert "campaign.json" in v["provenance"]["input_files"] and v["provenance"]["author"] == "writer-owner"
        evil = bytesio.BytesIO()
        with zipfile.ZipFile(evil, "w") as zf:
            zf.writestr("../escape.json", "{}")
        r = c.post("/api/v1/catalogue", json={**body, "file_b64": base64.b64encode(evil.getvalue()).decode()})
        assert r.status_code == 422 and "plain file name" in r.json()["error"]
        r = c.post("/api/v1/catalogue", json={**body, "file_b64": base64.b64encode(b"not a zip").decode()})
        assert r.status_code == 422 and "not a zip" in r.json()["error"]
    assert not (tmp_path.parent / "escape.json").exists()


def test_predict_and_lobes(catalogued):
    from pathlib import Path

    from jointdb import usecases
    from jointdb.stack import stack_from_dict

    stacks = Path(__file__).resolve().parents[2] / "fixtures" / "stacks"
    stack = json.loads((stacks / "endmill-catalogued-joint.json").read_text())
    stack["spindle"]["model"] = json.loads((stacks / stack["spindle"]["model"]).read_text())  # inline
    stack["interfaces"]["tool-holder"] = "rigid"
    stack["frequency"] = {"min": 100.0, "max": 3000.0, "step": 20.0}
    with catalogued.client("reader") as c:
        r = c.post("/api/v1/predict", json={"stack": stack})
        assert r.status_code == 200, r.text
        out = r.json()
        expected = usecases.predict_stack(stack_from_dict(stack), None).prediction.summary()
        assert [row["peak_hz"] for row in out["prediction"]] == [row["peak_hz"] for row in expected]
        tip = out["tip_frf"]
        assert tip["units"][0][0] == "m/N" and len(tip["freq_hz"]) == 146
        x = dict(tip)  # the JSON form of an FRF is accepted back as is
        lobes = c.post("/api/v1/lobes", json={"frf": x, "teeth": 4, "kt": 6e8, "kr": 2e8, "immersion": 0.5,
                                              "n_speeds": 40, "refine": 0})
        assert lobes.status_code == 200, lobes.text
        rows = lobes.json()["rows"]
        assert len(rows) == 40 and all(r["depth_m"] is None or r["depth_m"] > 0 for r in rows)
        stack["spindle"]["model"] = "parts/spindle-two-bearings.json"
        r = c.post("/api/v1/predict", json={"stack": stack})
        assert r.status_code == 422 and "inline" in r.json()["error"]
        r = c.post("/api/v1/lobes", json={"frf": x, "kt": 6e8})
        assert r.status_code == 422 and "kr" in r.json()["error"]
