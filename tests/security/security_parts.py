"""Hostile requests to the parts API (issue 21): names, payloads, files, nesting, roles, server paths.

Each request is refused with a 4xx (or, where legitimate in form, answered below 500); nothing in
an answer may name a server directory or the content of a server file (checked by the suite)."""

from __future__ import annotations

import base64
import copy
import json
from pathlib import Path

from security_attacks import API, NAMES, STRINGS, _nested
from security_run import JSON, Attack, json_body

_STACK = json.loads((Path(__file__).resolve().parents[2] / "jointdb" / "data" / "catalogue" /
                     "demo-stack.json").read_text())


def _part(**over) -> dict:
    body = {"name": "SEC-PART", "kind": "holder", "payload": copy.deepcopy(_STACK["holder"]),
            "attributes": {"family": "ER32"}}
    body.update(over)
    return body


def parts(target) -> list[Attack]:
    out = []
    post = f"{API}/parts"
    for what, s in STRINGS.items():  # hostile text as the name, an attribute, the label
        for field, body in (("name", _part(name=s)), ("family", _part(attributes={"family": s})),
                            ("label", _part(name=f"SEC-LBL-{len(out)}", label=s))):
            expect = "4xx" if field in ("name", "label") or what in ("NUL", "lone surrogate", "control characters",
                                                                      "CRLF", "100k characters") else "ok"
            out.append(Attack("parts", f"{what} as part {field}", "POST", post, "writer", JSON, json_body(body),
                              expect=expect))
    for depth in (100, 1000):
        raw = json_body(_part(payload="__HOLE__")).replace(b'"__HOLE__"', _nested(depth).encode())
        out.append(Attack("deep nesting", f"part payload nested {depth}", "POST", post, "writer", JSON, raw))
    for what, path in {"/etc/passwd": "/etc/passwd", "traversal": "../../../../etc/passwd",
                       "server fixture": str(Path(target.campaign_dir).parents[1] / "stacks" / "parts" /
                                             "spindle-two-bearings.json")}.items():
        body = {"name": "SEC-SP", "kind": "spindle", "payload": {"model": path, "point": "nose"},
                "attributes": {"machine": "m"}}
        out.append(Attack("server paths in requests", f"part spindle model = {what}", "POST", post, "writer", JSON,
                          json_body(body)))
        s = copy.deepcopy(_STACK)
        s["spindle"] = {"part": f"{path}@1"}
        out.append(Attack("server paths in requests", f"predict spindle part = {what}", "POST", f"{API}/predict",
                          "reader", JSON, json_body({"stack": s})))
    for fname in ("../nose.h5", "/etc/passwd", "a/b.uff", ".x.h5", "nose.json", "nose.h5\x00.txt"):
        body = {"name": "SEC-UP", "kind": "spindle", "payload": {"node": 7}, "attributes": {"machine": "m"},
                "filename": fname, "file_b64": base64.b64encode(b"58\n").decode()}
        out.append(Attack("file names and encodings", f"part FRF file name {fname[:20]!r}", "POST", post, "writer",
                          JSON, json_body(body)))
    for what, data in {"not HDF5": b"hello", "not UFF": b"    -1\n  58\n garbage\n", "empty": b""}.items():
        name = "nose.uff" if "UFF" in what else "nose.h5"
        body = {"name": "SEC-UP", "kind": "spindle", "payload": {"node": 7}, "attributes": {"machine": "m"},
                "filename": name, "file_b64": base64.b64encode(data).decode()}
        out.append(Attack("HDF5 files", f"part FRF file {what}", "POST", post, "writer", JSON, json_body(body)))
    for n in NAMES:
        for route in (f"/parts/{n}", f"/parts/{n}/1", f"/parts/{n}/released", f"/parts/{n}/1/frf"):
            # as for joints: a name that normalises to another path may be redirected; any answer below 500
            out.append(Attack("path traversal and names", f"part {n[:24]}", "GET", f"{API}{route}", expect="ok"))
        out.append(Attack("path traversal and names", f"label part {n[:24]}", "POST", f"{API}/parts/{n}/1/labels",
                          "writer", JSON, json_body({"label": "x"})))
    for role in ("reader", None):
        out.append(Attack("authorisation", f"{role} catalogues a part", "POST", post, role, JSON, json_body(_part())))
        out.append(Attack("authorisation", f"{role} labels a part", "POST", f"{API}/parts/SEC-PART/1/labels", role,
                          JSON, json_body({"label": "x"})))
    boundary = "jdbBOUNDARY"
    form = (f"--{boundary}\r\nContent-Disposition: form-data; name=\"name\"\r\n\r\nSEC-FORM\r\n"
            f"--{boundary}\r\nContent-Disposition: form-data; name=\"kind\"\r\n\r\nspindle\r\n"
            f"--{boundary}\r\nContent-Disposition: form-data; name=\"node\"\r\n\r\n7\r\n"
            f"--{boundary}\r\nContent-Disposition: form-data; name=\"frf\"; filename=\"../../etc/passwd\"\r\n"
            f"Content-Type: application/octet-stream\r\n\r\nroot:x:0:0\r\n--{boundary}--\r\n").encode()
    out.append(Attack("file names and encodings", "multipart part FRF named ../../etc/passwd", "POST", post, "writer",
                      [("Content-Type", f"multipart/form-data; boundary={boundary}")], form))
    out.append(Attack("file names and encodings", "multipart with too many files", "POST", post, "writer",
                      [("Content-Type", f"multipart/form-data; boundary={boundary}")],
                      b"".join(f"--{boundary}\r\nContent-Disposition: form-data; name=\"frf\"; filename=\"{i}.h5\""
                               f"\r\n\r\nx\r\n".encode() for i in range(5)) + f"--{boundary}--\r\n".encode()))
    return out
