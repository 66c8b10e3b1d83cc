"""Issue 20's attack suite: at least 800 hostile requests against a live ``jointdb serve`` on
SQLite and PostgreSQL (see README.md here), then what must hold:

- no answer is a 5xx, and each hostile request gets what it may (refused, or accepted where
  it is a legitimate request);
- no answer (body or header) and no log line carries a server path, the database URL or a
  token; every log line is one JSON object; 5xx are logged with their status;
- an upload naming an existing server file is answered as one naming a missing file;
- afterwards every role still reads the list, a joint, its history and nearest joints;
- the web catalogue: the cookie is not the API token, sign-out ends the session, markup
  stored in a joint is escaped, authenticated pages carry the security headers.

The attacks run once per backend (module fixture); each test reports one property, naming
the first offending requests.
"""

from __future__ import annotations

import json
import os
import random
import re
import time
from dataclasses import dataclass
from urllib.parse import quote

import httpx
import pytest
from security_attacks import auth, http_oddities, json_bodies, path_names, query_params
from security_parts import parts
from security_run import Result, first, leaks, log_problems, per_class, response_leaks, run
from security_uploads import archives, campaign_paths, existence_oracle
from security_web import sign_in, web

MIN_REQUESTS = 800


@dataclass
class Outcome:
    results: list[Result]
    oracle: list[tuple[Result, Result, str, str]]
    cookie: str | None
    seconds: float


@pytest.fixture(scope="module")
def attacked(target) -> Outcome:
    """Every hostile request, sent once per backend (reads first, then writes and uploads, so
    that a poisoning write shows in the checks after it, not in the other classes)."""
    t0 = time.perf_counter()
    cookie = sign_in(target.url, target.tokens["writer"])
    rng = random.Random(20)
    attacks = (http_oddities(target) + query_params(target) + path_names(target) + web(target, cookie)
               + auth(target) + json_bodies(target, rng) + parts(target) + archives(target) + campaign_paths(target))
    results = run(target, attacks)
    pairs = existence_oracle(target)
    answered = run(target, [x for a, b, _, _ in pairs for x in (a, b)])
    oracle = [(answered[2 * i], answered[2 * i + 1], yes, no) for i, (_, _, yes, no) in enumerate(pairs)]
    out = Outcome(results + answered, oracle, cookie, time.perf_counter() - t0)
    if os.environ.get("JOINTDB_SECURITY_REPORT"):  # one JSON line per request, for a closer look
        with open(f"{os.environ['JOINTDB_SECURITY_REPORT']}.{target.backend}.jsonl", "w", encoding="utf-8") as fh:
            for r in out.results:
                fh.write(json.dumps({"class": r.attack.cls, "what": r.attack.what, "method": r.attack.method,
                                     "path": r.attack.path[:200], "role": r.attack.role, "expect": r.attack.expect,
                                     "status": r.status, "ok": r.expected(), "seconds": round(r.seconds, 3),
                                     "leaks": leaks(r.headers + r.body, target.secrets, r.attack.sent_text()),
                                     "body": r.body[:300]}) + "\n")
    return out


def _check(problems: list, message: str) -> None:
    """Fail with ``message`` alone when there are problems (no repr of a thousand results)."""
    if problems:
        pytest.fail(message, pytrace=False)


def _summary(out: Outcome) -> str:
    classes: dict[str, int] = {}
    for r in out.results:
        classes[r.attack.cls] = classes.get(r.attack.cls, 0) + 1
    return f"{len(out.results)} requests in {out.seconds:.0f} s: " + ", ".join(f"{c} {n}" for c, n in classes.items())


def test_at_least_800_hostile_requests(attacked):
    assert len(attacked.results) >= MIN_REQUESTS, _summary(attacked)
    print(_summary(attacked))


def test_no_5xx(attacked):
    bad = [r for r in attacked.results if r.status >= 500]
    _check(bad, (f"{len(bad)} of {len(attacked.results)} hostile requests got a 5xx (per class: "
                     f"{per_class(attacked.results, lambda r: r.status >= 500)}):{first([r.line() for r in bad])}"))


def test_each_hostile_request_is_refused_or_legitimately_accepted(attacked):
    bad = [r for r in attacked.results if r.status < 500 and not r.expected()]
    _check(bad, (f"{len(bad)} hostile requests got an answer they may not (per class: "
                     f"{per_class(attacked.results, lambda r: r.status < 500 and not r.expected())}):"
                 f"{first([f'{r.line()} (expected {r.attack.expect})' for r in bad], 12)}"))


def test_no_server_secret_in_any_answer(target, attacked):
    found = response_leaks(attacked.results, target.secrets)
    _check(found, f"{len(found)} answers carry a server path, URL, token or file content:{first(found)}")


def test_every_log_line_is_one_json_object(target, attacked):
    not_json, _, _ = log_problems(target.log.read_text(encoding="utf-8", errors="replace"), target.secrets)
    total = len(target.log.read_text(encoding="utf-8", errors="replace").splitlines())
    _check(not_json, f"{len(not_json)} of {total} server log lines are not one JSON object:{first(not_json)}")


def test_no_secret_in_the_log_and_failures_logged_with_their_status(target, attacked):
    _, leaking, bad_status = log_problems(target.log.read_text(encoding="utf-8", errors="replace"), target.secrets)
    problems = ([f"{len(leaking)} log lines carry a server path, URL, token or file content:{first(leaking)}"]
                if leaking else []) + \
               ([f"{len(bad_status)} request log lines with status 0 or 5xx:{first(bad_status)}"] if bad_status else [])
    _check(problems, "\n".join(problems))


def _normal(r: Result, *paths: str) -> tuple[int, str]:
    try:
        text = str(json.loads(r.body).get("error", ""))
    except (ValueError, AttributeError):
        text = r.body
    for p in sorted(paths, key=len, reverse=True):
        text = text.replace(p, "<P>")
    return r.status, re.sub(r"[0-9a-f]{16}", "<id>", text)


def test_no_answer_tells_whether_a_server_file_exists(attacked):
    told = [f"{a.attack.what}: {_normal(a, yes, no)} / {_normal(b, yes, no)}"
            for a, b, yes, no in attacked.oracle if _normal(a, yes, no) != _normal(b, yes, no)]
    _check(told, f"{len(told)} of {len(attacked.oracle)} pairs tell an existing server file from a missing one:"
                 f"{first(told)}")


def test_every_role_still_reads_the_catalogue(target, attacked):
    """No hostile request poisoned the catalogue for anyone."""
    a = target.joints["writer"]
    failed = []
    for role in ("reader", "writer", "writer2", "admin"):
        with httpx.Client(base_url=target.url, timeout=60.0,
                          headers={"Authorization": f"Bearer {target.tokens[role]}"}) as c:
            for method, path, body in (("GET", "/api/v1/joints", None), ("GET", f"/api/v1/joints/{a}", None),
                                       ("GET", f"/api/v1/joints/{a}/history", None),
                                       ("POST", "/api/v1/query/nearest",
                                        {"joint_type": "tool-holder", "conditions": {"torque_nm": 40.0}}),
                                       ("POST", "/api/v1/query/nearest", {"joint_type": "tool-holder", "k": 50,
                                                                          "all_versions": True})):
                status, text = _ask(c, method, path, body)
                if status != 200:
                    failed.append(f"{role}: {method} {path} -> {status} {text[:120]!r}")
            if role == "reader":
                failed += _every_joint(c)
    _check(failed, f"after the attacks, {len(failed)} normal requests fail:{first(failed)}")


def _ask(c: httpx.Client, method: str, path: str, body=None, params=None) -> tuple[int, str]:
    """Status and text of a normal request (0 when the server closed the connection twice)."""
    for attempt in (1, 2):
        try:
            r = c.request(method, path, json=body, params=params)
            return r.status_code, r.text
        except httpx.TransportError as exc:
            if attempt == 2:
                return 0, f"{type(exc).__name__}: {exc}"
    raise AssertionError("unreachable")


def _every_joint(c: httpx.Client) -> list[str]:
    """Each catalogued joint (the hostile ones that were accepted too) and its history read back."""
    failed, offset, names = [], 0, []
    while offset is not None:
        status, text = _ask(c, "GET", "/api/v1/joints", params={"offset": offset, "limit": 500})
        if status != 200:
            return [f"reader: GET /api/v1/joints?offset={offset} -> {status} {text[:120]!r}"]
        names += [v["name"] for v in json.loads(text)["items"]]
        offset = json.loads(text).get("next_offset")
    for name in names:
        for path in (f"/api/v1/joints/{quote(name, safe='')}", f"/api/v1/joints/{quote(name, safe='')}/history"):
            status, text = _ask(c, "GET", path)
            if status != 200:
                failed.append(f"reader: GET {path} -> {status} {text[:120]!r}")
    return failed


def test_stored_markup_is_escaped_in_pages(target, attacked):
    """Joints accepted with markup in their fields are shown escaped in the web catalogue."""
    cookie = sign_in(target.url, target.tokens["reader"]) or attacked.cookie
    if cookie is None:
        pytest.fail("could not sign in to the web catalogue through its form")
    accepted = [r for r in attacked.results if r.status == 201 and "<script>" in r.attack.sent_text()]
    raw = []
    with httpx.Client(base_url=target.url, timeout=60.0, headers={"Cookie": cookie}) as c:
        for r in accepted:
            name = json.loads(r.body)["name"]
            page = c.get(f"/ui/joints/{quote(name, safe='')}")
            if "<script>alert(1)</script>" in page.text:
                raw.append(f"{r.attack.what}: /ui/joints/{name}")
    assert accepted, "no joint with markup was accepted; nothing to check"
    _check(raw, f"{len(raw)} pages show stored markup unescaped:{first(raw)}")


SECURITY_HEADERS = ("content-security-policy", "x-frame-options", "x-content-type-options", "referrer-policy")


def test_authenticated_pages_carry_security_headers(target, attacked):
    cookie = sign_in(target.url, target.tokens["reader"])
    assert cookie, "could not sign in to the web catalogue through its form"
    with httpx.Client(base_url=target.url, timeout=60.0, headers={"Cookie": cookie}) as c:
        r = c.get(f"/ui/joints/{target.joints['writer']}")
    missing = [h for h in SECURITY_HEADERS if h not in r.headers]
    if "no-store" not in r.headers.get("cache-control", ""):
        missing.append("cache-control: no-store")
    assert r.status_code == 200 and not missing, f"{r.status_code}; missing {missing}"


def test_sign_out_ends_the_session(target, attacked):
    from security_web import session_csrf

    cookie = sign_in(target.url, target.tokens["writer2"])
    assert cookie, "could not sign in to the web catalogue through its form"
    fields = session_csrf(target.url, cookie, "/ui/joints", "/ui/signout")
    with httpx.Client(base_url=target.url, timeout=60.0, follow_redirects=False) as c:
        assert c.get("/ui/joints", headers={"Cookie": cookie}).status_code == 200
        out = c.post("/ui/signout", data=fields, headers={"Cookie": cookie})
        assert out.status_code in (302, 303), out.text[:200]
        again = c.get("/ui/joints", headers={"Cookie": cookie})
    assert again.status_code != 200, "the session cookie still opens /ui/joints after signing out"
    found = leaks(out.headers.get("set-cookie", ""), {"writer2 token": target.tokens["writer2"]})
    assert not found
