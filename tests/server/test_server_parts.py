"""The parts API (issue 21, item 2; contract-21): list / versions / one record / catalogue (JSON and
multipart) / labels, with reader and writer roles, hostile inputs answered with one-line 4xx, the
client (RemoteRepository) over it, and POST /predict assembling a stack from catalogued parts."""

from __future__ import annotations

import base64
import json
from pathlib import Path

import numpy as np
from server_helpers import one_line_4xx as _one_line_4xx

ROOT = Path(__file__).resolve().parents[2]
DEMO = json.loads((ROOT / "jointdb" / "data" / "catalogue" / "demo-stack.json").read_text())
EXPLICIT = {"tool-holder": {"k": [8e7, 6e5], "c": [120.0, 4.0]}, "holder-spindle": {"k": [3e8, 2e6], "c": [300.0, 9.0]}}
API = "/api/v1"


def _nose_frf(node: int = 7):
    from jointdb.fe import model_from_dict
    from jointdb.frf import Dof

    frf = model_from_dict(DEMO["spindle"]["model"]).frf(np.arange(50.0, 3000.0 + 1e-9, 25.0), ["nose"],
                                                         directions=("x", "y", "rx", "ry"))
    return frf.replace(outputs=tuple(Dof(node, d.direction) for d in frf.outputs),
                       inputs=tuple(Dof(node, d.direction) for d in frf.inputs))


def test_catalogue_list_show_and_label_over_http(server):
    holder = {"name": "er32-hsk63", "kind": "holder", "payload": DEMO["holder"],
              "attributes": {"family": "ER32", "taper": "HSK-A63", "bore_mm": 12}}
    with server.client("reader") as c:
        assert _one_line_4xx(c.post(f"{API}/parts", json=holder), 403)
    with server.client() as c:
        _one_line_4xx(c.post(f"{API}/parts", json=holder), 401)
    with server.client("writer") as c:
        r = c.post(f"{API}/parts", json=holder)
        assert r.status_code == 201, r.text
        assert r.json()["author"] == "writer-owner" and r.json()["identical"] is False
        r = c.post(f"{API}/parts", json=holder)
        assert r.status_code == 200 and r.json()["identical"] is True and r.json()["version"] == 1
        r = c.post(f"{API}/parts", json={"name": "em12", "kind": "tool", "payload": DEMO["tool"]})
        assert r.status_code == 201, r.text
        r = c.post(f"{API}/parts", json={"name": "mill-spindle", "kind": "spindle", "payload": DEMO["spindle"],
                                         "attributes": {"machine": "demo-mill"}, "label": "released"})
        assert r.status_code == 201, r.text
        r = c.post(f"{API}/parts/er32-hsk63/1/labels", json={"label": "released"})
        assert r.status_code == 200 and r.json()["labels"] == ["released"]
    with server.client("reader") as c:
        items = c.get(f"{API}/parts", params={"kind": "holder", "family": "ER32"}).json()["items"]
        assert [(p["name"], p["version"], p["attributes"]["bore_mm"]) for p in items] == [("er32-hsk63", 1, 12.0)]
        assert "payload" not in items[0]
        assert items[0]["geometry"] == {"length_mm": 70.0, "bore_mm": 12.0, "mouth_diameter_mm": 32.0,
                                        "material": "steel"}  # the demo holder: 40 + 30 mm, Ø32 mouth, Ø12 bore
        spindles = c.get(f"{API}/parts", params={"machine": "demo-mill"}).json()["items"]
        assert [p["name"] for p in spindles] == ["mill-spindle"]
        versions = c.get(f"{API}/parts/er32-hsk63").json()
        assert versions["kind"] == "holder" and [v["version"] for v in versions["items"]] == [1]
        one = c.get(f"{API}/parts/er32-hsk63/released").json()
        assert one["payload"] == DEMO["holder"] and one["record_sha256"]
        assert c.get(f"{API}/parts/mill-spindle/1").json()["payload"]["point"] == "nose"
        assert "no part named" in _one_line_4xx(c.get(f"{API}/parts/nope"), 404)
        _one_line_4xx(c.get(f"{API}/parts/er32-hsk63/7"), 404)
        _one_line_4xx(c.get(f"{API}/parts/er32-hsk63/1/frf"), 404)  # a holder has no FRF set
        _one_line_4xx(c.get(f"{API}/parts", params={"kind": "bearing"}), 422)


def test_measured_spindle_as_json_file_and_multipart(server, tmp_path):
    from jointdb.io import frf_from_json, write_frf_hdf5

    frf = _nose_frf()
    path = tmp_path / "nose.h5"
    write_frf_hdf5(path, frf)
    body = {"name": "ms-json", "kind": "spindle", "payload": {"node": 7}, "attributes": {"machine": "m1"},
            "filename": "nose.h5", "file_b64": base64.b64encode(path.read_bytes()).decode()}
    with server.client("writer") as c:
        r = c.post(f"{API}/parts", json=body)
        assert r.status_code == 201, r.text
        assert r.json()["measured"] and r.json()["provenance"]["input_files"]["nose.h5"]
        r = c.post(f"{API}/parts", data={"name": "ms-form", "kind": "spindle", "node": "7",
                                         "attributes": json.dumps({"machine": "m2"})},
                   files={"frf": ("nose.h5", path.read_bytes(), "application/x-hdf5")})
        assert r.status_code == 201, r.text
        assert r.json()["blob_sha256"] == c.get(f"{API}/parts/ms-json/1").json()["blob_sha256"]  # one blob
    with server.client("reader") as c:
        back = frf_from_json(c.get(f"{API}/parts/ms-form/1/frf").json())
    assert np.array_equal(back.values, frf.values) and np.array_equal(back.freq, frf.freq)


def test_hostile_part_requests_are_one_line_4xx_and_write_nothing(server, tmp_path):
    good = {"name": "hostile-target", "kind": "tool", "payload": DEMO["tool"]}
    deep = '{"a":' * 1000 + "1" + "}" * 1000
    with server.client("writer") as c:
        h = {"content-type": "application/json"}
        raw = json.dumps({**good, "payload": "__HOLE__"}).replace('"__HOLE__"', deep)
        assert "nested" in _one_line_4xx(c.post(f"{API}/parts", content=raw, headers=h), 422)
        mid = '{"a":' * 70 + "1" + "}" * 70  # under the body's depth limit, over the stored field's
        raw = json.dumps({**good, "payload": {**DEMO["tool"], "x": "__HOLE__"}}).replace('"__HOLE__"', mid)
        _one_line_4xx(c.post(f"{API}/parts", content=raw, headers=h), 422)
        msg = _one_line_4xx(c.post(f"{API}/parts", json={
            "name": "s-path", "kind": "spindle", "payload": {"model": "/etc/passwd", "point": "nose"},
            "attributes": {"machine": "m"}}), 422)
        assert "root:" not in msg
        for bad in ("../nose.h5", "a/b.h5", ".hidden.h5", "nose.json", "C:\\x.h5"):
            body = {"name": "s-up", "kind": "spindle", "payload": {"node": 7}, "attributes": {"machine": "m"},
                    "filename": bad, "file_b64": base64.b64encode(b"x").decode()}
            assert "file" in _one_line_4xx(c.post(f"{API}/parts", json=body), 422)
        body = {"name": "s-up", "kind": "spindle", "payload": {"node": 7}, "attributes": {"machine": "m"},
                "filename": "nose.h5", "file_b64": base64.b64encode(b"not hdf5").decode()}
        msg = _one_line_4xx(c.post(f"{API}/parts", json=body), 422)
        assert "jointdb-part-" not in msg and "/tmp" not in msg
        _one_line_4xx(c.post(f"{API}/parts", json={**body, "file_b64": "@@@"}), 422)
        _one_line_4xx(c.post(f"{API}/parts", json={**good, "name": "../x"}), 422)
        _one_line_4xx(c.post(f"{API}/parts", json={**good, "name": "a@1"}), 422)
        _one_line_4xx(c.post(f"{API}/parts", json={**good, "kind": "bearing"}), 422)
        _one_line_4xx(c.post(f"{API}/parts", json={**good, "surprise": 1}), 422)
        _one_line_4xx(c.post(f"{API}/parts", json=[1, 2]), 422)
        _one_line_4xx(c.post(f"{API}/parts", content=b"\xff\xfe", headers=h), 422)
        _one_line_4xx(c.post(f"{API}/parts", json={**good, "payload": {**DEMO["tool"], "segments": [
            {"length": 1e300, "diameter": 0.012}]}}), 422)
        _one_line_4xx(c.post(f"{API}/parts", json={**good, "attributes": {"machine": "m"}}), 422)
        _one_line_4xx(c.post(f"{API}/parts", data={"name": "f", "kind": "tool", "evil": "1"}), 422)
        _one_line_4xx(c.post(f"{API}/parts", data={"name": "f", "kind": "tool", "payload": deep}), 422)
        _one_line_4xx(c.post(f"{API}/parts/hostile-target/1/labels", json={"label": "has space"}), 422)
        _one_line_4xx(c.post(f"{API}/parts/nope/1/labels", json={"label": "ok"}), 404)
        big = b'{"name": "' + b"x" * (65 * 2**20) + b'"}'
        assert "limit" in _one_line_4xx(c.post(f"{API}/parts", content=big, headers=h), 413)
    with server.client("reader") as c:
        names = [p["name"] for p in c.get(f"{API}/parts").json()["items"]]
    assert not any(n in names for n in ("hostile-target", "s-path", "s-up", "f"))
    text = server.log_text()
    assert "Traceback" not in text
    assert all(json.loads(line)["status"] < 500 for line in text.splitlines() if line.startswith('{"event": "request"'))


def test_client_and_predict_from_parts(server):
    from jointdb import usecases
    from jointdb.client import RemoteRepository
    from jointdb.io import frf_from_json

    with RemoteRepository(server.url, server.tokens["writer"]) as remote:
        remote.add_part("c-tool", "tool", DEMO["tool"])
        remote.add_part("c-holder", "holder", DEMO["holder"], attributes={"family": "ER32"})
        part = remote.add_part("c-spindle", "spindle", {"node": 7}, frf=_nose_frf(), attributes={"machine": "m3"})
        remote.label_part("c-spindle", 1, "released")
        assert remote.resolve_part("c-spindle@released").record_sha256 == part.record_sha256
        assert np.array_equal(remote.load_part_frf(part).values, _nose_frf().values)
        assert "c-holder" in [p.name for p in remote.list_parts("holder", family="ER32")]
        doc = {**DEMO, "interfaces": EXPLICIT, "frequency": {"min": 50.0, "max": 3000.0, "step": 25.0},
               "tool": {"part": "c-tool@1"}, "holder": {"part": "c-holder@1"}, "spindle": {"part": "c-spindle@released"}}
        local = usecases.predict_stack(usecases.stack_from_document(doc, remote), remote).prediction
    with server.client("reader") as c:
        r = c.post(f"{API}/predict", json={"stack": doc})
        assert r.status_code == 200, r.text
    out = r.json()
    assert [p["part"] for p in out["parts"]] == ["c-tool@1", "c-holder@1", "c-spindle@1"]
    assert np.array_equal(frf_from_json(out["tip_frf"]).values, local.tip.values)


def test_cli_parts_against_the_server(server, tmp_path):
    import os
    import subprocess
    import sys

    env = {**os.environ, "JOINTDB_TOKEN": server.tokens["writer"]}

    def cli(*args):
        out = subprocess.run([sys.executable, "-m", "jointdb", "--server", server.url, *map(str, args)],
                             capture_output=True, text=True, env=env, timeout=120)
        return out.returncode, out.stdout, out.stderr

    stack = ROOT / "jointdb" / "data" / "catalogue" / "demo-stack.json"
    rc, out, err = cli("parts", "add", "holder", "cli-holder", "--from-stack", stack, "--family", "ER16", "--json")
    assert rc == 0, err
    assert json.loads(out)["author"] == "writer-owner"  # the token's owner, whatever the client says
    rc, out, err = cli("parts", "label", "cli-holder@1", "released")
    assert rc == 0, err
    rc, out, err = cli("parts", "list", "--family", "ER16", "--json")
    assert rc == 0 and [(p["name"], p["labels"]) for p in json.loads(out)] == [("cli-holder", ["released"])]
    rc, out, err = cli("parts", "show", "cli-holder@released", "--json")
    assert rc == 0 and json.loads(out)["payload"] == DEMO["holder"]
    rc, out, err = cli("parts", "show", "no-such-part")
    assert rc != 0 and err.startswith("error:") and "no part named" in err and "Traceback" not in err
