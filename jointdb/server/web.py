"""The web pages under ``/ui``: server-rendered (Jinja2), interactive plots drawn in the browser
by uPlot, CSS and scripts bundled in the package (works with no internet; see
:mod:`jointdb.server.web_catalogue` for the catalogue pages, :mod:`jointdb.server.web_flow`
for the upload / design / lobes pages); and ``/docs``, Swagger UI served from the package.

Sign-in: the token is posted once from a form and exchanged for a server-side session
(:func:`jointdb.store._tokens.open_session`): the cookie holds only a random session id
(256 bits; the database keeps its SHA-256), never the token. Signing out revokes the
session in the database; an unknown, revoked, idle or expired session (or one whose token
was revoked) is signed out. Cookies are HttpOnly, SameSite=Strict, ``Secure`` unless the
server runs on loopback without TLS (:class:`Settings`); the session cookie is scoped to the
whole site, so the pages' scripts call the JSON API with it
(:func:`jointdb.server._deps.session_identity`: writes need the ``X-CSRF-Token`` header).

CSRF: every form carries a token checked before anything is done, and a browser POST
whose ``Origin`` is another site (or ``null``) is refused. The sign-in form's token is bound
to a pre-session cookie (double submit); the other forms' token to the session id
(HMAC keyed with it), so neither can be forged without reading an HttpOnly cookie.
"""

from __future__ import annotations

import hmac

from fastapi import Request
from fastapi.responses import HTMLResponse, RedirectResponse
from fastapi.staticfiles import StaticFiles

from jointdb.errors import InputError
from jointdb.server._deps import SESSION_COOKIE
from jointdb.server.web_core import (HERE, SIGNIN_COOKIE, _csrf, _form, _handle, _mac, _page,
                                     _session, _set_cookie,
                                     _signin_nonce, router, templates)
from jointdb.store._tokens import close_session, open_session

@router.get("")
@router.get("/")
async def home() -> RedirectResponse:
    return RedirectResponse("/ui/joints", status_code=303)


@router.get("/signin")
@_handle
def signin_page(request: Request):
    return _page(request, "signin.html", title="sign in")


@router.post("/signin")
@_handle
def signin(request: Request):
    form = _form(request)
    nonce = _signin_nonce(request)
    if nonce is None:
        return _page(request, "signin.html", 403, title="sign in", error=(
            "the sign-in form's cookie did not come back; reload this page and sign in again (over plain HTTP "
            "a Secure cookie is dropped: see JOINTDB_SECURE_COOKIES)"))
    if not hmac.compare_digest(form.get("csrf", ""), _mac(nonce, b"jointdb-signin")):
        raise InputError("the sign-in form's CSRF token does not match; reload the sign-in page and try again")
    settings, r = request.app.state.settings, request.app.state.repo
    opened = open_session(r, form.get("token", "").strip(), settings.session_lifetime_s)
    if opened is None:
        return _page(request, "signin.html", 401, title="sign in",
                     error="token not accepted (unknown, revoked or expired)")
    close_session(r, request.cookies.get(SESSION_COOKIE))  # a new sign-in never reuses a session id
    request.state.stale_session = False
    sid, session = opened
    request.state.actor = session.token.name
    resp = RedirectResponse("/ui/joints", status_code=303)
    lifetime = max(1, int((session.expires_at - session.created_at).total_seconds()))
    _set_cookie(request, resp, SESSION_COOKIE, sid, lifetime)
    resp.delete_cookie(SIGNIN_COOKIE, path="/ui/signin", httponly=True, samesite="strict",
                       secure=settings.cookie_secure)
    return resp


@router.post("/signout")
@_handle
def signout(request: Request):
    form = _form(request)
    sid, _ = _session(request)
    if sid and not hmac.compare_digest(form.get("csrf", ""), _csrf(sid)):
        raise InputError("the form's CSRF token does not match your session")
    close_session(request.app.state.repo, sid)
    resp = RedirectResponse("/ui/signin", status_code=303)
    resp.delete_cookie(SESSION_COOKIE, path="/", httponly=True, samesite="strict",
                       secure=request.app.state.settings.cookie_secure)
    return resp


def mount(app) -> None:
    """Add the pages, the bundled static files and ``/docs`` (Swagger UI from the package) to
    ``app``. FastAPI's own ``/docs``, ``/docs/oauth2-redirect`` and ``/redoc`` pages load
    their scripts from a CDN with inline code: they are replaced (``/docs``) or removed."""
    from jointdb.server import web_catalogue, web_flow  # noqa: F401 - their pages join ``router``

    app.include_router(router)

    @app.get("/", include_in_schema=False)
    def root() -> RedirectResponse:
        return RedirectResponse("/ui/joints", status_code=303)

    app.mount("/ui/static", StaticFiles(directory=str(HERE / "static")), name="static")
    cdn_pages = {app.docs_url, app.redoc_url, app.swagger_ui_oauth2_redirect_url} - {None}
    app.router.routes[:] = [rt for rt in app.router.routes if getattr(rt, "path", None) not in cdn_pages]
    openapi_url = app.openapi_url or "/openapi.json"

    @app.get("/docs", include_in_schema=False)
    def docs(request: Request) -> HTMLResponse:
        return templates.TemplateResponse(request, "docs.html", {"openapi_url": openapi_url,
                                                                 "title": f"{app.title} API"})
