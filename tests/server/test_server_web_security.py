"""Web hardening of ``jointdb serve`` (issue 20, item 7), against a live server on SQLite and
PostgreSQL: server-side sessions (the cookie is a random session id, not the token; sign-out
and token revocation end it; idle and absolute timeouts), CSRF on every form including
sign-in, security headers on every answer, Swagger UI served from the package with a bearer
scheme, cookie flags, and who may label or deprecate a joint. Plus a real browser (the
distribution's chromium) on /ui and /docs under the Content-Security-Policy, offline."""

from __future__ import annotations

import json
import re
from contextlib import closing
import shutil
import subprocess
import sys
from datetime import datetime, timedelta, timezone

import httpx
import pytest

from server_helpers import joint_upload

CSRF = re.compile(r'name="csrf" value="([0-9a-f]{64})"')


def _web(server) -> httpx.Client:
    return httpx.Client(base_url=server.url, follow_redirects=False, timeout=60.0)


def _signin(server, token: str) -> httpx.Client:
    """A client signed in to /ui through the sign-in form (with its CSRF token)."""
    c = _web(server)
    page = c.get("/ui/signin")
    assert page.status_code == 200
    m = CSRF.search(page.text)  # (a form without one is refused by test_sign_in_needs_its_csrf_token)
    r = c.post("/ui/signin", data={"csrf": m.group(1) if m else "", "token": token})
    assert r.status_code == 303 and r.headers["location"] == "/ui/joints", (r.status_code, r.text[:300])
    return c


def _form_csrf(client: httpx.Client, path: str) -> str:
    page = client.get(path)
    assert page.status_code == 200, (path, page.status_code)
    return CSRF.search(page.text).group(1)


def _session_cookie(client: httpx.Client) -> str:
    return client.cookies.get("jointdb_session", path="/")


def _new_token(server, name: str, role: str = "writer", team: str | None = None) -> str:
    from jointdb.store._tokens import create_token

    with server.repo() as r:
        return create_token(r, name, role, **({"team": team} if team else {}))[0]


def _catalogue(server, token: str, tmp_path, name: str, **extra) -> None:
    with server.client(token=token) as c:
        r = c.post("/api/v1/catalogue", json={**joint_upload(tmp_path, name), **extra})
        assert r.status_code == 201, r.text


def test_cookie_is_a_random_session_id_stored_hashed(server):
    token = server.tokens["writer"]
    with closing(_signin(server, token)) as c:
        sid = _session_cookie(c)
        assert sid and sid != token and token not in sid and len(sid) >= 43  # >= 256 bits, base64url
        assert c.get("/ui/joints").status_code == 200
        with closing(_signin(server, token)) as other:
            assert _session_cookie(other) != sid  # every sign-in a new id
    from sqlalchemy import select

    from jointdb.store._models import WebSessionRow
    from jointdb.store._tokens import session_sha256

    with server.repo() as r, r._read() as s:
        rows = s.scalars(select(WebSessionRow)).all()
    assert session_sha256(sid) in {row.sha256 for row in rows}
    assert all(sid not in (row.sha256, row.token_id) for row in rows)
    assert {row.owner for row in rows} >= {"writer-owner"}


def test_sign_out_revokes_the_session_on_the_server(server):
    c = _signin(server, server.tokens["reader"])
    sid = _session_cookie(c)
    csrf = _form_csrf(c, "/ui/joints")
    r = c.post("/ui/signout", data={"csrf": csrf})
    assert r.status_code == 303 and r.headers["location"] == "/ui/signin"
    c.close()
    with _web(server) as replay:  # the old cookie, replayed: signed out
        replay.cookies.set("jointdb_session", sid, path="/")
        r = replay.get("/ui/joints")
        assert r.status_code == 303 and r.headers["location"] == "/ui/signin"
        assert 'jointdb_session=""' in r.headers.get("set-cookie", "")  # and the stale cookie is cleared


def test_revoking_the_token_ends_its_sessions(server):
    token = _new_token(server, "session-revoke")
    c = _signin(server, token)
    assert c.get("/ui/joints").status_code == 200
    with server.client("admin") as a:
        assert a.delete(f"/api/v1/admin/tokens/{token[4:16]}").status_code == 200
    r = c.get("/ui/joints")
    assert r.status_code == 303 and r.headers["location"] == "/ui/signin"
    c.close()


def test_idle_and_absolute_timeouts(server):
    from sqlalchemy import update

    from jointdb.store._models import WebSessionRow
    from jointdb.store._tokens import session_sha256

    now = datetime.now(timezone.utc)
    for column, value in (("last_seen_at", now - timedelta(minutes=31)), ("expires_at", now - timedelta(seconds=1))):
        c = _signin(server, server.tokens["reader"])
        assert c.get("/ui/joints").status_code == 200
        with server.repo() as r, r._write() as s, s.begin():
            s.execute(update(WebSessionRow).where(WebSessionRow.sha256 == session_sha256(_session_cookie(c)))
                      .values(**{column: value}))
        r = c.get("/ui/joints")
        assert r.status_code == 303 and r.headers["location"] == "/ui/signin", column
        c.close()


def test_sign_in_needs_its_csrf_token(server):
    token = server.tokens["writer"]
    with _web(server) as c:  # no form, no cookie: a cross-site POST
        r = c.post("/ui/signin", data={"token": token})
        assert r.status_code in (403, 422) and "jointdb_session" not in r.headers.get("set-cookie", "")
    with _web(server) as c:  # the pre-session cookie, but a forged form token
        c.get("/ui/signin")
        r = c.post("/ui/signin", data={"token": token, "csrf": "0" * 64})
        assert r.status_code == 422 and "jointdb_session" not in r.headers.get("set-cookie", "")
        assert "CSRF" in r.text
    with _web(server) as c:  # a valid form sent from another site
        csrf = CSRF.search(c.get("/ui/signin").text).group(1)
        r = c.post("/ui/signin", data={"token": token, "csrf": csrf}, headers={"Origin": "https://evil.example"})
        assert r.status_code == 403 and "jointdb_session" not in r.headers.get("set-cookie", "")


def test_pages_scripts_call_the_api_with_the_session_and_its_csrf_header(server, tmp_path):
    token = server.tokens["writer"]
    _catalogue(server, token, tmp_path, "SESSION-API")
    with closing(_signin(server, token)) as web:
        csrf = _form_csrf(web, "/ui/joints/SESSION-API")
        assert web.get("/api/v1/joints/SESSION-API").json()["name"] == "SESSION-API"  # reads: the cookie is enough
        body = {"version": 1, "label": "by-script"}
        r = web.post("/api/v1/joints/SESSION-API/labels", json=body)  # a write without the header
        assert r.status_code == 403 and "X-CSRF-Token" in r.json()["error"]
        r = web.post("/api/v1/joints/SESSION-API/labels", json=body, headers={"X-CSRF-Token": "0" * 64})
        assert r.status_code == 403
        r = web.post("/api/v1/joints/SESSION-API/labels", json=body,
                     headers={"X-CSRF-Token": csrf, "Origin": "https://evil.example"})
        assert r.status_code == 403
        with server.repo() as repo:
            assert repo.get("SESSION-API").labels == ()
        r = web.post("/api/v1/joints/SESSION-API/labels", json=body, headers={"X-CSRF-Token": csrf})
        assert r.status_code == 200 and r.json()["labels"] == ["by-script"]
        assert web.get("/api/v1/admin/tokens").status_code == 403  # the session has its token's role, no more
    with _web(server) as anon:  # no session: 401 as before
        assert anon.get("/api/v1/joints").status_code == 401


def test_form_csrf_is_bound_to_the_session_not_the_token(server, tmp_path):
    token = server.tokens["writer"]
    _catalogue(server, token, tmp_path, "CSRF-BIND")
    first, second = _signin(server, token), _signin(server, token)
    csrf_first = _form_csrf(first, "/ui/joints/CSRF-BIND")
    assert csrf_first != _form_csrf(second, "/ui/joints/CSRF-BIND")
    r = second.post("/ui/joints/CSRF-BIND/deprecate", data={"csrf": csrf_first, "reason": "x"})
    assert r.status_code == 422
    with server.repo() as repo:
        assert repo.get("CSRF-BIND").state == "active"
    first.close(), second.close()


SECURITY = {"x-frame-options": "DENY", "x-content-type-options": "nosniff"}


def _assert_secured(r: httpx.Response, no_store: bool = True) -> None:
    what = f"{r.request.method} {r.request.url.path} -> {r.status_code}"
    csp = r.headers.get("content-security-policy", "")
    for part in ("default-src 'self'", "frame-ancestors 'none'", "script-src 'self'"):
        assert part in csp, (what, csp)
    assert "unsafe-inline" not in csp and "unsafe-eval" not in csp, (what, csp)
    for k, v in SECURITY.items():
        assert r.headers.get(k) == v, (what, k)
    assert r.headers.get("referrer-policy") in ("no-referrer", "same-origin"), what
    if no_store:
        assert "no-store" in r.headers.get("cache-control", ""), (what, r.headers.get("cache-control"))


def test_security_headers_on_pages_api_answers_and_errors(server, tmp_path):
    _catalogue(server, server.tokens["writer"], tmp_path, "HDR-1")
    with closing(_signin(server, server.tokens["reader"])) as web:
        for path in ("/ui/joints", "/ui/joints/HDR-1", "/ui/nearest", "/ui/joints/NOPE-404"):
            _assert_secured(web.get(path))
        dl = web.get("/ui/joints/HDR-1/versions/1/frf?format=csv")
        _assert_secured(dl)  # a signed-in download is not kept in the browser's cache
    with _web(server) as anon:
        for path in ("/ui/signin", "/ui/joints", "/docs", "/openapi.json", "/healthz", "/readyz"):
            _assert_secured(anon.get(path))
        _assert_secured(anon.get("/ui/static/style.css"), no_store=False)
        _assert_secured(anon.get("/api/v1/joints"))  # 401
    with server.client("reader") as c:
        _assert_secured(c.get("/api/v1/joints"))
        _assert_secured(c.get("/api/v1/joints/NOPE-404"))
        _assert_secured(c.post("/api/v1/query/nearest", content=b"{not json", headers={"content-type": "application/json"}))
        _assert_secured(c.post("/api/v1/catalogue", json={}))  # 403 for a reader
        frf = c.get("/api/v1/joints/HDR-1/versions/1/frf?format=csv")
        _assert_secured(frf, no_store=False)  # a pinned version: ETag and long caching, private behind a token
        assert frf.headers["etag"] and "private" in frf.headers["cache-control"]
        assert "Authorization" in frf.headers.get("vary", "")
    head = _raw_head(server, "POST /api/v1/catalogue HTTP/1.1\r\nHost: x\r\nContent-Length: 1099511627776\r\n"
                             f"Authorization: Bearer {server.tokens['writer']}\r\n\r\n")
    assert head.startswith("HTTP/1.1 413")  # refused by the service middleware before any route
    for line in ("content-security-policy: default-src 'self'", "x-frame-options: DENY", "cache-control: no-store"):
        assert line.lower() in head.lower(), (line, head)


def _raw_head(server, request: str) -> str:
    """The status line and headers of a raw HTTP request (for what an HTTP client refuses to send)."""
    import socket

    host, port = server.url.rsplit("/", 1)[1].split(":")
    with socket.create_connection((host, int(port)), timeout=30) as sock:
        sock.sendall(request.encode())
        data = b""
        while b"\r\n\r\n" not in data:
            chunk = sock.recv(4096)
            if not chunk:
                break
            data += chunk
    return data.split(b"\r\n\r\n")[0].decode("latin-1")


def test_docs_are_served_from_the_package(server):
    with _web(server) as c:
        page = c.get("/docs")
        assert page.status_code == 200
        refs = re.findall(r'(?:src|href)="([^"]*)"', page.text)
        assert refs and not [u for u in refs if "//" in u], refs  # no external host
        assert "<script>" not in page.text  # no inline script (every script has a src)
        assert "cdn" not in page.text.lower()
        for url in refs:
            asset = c.get(url)
            assert asset.status_code == 200 and len(asset.content) > 0, url
        assert any(u.endswith("swagger-ui-bundle.js") for u in refs) and any(u.endswith(".css") for u in refs)
        assert c.get("/ui/static/swagger/LICENSE").status_code == 200
        assert c.get("/redoc").status_code == 404  # FastAPI's ReDoc page loads its script from a CDN


def test_openapi_declares_the_bearer_scheme(server):
    with _web(server) as c:
        spec = c.get("/openapi.json").json()
    schemes = spec["components"]["securitySchemes"]
    assert any(s["type"] == "http" and s["scheme"].lower() == "bearer" for s in schemes.values())
    name = next(k for k, s in schemes.items() if s["type"] == "http")
    for path, method in (("/api/v1/joints", "get"), ("/api/v1/catalogue", "post"), ("/api/v1/admin/tokens", "get")):
        assert {name: []} in spec["paths"][path][method]["security"], path
    assert "security" not in spec["paths"]["/healthz"]["get"]


def test_writer_may_change_only_their_own_or_their_teams_joints(server, tmp_path):
    suffix = server.url.rsplit(":", 1)[1]
    alice, admin = server.tokens["writer"], server.tokens["admin"]  # alice: writer-owner
    bob = _new_token(server, f"bob-{suffix}")
    _catalogue(server, alice, tmp_path, "OWN-A")
    _catalogue(server, bob, tmp_path, "OWN-A", allow_identical=True)  # bob adds v2: still alice's joint
    for body_path, body in (("labels", {"version": 1, "label": "released"}), ("deprecate", {"reason": "mine now"})):
        with server.client(token=bob) as c:
            r = c.post(f"/api/v1/joints/OWN-A/{body_path}", json=body)
        assert r.status_code == 403, r.text
        assert "writer-owner" in r.json()["error"] and "\n" not in r.json()["error"]
    with server.repo() as repo:
        assert repo.get("OWN-A").labels == () and repo.get("OWN-A").state == "active"
    with closing(_signin(server, bob)) as web:  # the web form: the same rule
        page = web.get("/ui/joints/OWN-A").text
        assert 'id="not-owner"' in page and 'id="deprecate-form"' not in page  # the forms are not offered
        csrf = CSRF.search(page).group(1)  # (the sign-out form's: the same session) -- a hand-made POST:
        r = web.post("/ui/joints/OWN-A/deprecate", data={"csrf": csrf, "reason": "mine now"})
        assert r.status_code == 403 and "writer-owner" in r.text
    with server.client(token=admin) as c:
        assert c.post("/api/v1/joints/OWN-A/labels", json={"version": 1, "label": "released"}).status_code == 200
    with server.client(token=alice) as c:
        assert c.post("/api/v1/joints/OWN-A/labels", json={"version": 2, "label": "released"}).status_code == 200
        assert c.post("/api/v1/joints/OWN-A/deprecate", json={"version": 1, "reason": "v2 is better"}).status_code == 200

    # a team: `jointdb tokens create --team` (the CLI), carol and dave in team "spindles"
    def cli_token(name: str) -> str:
        out = subprocess.run([sys.executable, "-m", "jointdb", "tokens", "create", "--name", name, "--role", "writer",
                              "--team", f"spindles-{suffix}", "--db", server.db, "--blobs", str(server.blobs), "--json"],
                             capture_output=True, text=True, timeout=120)
        assert out.returncode == 0, out.stderr
        data = json.loads(out.stdout)
        assert data["team"] == f"spindles-{suffix}"
        return data["token"]

    carol, dave = cli_token(f"carol-{suffix}"), cli_token(f"dave-{suffix}")
    _catalogue(server, carol, tmp_path, "OWN-C")
    with server.client(token=dave) as c:
        assert c.post("/api/v1/joints/OWN-C/labels", json={"version": 1, "label": "team"}).status_code == 200
        assert c.post("/api/v1/joints/OWN-A/labels", json={"version": 1, "label": "x"}).status_code == 403
    with server.client(token=bob) as c:
        assert c.post("/api/v1/joints/OWN-C/deprecate", json={"reason": "x"}).status_code == 403


def test_cookies_flags_on_a_loopback_server(server):
    with _web(server) as c:
        r = c.get("/ui/signin")
        cookie = r.headers["set-cookie"].lower()
        assert "httponly" in cookie and "samesite=strict" in cookie and "path=/ui/signin" in cookie
        assert "secure" not in cookie  # `jointdb serve` on 127.0.0.1 without TLS
        assert "strict-transport-security" not in r.headers


# --- in-process app: what depends on the bind address and on a failing route -------------------------


@pytest.fixture(scope="module")
def local_repo(tmp_path_factory):
    from jointdb.store import Repository, upgrade

    tmp = tmp_path_factory.mktemp("web-local")
    url = f"sqlite:///{tmp / 'j.sqlite'}"
    upgrade(url)
    with Repository(url, blobs=tmp / "blobs", auto_create=False) as repo:
        yield repo


def _local_client(repo, **settings):
    from fastapi.testclient import TestClient

    from jointdb.server import create_app
    from jointdb.server import Settings

    return TestClient(create_app(Settings(**settings), repo=repo), raise_server_exceptions=False)


@pytest.mark.parametrize("settings, secure", [
    ({"bind_host": "0.0.0.0"}, True), ({"bind_host": "192.0.2.10"}, True), ({}, True),
    ({"bind_host": "127.0.0.1"}, False), ({"bind_host": "::1"}, False),
    ({"bind_host": "127.0.0.1", "secure_cookies": True}, True), ({"bind_host": "0.0.0.0", "secure_cookies": False}, False),
])
def test_secure_cookies_unless_plain_http_on_loopback(local_repo, settings, secure):
    with _local_client(local_repo, **settings) as c:
        r = c.get("/ui/signin")
    cookie = r.headers["set-cookie"].lower()
    assert ("; secure" in cookie) is secure, (settings, cookie)
    assert ("strict-transport-security" in r.headers) is secure
    assert "httponly" in cookie and "samesite=strict" in cookie


def test_secure_cookie_setting_from_the_environment(monkeypatch):
    from jointdb.server import Settings

    monkeypatch.setenv("JOINTDB_BIND_HOST", "0.0.0.0")
    monkeypatch.setenv("JOINTDB_SECURE_COOKIES", "auto")
    assert Settings.from_env().cookie_secure is True
    monkeypatch.setenv("JOINTDB_SECURE_COOKIES", "false")
    assert Settings.from_env().cookie_secure is False
    monkeypatch.setenv("JOINTDB_BIND_HOST", "127.0.0.1")
    monkeypatch.delenv("JOINTDB_SECURE_COOKIES")
    assert Settings.from_env().cookie_secure is False


def test_security_headers_on_an_unexpected_500(local_repo):
    from jointdb.server import create_app
    from jointdb.server import Settings
    from fastapi.testclient import TestClient

    app = create_app(Settings(bind_host="127.0.0.1"), repo=local_repo)

    @app.get("/boom")
    def boom():
        raise RuntimeError("unexpected")

    with TestClient(app, raise_server_exceptions=False) as c:
        r = c.get("/boom")
    assert r.status_code == 500
    _assert_secured(r)


# --- a real browser, offline, under the CSP ---------------------------------------------------------------

CHROMIUM = shutil.which("chromium")


@pytest.mark.skipif(CHROMIUM is None, reason="chromium is not installed (apt-get install chromium)")
@pytest.mark.parametrize("server", ["sqlite"], indirect=True)
def test_ui_and_docs_in_a_browser_under_the_csp_offline(server, tmp_path):
    sync_api = pytest.importorskip("playwright.sync_api", reason="the playwright package is not installed")
    _catalogue(server, server.tokens["writer"], tmp_path, "CSP-1")
    problems, outside = [], []
    with sync_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox", "--disable-gpu",
                                                                    "--disable-background-networking"])
        context = browser.new_context()

        def offline(route):  # anything not from the server: refused (and counted)
            if route.request.url.startswith(server.url):
                route.continue_()
            else:
                outside.append(route.request.url)
                route.abort()

        context.route("**/*", offline)
        page = context.new_page()
        page.on("console", lambda m: problems.append(m.text) if m.type == "error" else None)
        page.on("pageerror", lambda e: problems.append(str(e)))
        page.goto(f"{server.url}/ui/signin")
        page.fill("#token", server.tokens["writer"])
        page.click("#signin")
        page.wait_for_url("**/ui/joints")
        cookie = next(c for c in context.cookies() if c["name"] == "jointdb_session")
        assert cookie["value"] != server.tokens["writer"] and cookie["httpOnly"] and cookie["sameSite"] == "Strict"
        page.goto(f"{server.url}/ui/joints/CSP-1")
        page.wait_for_selector(".plot .uplot canvas")  # the bundled plotting library ran under the CSP
        assert page.evaluate("getComputedStyle(document.querySelector('header')).display") == "flex"  # CSS applied
        page.fill("#label-name", "csp-ok")
        page.click("#label")
        page.click("#confirm")
        page.wait_for_selector("#notice")
        page.click("#signout")
        page.wait_for_url("**/ui/signin")
        page.goto(f"{server.url}/ui/joints")
        assert page.url.endswith("/ui/signin")  # signed out for good

        page.goto(f"{server.url}/docs")
        page.wait_for_selector(".swagger-ui .info .title", timeout=30000)
        assert "jointdb" in page.inner_text(".swagger-ui .info .title")
        page.wait_for_selector(".opblock", timeout=30000)
        assert page.locator(".opblock").count() > 10  # the operations are listed
        assert page.locator(".btn.authorize").count() == 1  # the bearer scheme: an Authorize button
        browser.close()
    assert not outside, outside
    csp = [m for m in problems if "Content Security Policy" in m or "Refused" in m]
    assert not csp, csp
    assert not problems, problems
