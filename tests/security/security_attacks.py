"""Hostile requests without archives: query and path parameters, JSON bodies, authentication
and authorisation, HTTP oddities. Each generator returns a list of :class:`Attack`; the
random choices are seeded, so a run is repeatable."""

from __future__ import annotations

import copy
import random
from urllib.parse import quote

from security_run import JSON, Attack, json_body

API = "/api/v1"

#: hostile text for string fields (JSON bodies)
STRINGS = {
    "NUL": "a\x00b", "control characters": "a\x01\x1b[31m\x7fb", "lone surrogate": "a\ud800b",
    "bidi override": "a\u202eb", "100k characters": "x" * 100_000, "SQL": "' OR '1'='1'; DROP TABLE joints;--",
    "path traversal": "../../../../etc/passwd", "absolute path": "/etc/passwd", "template": "{{7*7}}${7*7}",
    "markup": "<script>alert(1)</script>", "CRLF": "a\r\nX-Injected: 1", "emoji": "\U0001f529\u0301",
}
REFUSE_STRINGS = {"NUL", "lone surrogate"}  # the issue: nothing unreadable is stored

#: hostile text for query and path parameters (already percent-encoded)
PARAMS = ["%00", "a%00b", "%ff%fe", "%C0%AF", "x" * 10_000, "%F0%9F%94%A9", "'%20OR%201=1--", "%25",
          "nan", "inf", "-inf", "1e400", "-1", "99999999999999999999999", "%5B%5D", "%0d%0aX:%20y",
          "..%2f..%2fetc%2fpasswd"]

NAMES = ["..%2f..%2fetc%2fpasswd", "%2e%2e", "%2e%2e%2f", "%00", "SEC-A%00", "%ff", "x" * 5000, "%F0%9F%94%A9",
         quote("'; DROP TABLE joints;--", safe=""), "%252e%252e%252f", "SEC-A%2f..", "%20", "CON", "~root",
         "%5c..%5cwindows", "..%5c..%5c"]


def _catalogue(target, joint: str, **over) -> dict:
    """A valid catalogue request with the FRF as JSON (no file); ``over`` replaces fields."""
    body = {"name": joint, "frf": copy.deepcopy(target.frf), "joint_type": "tool-holder", "model_kind": "spring-damper-planar",
            "conditions": {"materials": ["tungsten-carbide", "steel"], "torque_nm": 40.0}}
    for k, v in over.items():
        body[k] = v
    return body


def _set(body: dict, where: str, value) -> dict:
    """Put ``value`` at ``where`` (a dotted path; ``[k]`` keys a dict, a trailing ``0`` a list)."""
    obj, *path, last = [body] + where.split(".")
    obj = body
    for p in path:
        obj = obj[int(p)] if isinstance(obj, list) else obj.setdefault(p, {})
    if isinstance(obj, list):
        obj[int(last)] = value
    else:
        obj[last] = value
    return body


def _nested(depth: int, leaf: str = "1", key: str = "a") -> str:
    return f'{{"{key}":' * depth + leaf + "}" * depth


def query_params(target) -> list[Attack]:
    out = []
    for p in ("type", "material", "label", "q", "torque_min", "torque_max", "preload_min", "preload_max",
              "include_deprecated", "offset", "limit"):
        for v in PARAMS:
            out.append(Attack("query parameters", f"GET /joints?{p}={v[:20]}", "GET", f"{API}/joints?{p}={v}",
                              expect="ok"))
    a = target.joints["writer"]
    for v in ("0", "-1", "2147483648", str(2**63), "9" * 30, "abc", "1.5", "1e3", "%00", "1%20OR%201=1", "%2B1",
              "%EF%BC%91", "0x1"):
        out.append(Attack("query parameters", f"version {v}", "GET", f"{API}/joints/{a}/versions/{v}", expect="ok"))
        out.append(Attack("query parameters", f"diff a={v}", "GET", f"{API}/joints/{a}/diff?a=1&b={v}", expect="ok"))
    for v in ("-1", "0", "501", "9" * 25, "x", "%00"):
        for route in (f"/joints/{a}/history", "/audit", "/joints"):
            out.append(Attack("query parameters", f"{route} limit/offset {v}", "GET",
                              f"{API}{route}?limit={v}&offset={v}", expect="ok"))
    for v in ("../../etc/passwd", "%00", "uff58%00", "HDF5", "json%0d%0a", "", "csv%2f..%2f.."):
        out.append(Attack("query parameters", f"frf format {v}", "GET", f"{API}/joints/{a}/versions/1/frf?format={v}",
                          expect="ok" if v == "" else "4xx"))
    for v in ("not-a-date", "9999-12-31T99:99:99", "%00", "2020-01-01T00:00:00%2B99:00", "-infinity", "1e400",
              "0000-00-00", "x" * 39, "2020-13-45", "now()", "1970-01-01", "294277-01-01"):
        out.append(Attack("query parameters", f"at={v[:20]}", "GET", f"{API}/joints/{a}?at={v}", expect="ok"))
        out.append(Attack("query parameters", f"label={v[:20]}", "GET", f"{API}/joints/{a}?label={v}", expect="ok"))
    return out


def path_names(target) -> list[Attack]:
    out = []
    for n in NAMES:
        for route in (f"/joints/{n}", f"/joints/{n}/history", f"/joints/{n}/diff?a=1", f"/joints/{n}/versions/1",
                      f"/joints/{n}/versions/1/frf", f"/audit?joint={n}", f"/joints/SEC-A/diff?a=1&other={n}"):
            out.append(Attack("path traversal and names", f"name {n[:24]}", "GET", f"{API}{route}", expect="ok"))
        out.append(Attack("path traversal and names", f"label joint {n[:24]}", "POST", f"{API}/joints/{n}/labels",
                          "writer", JSON, json_body({"version": 1, "label": "x"}), expect="4xx"))
    return out


def json_bodies(target, rng: random.Random) -> list[Attack]:
    out = []
    fields = ["name", "joint_type", "model_kind", "method", "label", "conditions.materials.0", "conditions.extra.note",
              "conditions.geometry.KEY", "quality.KEY", "input_files.f.h5", "parameters.p", "frf.outputs.0",
              "frf.inputs.0", "frf.quantity"]
    for f in fields:
        for what, s in STRINGS.items():
            name = f"BODY-{rng.randrange(10**9)}"
            body = _catalogue(target, name)
            if f.endswith("KEY"):
                key_owner = f.rsplit(".", 1)[0]
                _set(body, key_owner, {s: 1.0})
            elif f == "input_files.f.h5":
                body["input_files"] = {s: "0" * 64, "f.h5": s}
            else:
                _set(body, f, s)
            expect = "4xx" if what in REFUSE_STRINGS else "ok"
            out.append(Attack("strings in every field", f"{what} in {f}", "POST", f"{API}/catalogue", "writer", JSON,
                              json_body(body), expect=expect))
    numbers = {"NaN": "NaN", "Infinity": "Infinity", "-Infinity": "-Infinity", "1e400": "1e400", "-1e400": "-1e400",
               "string": '"30"', "bool": "true", "list": "[]", "object": "{}", "negative": "-1", "1e308": "1e308"}
    for where in ("conditions.torque_nm", "conditions.preload_n", "conditions.geometry.diameter_m", "quality.fit_error",
                  "frf.freq_hz.0", "frf.real.0.0.0"):
        for what, lit in numbers.items():
            body = _catalogue(target, f"NUM-{rng.randrange(10**9)}")
            _set(body, where, "__HOLE__")
            raw = json_body(body).replace(b'"__HOLE__"', lit.encode())
            nonfinite = what in ("NaN", "Infinity", "-Infinity", "1e400", "-1e400")
            expect = "4xx" if nonfinite or what in ("list", "object") else "ok"
            out.append(Attack("numbers", f"{what} as {where}", "POST", f"{API}/catalogue", "writer", JSON, raw,
                              expect=expect))
    for depth in (100, 200, 300, 1000):
        for where in ("conditions.extra", "parameters"):
            body = _catalogue(target, f"DEEP-{where[:4]}-{depth}")
            _set(body, where, "__HOLE__")
            raw = json_body(body).replace(b'"__HOLE__"', _nested(depth).encode())
            out.append(Attack("deep nesting", f"{where} nested {depth} deep", "POST", f"{API}/catalogue", "writer",
                              JSON, raw, expect="4xx" if depth >= 1000 else "ok"))
        nearest = '{"joint_type": "tool-holder", "conditions": {"extra": ' + _nested(depth) + "}}"
        out.append(Attack("deep nesting", f"nearest extra nested {depth}", "POST", f"{API}/query/nearest", "reader",
                          JSON, nearest.encode(), expect="ok"))
        out.append(Attack("deep nesting", f"predict stack nested {depth}", "POST", f"{API}/predict", "reader", JSON,
                          ('{"stack": ' + _nested(depth) + "}").encode(), expect="4xx"))
    for n in (10_000, 100_000):
        out.append(Attack("deep nesting", f"top-level arrays {n} deep", "POST", f"{API}/catalogue", "writer", JSON,
                          b"[" * n + b"]" * n))
        out.append(Attack("deep nesting", f"extra lists {n} deep", "POST", f"{API}/query/nearest", "reader", JSON,
                          b'{"joint_type": "x", "conditions": {"extra": {"a": ' + b"[" * n + b"]" * n + b"}}}"))
    out += _shapes_and_types(target, rng)
    return out


def _shapes_and_types(target, rng: random.Random) -> list[Attack]:
    out = []
    bad = {"extra field": {"evil": 1}, "name int": {"name": 123}, "name list": {"name": []}, "name null": {"name": None},
           "force string": {"force": "yes"}, "parent -1": {"parent": -1}, "parent 0": {"parent": 0},
           "parent 2^63": {"parent": 2**63}, "parent 10^30": {"parent": 10**30}, "conditions list": {"conditions": []},
           "conditions string": {"conditions": "x"}, "materials 11": {"conditions": {"materials": ["steel"] * 11}},
           "materials object": {"conditions": {"materials": {"a": 1}}}, "frf null": {"frf": None},
           "frf ragged": {"frf": {**target.frf, "real": [[[1.0]]]}},
           "frf empty": {"frf": {**target.frf, "freq_hz": [], "real": [], "imag": []}},
           "frf units ragged": {"frf": {**target.frf, "units": [["m/N"]]}},
           "frf 10^6 freqs": {"frf": {**target.frf, "freq_hz": [1.0] * 1_000_000}},
           "both file and frf": {"file_b64": "AAAA", "filename": "x.h5"},
           "1 MB method": {"method": "m" * 1_000_000}, "10 MB extra": {"conditions": {"extra": {"x": "y" * 10_000_000}}}}
    for what, over in bad.items():
        expect = "ok" if what in ("1 MB method", "10 MB extra", "force string") else "4xx"
        body = _catalogue(target, f"TYPE-{rng.randrange(10**9)}", **over)
        out.append(Attack("wrong types and shapes", what, "POST", f"{API}/catalogue", "writer", JSON, json_body(body),
                          expect=expect))
    a = target.joints["writer"]
    for what, body in {"version 0": {"version": 0, "label": "x"}, "version -1": {"version": -1, "label": "x"},
                       "version 2^31": {"version": 2**31, "label": "x"}, "version string": {"version": "1", "label": "x"},
                       "version 1.5": {"version": 1.5, "label": "x"}, "version 99": {"version": 99, "label": "x"},
                       **{f"label {k}": {"version": 1, "label": s} for k, s in STRINGS.items()}}.items():
        expect = "ok" if what in ("version string", "label emoji") else "4xx"
        if what in ("label markup", "label template", "label SQL", "label control characters", "label bidi override",
                    "label CRLF"):
            expect = "ok"
        out.append(Attack("wrong types and shapes", f"label: {what}", "POST", f"{API}/joints/{a}/labels", "writer", JSON,
                          json_body(body), expect=expect))
    for what, s in STRINGS.items():
        out.append(Attack("wrong types and shapes", f"deprecate reason: {what}", "POST", f"{API}/joints/{a}/deprecate",
                          "writer", JSON, json_body({"version": 99, "reason": s}), expect="4xx"))
    for what, s in STRINGS.items():
        for route in ("query/nearest", "query/interpolate"):
            out.append(Attack("wrong types and shapes", f"{route} joint_type: {what}", "POST", f"{API}/{route}", "reader",
                              JSON, json_body({"joint_type": s, "conditions": {"torque_nm": 40}}), expect="ok"))
        out.append(Attack("wrong types and shapes", f"nearest at: {what}", "POST", f"{API}/query/nearest", "reader",
                          JSON, json_body({"joint_type": "tool-holder", "at": s[:40]}), expect="ok"))
    for what, lit in {"NaN torque": '{"joint_type": "tool-holder", "conditions": {"torque_nm": NaN}}',
                      "k 0": '{"joint_type": "tool-holder", "k": 0}', "k 10^20": '{"joint_type": "tool-holder", "k": 1e20}',
                      "1e400 geometry": '{"joint_type": "tool-holder", "conditions": {"geometry": {"d": 1e400}}}'}.items():
        out.append(Attack("numbers", f"nearest {what}", "POST", f"{API}/query/nearest", "reader", JSON, lit.encode(),
                          expect="4xx" if what != "1e400 geometry" else "ok"))
    lobes = {"rpm NaN": {"rpm_min": "NaN"}, "rpm inverted": {"rpm_min": 5000, "rpm_max": 100},
             "n_speeds 10^9": {"n_speeds": 10**9}, "joint traversal": {"joint": "../../etc/passwd", "version": 1},
             "version 2^63": {"joint": a, "version": 2**63}, "frf NaN": {"frf": {**target.frf, "real": "NaN"}},
             "kt Infinity": {"kt": "Infinity"}}
    for what, over in lobes.items():
        body = {"joint": a, "version": 1, "kt": 6e8, "kr": 2e8, **over}
        if "frf" in over:
            body.pop("joint"), body.pop("version")
        raw = json_body(body).replace(b'"NaN"', b"NaN").replace(b'"Infinity"', b"Infinity")
        out.append(Attack("numbers", f"lobes {what}", "POST", f"{API}/lobes", "reader", JSON, raw, expect="4xx"))
    return out


def _predict_stacks(target) -> list[Attack]:
    import json
    from pathlib import Path

    stacks = Path(target.campaign_dir).parents[1] / "stacks"
    stack = json.loads((stacks / "endmill-catalogued-joint.json").read_text())
    stack["spindle"]["model"] = json.loads((stacks / stack["spindle"]["model"]).read_text())
    out = []
    server_file = str(stacks / "parts" / "spindle-two-bearings.json")
    for what, path in {"absolute server path": server_file, "/etc/passwd": "/etc/passwd",
                       "traversal": "../../../../etc/passwd", "/proc/self/environ": "/proc/self/environ"}.items():
        for where in ("spindle.model", "tool.model", "holder.model"):
            s = copy.deepcopy(stack)
            _set(s, where, path)
            out.append(Attack("server paths in requests", f"predict {where} = {what}", "POST", f"{API}/predict",
                              "reader", JSON, json_body({"stack": s}), expect="4xx"))
    for what, freq in {"step 0": {"min": 50, "max": 5000, "step": 0}, "NaN": {"min": "NaN", "max": 5000, "step": 20},
                       "negative": {"min": -50, "max": -10, "step": 20}}.items():
        s = copy.deepcopy(stack)
        s["frequency"] = freq
        out.append(Attack("numbers", f"predict frequency {what}", "POST", f"{API}/predict", "reader", JSON,
                          json_body({"stack": s}).replace(b'"NaN"', b"NaN"), expect="4xx"))
    return out


def auth(target) -> list[Attack]:
    a, b = target.joints["writer"], target.joints["writer2"]
    reads = [("GET", f"{API}/joints", None), ("GET", f"{API}/joints/{a}", None), ("GET", f"{API}/joints/{a}/history", None),
             ("GET", f"{API}/joints/{a}/versions/1/frf?format=csv", None), ("GET", f"{API}/audit", None),
             ("POST", f"{API}/query/nearest", {"joint_type": "tool-holder"})]
    writes = [("POST", f"{API}/catalogue", _catalogue(target, "AUTH-W")),
              ("POST", f"{API}/joints/{a}/labels", {"version": 1, "label": "auth"}),
              ("POST", f"{API}/joints/{a}/deprecate", {"version": 2, "reason": "auth"})]
    admin = [("GET", f"{API}/admin/tokens", None), ("POST", f"{API}/admin/tokens", {"name": "evil", "role": "admin"}),
             ("DELETE", f"{API}/admin/tokens/000000000000", None), ("POST", f"{API}/admin/gc", {"dry_run": False}),
             ("GET", f"{API}/admin/check", None), ("GET", f"{API}/admin/migrations", None),
             ("POST", f"{API}/admin/migrations/upgrade", None)]
    reader_id = "_".join(target.tokens["reader"].split("_")[:2])  # jdb_<id>
    bad = {"no token": None, "empty bearer": "Bearer", "two spaces": "Bearer  x", "basic": "Basic dXNlcjpwYXNz",
           "unknown token": "Bearer jdb_000000000000_" + "A" * 40, "right id wrong secret": f"Bearer {reader_id}_wrong",
           "8k token": "Bearer " + "A" * 8000, "two tokens": f"Bearer {target.tokens['reader']} extra",
           "revoked": f"Bearer {target.tokens['revoked']}", "expired": f"Bearer {target.tokens['expired']}",
           "token with SQL": "Bearer jdb_' OR '1'='1"}
    out = []
    for what, header in bad.items():
        for method, path, body in reads + writes + admin:
            h = [("Authorization", header)] if header else []
            out.append(Attack("authentication", f"{what} on {method} {path.split('/api/v1')[1][:30]}", method, path,
                              None, h + (JSON if body else []), json_body(body) if body else None))
    for role, routes in (("reader", writes + admin), ("writer", admin), ("writer2", admin[:3])):
        for method, path, body in routes:
            out.append(Attack("authorisation", f"{role} on {method} {path.split('/api/v1')[1][:30]}", method, path, role,
                              JSON if body else [], json_body(body) if body else None))
    out.append(Attack("authentication", "token in the query string", "GET",
                      f"{API}/joints?token={target.tokens['reader']}&access_token={target.tokens['reader']}", None))
    out.append(Attack("authentication", "lower-case bearer scheme", "GET", f"{API}/joints", None,
                      [("Authorization", f"bearer {target.tokens['reader']}")], expect="ok"))
    # ownership: a writer labels or deprecates a joint another writer catalogued
    out.append(Attack("ownership", "writer2 labels writer's joint", "POST", f"{API}/joints/{a}/labels", "writer2", JSON,
                      json_body({"version": 1, "label": "hijacked"})))
    out.append(Attack("ownership", "writer2 deprecates writer's version", "POST", f"{API}/joints/{a}/deprecate",
                      "writer2", JSON, json_body({"version": 1, "reason": "hijacked"})))
    out.append(Attack("ownership", "writer labels writer2's joint", "POST", f"{API}/joints/{b}/labels", "writer", JSON,
                      json_body({"version": 2, "label": "hijacked"})))
    out.append(Attack("ownership", "writer catalogues a version of writer2's joint", "POST", f"{API}/catalogue",
                      "writer", JSON, json_body(_catalogue(target, b)), expect="ok"))
    return out + _predict_stacks(target)


def http_oddities(target) -> list[Attack]:
    out = []
    a = target.joints["writer"]
    for method in ("PUT", "DELETE", "PATCH", "TRACE", "CONNECT", "PROPFIND"):
        for path in (f"{API}/joints", f"{API}/joints/{a}", f"{API}/catalogue", f"{API}/admin/tokens", "/ui/joints"):
            out.append(Attack("HTTP oddities", f"{method} {path}", method, path, "admin"))
    out.append(Attack("HTTP oddities", "GET on a POST route", "GET", f"{API}/catalogue", "writer"))
    out.append(Attack("HTTP oddities", "HEAD a list", "HEAD", f"{API}/joints", "reader", expect="ok"))
    body = json_body(_catalogue(target, "CT-TYPE"))
    for ct in ("text/plain", "application/x-www-form-urlencoded", "multipart/form-data; boundary=x",
               "application/xml", "application/json; charset=utf-16", "application/json; charset=\x7f", ""):
        out.append(Attack("HTTP oddities", f"content type {ct!r}", "POST", f"{API}/catalogue", "writer",
                          [("Content-Type", ct)] if ct else [], body, expect="ok"))
    for what, raw in {"empty": b"", "truncated": b'{"name": "x"', "trailing garbage": b"{}}", "BOM": b"\xef\xbb\xbf{}",
                      "UTF-16": '{"name": "x"}'.encode("utf-16"), "invalid UTF-8": b'{"name": "\xff\xfe"}',
                      "array": b"[]", "string": b'"x"', "null": b"null", "number 1e400": b"1e400", "NaN": b"NaN",
                      "duplicate keys": b'{"name": "ok", "name": "../../x"}'}.items():
        for path in (f"{API}/catalogue", f"{API}/query/nearest", f"{API}/joints/{a}/labels"):
            out.append(Attack("HTTP oddities", f"malformed JSON: {what}", "POST", path, "writer", JSON, raw))
    out.append(Attack("HTTP oddities", "two Authorization headers", "POST", f"{API}/joints/{a}/labels", None,
                      [("Authorization", f"Bearer {target.tokens['reader']}"),
                       ("Authorization", f"Bearer {target.tokens['writer']}"), *JSON],
                      json_body({"version": 1, "label": "dup"}), expect="ok"))
    out.append(Attack("HTTP oddities", "two Content-Type headers", "POST", f"{API}/query/nearest", "reader",
                      [("Content-Type", "text/plain"), ("Content-Type", "application/json")],
                      b'{"joint_type": "tool-holder"}', expect="ok"))
    out.append(Attack("HTTP oddities", "spoofed Host and X-Forwarded headers", "GET", f"{API}/joints", "reader",
                      [("Host", "evil.example"), ("X-Forwarded-For", "10.0.0.1"), ("X-Forwarded-Proto", "https"),
                       ("X-Original-URL", "/api/v1/admin/tokens")], expect="ok"))
    out.append(Attack("HTTP oddities", "client X-Request-ID", "GET", f"{API}/joints", "reader",
                      [("X-Request-ID", "../../etc/passwd")], expect="ok"))
    for n in (20_000, 100_000):
        out.append(Attack("HTTP oddities", f"{n}-byte header", "GET", f"{API}/joints", "reader",
                          [("X-Big", "b" * n)], expect="ok|closed"))
    out.append(Attack("HTTP oddities", "65 MiB body", "POST", f"{API}/catalogue", "writer", JSON,
                      b'{"name": "' + b"x" * (65 * 2**20) + b'"}'))
    host = target.url.split("//", 1)[1]
    raws = {
        "conflicting Content-Length": f"POST {API}/query/nearest HTTP/1.1\r\nHost: {host}\r\nContent-Length: 5\r\n"
                                      f"Content-Length: 40\r\n\r\n{{}}",
        "CL and TE (smuggling)": f"POST {API}/query/nearest HTTP/1.1\r\nHost: {host}\r\nContent-Length: 4\r\n"
                                 f"Transfer-Encoding: chunked\r\n\r\n0\r\n\r\nGET /api/v1/admin/tokens HTTP/1.1\r\n\r\n",
        "bad chunk size": f"POST {API}/query/nearest HTTP/1.1\r\nHost: {host}\r\nTransfer-Encoding: chunked\r\n\r\n"
                          f"zz\r\n{{}}\r\n0\r\n\r\n",
        "negative Content-Length": f"POST {API}/query/nearest HTTP/1.1\r\nHost: {host}\r\nContent-Length: -1\r\n\r\n",
        "dot segments": f"GET /api/v1/../../../../etc/passwd HTTP/1.1\r\nHost: {host}\r\n\r\n",
        "encoded dot segments": f"GET /ui/static/..%2f..%2f..%2f_app.py HTTP/1.1\r\nHost: {host}\r\n\r\n",
        "static traversal": f"GET /ui/static/../../_settings.py HTTP/1.1\r\nHost: {host}\r\n\r\n",
        "absolute-form target": f"GET http://evil.example/api/v1/joints HTTP/1.1\r\nHost: {host}\r\n\r\n",
        "HTTP/0.9": "GET /\r\n\r\n", "bad method token": f"G(T / HTTP/1.1\r\nHost: {host}\r\n\r\n",
        "header without colon": f"GET / HTTP/1.1\r\nHost: {host}\r\nBroken\r\n\r\n",
        "NUL in header": f"GET / HTTP/1.1\r\nHost: {host}\r\nX-A: a\x00b\r\n\r\n",
        # (to the API without a token: "/" now leads to the catalogue, a redirect, not a 404)
        "obs-fold header": f"GET {API}/joints HTTP/1.1\r\nHost: {host}\r\nX-A: a\r\n b\r\n\r\n",
        "1000 headers": f"GET {API}/joints HTTP/1.1\r\nHost: {host}\r\n" + "".join(f"X-{i}: {i}\r\n" for i in range(1000)) + "\r\n",
        "64 KiB URL": f"GET {API}/joints?q={'q' * 65536} HTTP/1.1\r\nHost: {host}\r\n\r\n",
        "lone percent": f"GET {API}/joints/% HTTP/1.1\r\nHost: {host}\r\n\r\n",
        "no Host": "GET /api/v1/joints HTTP/1.1\r\n\r\n",
    }
    for what, text in raws.items():
        out.append(Attack("HTTP oddities", f"raw: {what}", "RAW", what, None, raw=text.encode("latin-1"),
                          expect="4xx|closed"))
    return out
