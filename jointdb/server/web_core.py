"""What every web page shares: the router under ``/ui``, the templates, the browser session
(:func:`_session`), the CSRF token of its forms, the sign-in redirect, and :func:`_handle`
(pages run in the thread pool, their errors become pages). See :mod:`jointdb.server.web`."""

from __future__ import annotations

import hashlib
import hmac
import secrets
from pathlib import Path
from typing import Any
from urllib.parse import parse_qs

from fastapi import APIRouter, Request
from fastapi.responses import HTMLResponse, RedirectResponse, Response
from fastapi.templating import Jinja2Templates

from jointdb.errors import InputError, JointdbError
from jointdb.server._deps import SESSION_COOKIE, same_origin, session_csrf
from jointdb.store._tokens import session_user

HERE = Path(__file__).parent
templates = Jinja2Templates(directory=str(HERE / "templates"))
router = APIRouter(prefix="/ui", include_in_schema=False)
#: The pre-session cookie of the sign-in form (its CSRF double submit).
SIGNIN_COOKIE = "jointdb_signin"
_NONCE_CHARS = frozenset("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789-_")


def _session(request: Request) -> tuple[str | None, Any]:
    """``(session_id, token info)`` of the request's open session, or ``(None, None)``
    (then a cookie that was sent is marked to be cleared)."""
    cached = getattr(request.state, "web_session", None)
    if cached is not None:
        return cached
    sid = request.cookies.get(SESSION_COOKIE)
    settings = request.app.state.settings
    info = session_user(request.app.state.repo, sid, settings.session_idle_s) if sid else None
    if info is not None:
        request.state.actor = info.name
    elif sid:
        request.state.stale_session = True
    request.state.web_session = (sid if info else None, info)
    return request.state.web_session


def _mac(key: str, purpose: bytes) -> str:
    return hmac.new(key.encode(), purpose, hashlib.sha256).hexdigest()


#: The CSRF token of a session's forms (bound to the session id, which only the HttpOnly cookie holds).
_csrf = session_csrf


def _set_cookie(request: Request, resp: Response, name: str, value: str, max_age: int, path: str = "/") -> None:
    resp.set_cookie(name, value, httponly=True, samesite="strict", path=path, max_age=max_age,
                    secure=request.app.state.settings.cookie_secure)


def _signin_nonce(request: Request) -> str | None:
    nonce = request.cookies.get(SIGNIN_COOKIE) or ""
    return nonce if len(nonce) == 43 and set(nonce) <= _NONCE_CHARS else None


class _NeedSignIn(Exception):
    pass


def _page(request: Request, template: str, status: int = 200, **ctx: Any) -> HTMLResponse:
    sid, who = _session(request)
    ctx.setdefault("title", template.split(".")[0])
    nonce = None
    if template == "signin.html":  # the sign-in form's CSRF token, bound to a pre-session cookie
        nonce = _signin_nonce(request) or secrets.token_urlsafe(32)
        ctx["signin_csrf"] = _mac(nonce, b"jointdb-signin")
    resp = templates.TemplateResponse(request, template, {"who": who, "csrf": _csrf(sid), **ctx},
                                      status_code=status)
    if nonce is not None and nonce != _signin_nonce(request):
        _set_cookie(request, resp, SIGNIN_COOKIE, nonce, 3600, path="/ui/signin")
    return resp


def _reader(request: Request):
    _, who = _session(request)
    if who is None and not request.app.state.settings.open_reads:
        raise _NeedSignIn()
    return who


def _same_origin(request: Request) -> None:
    """Refuse a browser POST sent from another site (``Origin`` of another host, or ``null``).

    The host is the request's ``Host`` or, behind a proxy that rewrites it, the proxy's
    ``X-Forwarded-Host`` (a cross-site form cannot set that header)."""
    if not same_origin(request):
        raise PermissionError("this form was sent from another site; open the page on this server and try again")


def _form(request: Request) -> dict[str, str]:
    """The posted form's fields (the body was read by :func:`_handle` before the worker thread)."""
    _same_origin(request)
    body = getattr(request.state, "form_body", b"").decode("utf-8", "replace")
    return {k: v[-1] for k, v in parse_qs(body, keep_blank_values=True).items()}


def _writer_form(request: Request, form: dict[str, str]):
    sid, who = _session(request)
    if who is None:
        raise _NeedSignIn()
    if not hmac.compare_digest(form.get("csrf", ""), _csrf(sid)):
        raise InputError("the form's CSRF token does not match your session; reload the page and try again")
    if not who.allows("writer"):
        raise PermissionError(f"the token of {who.name} has role {who.role}; this needs writer")
    return who


def _handle(fn):
    """Run the page ``fn`` (a plain function: it calls the synchronous repository) in the
    thread pool, so a slow database never blocks the event loop; map its errors to the page
    with a one-line message (or to the sign-in page), and clear the cookie of a session that
    is no longer open. A POST's body is read here, on the loop, for :func:`_form`."""
    import functools

    from starlette.concurrency import run_in_threadpool

    @functools.wraps(fn)
    async def wrapper(request: Request, *args, **kwargs):
        if request.method == "POST":
            request.state.form_body = await request.body()
        return await run_in_threadpool(_respond, fn, request, *args, **kwargs)

    return wrapper


def _respond(fn, request: Request, *args, **kwargs) -> Response:
    """``fn(request, ...)``, its errors as pages (see :func:`_handle`); runs in a worker thread."""
    try:
        resp = fn(request, *args, **kwargs)
    except _NeedSignIn:
        resp = RedirectResponse("/ui/signin", status_code=303)
    except PermissionError as exc:
        resp = _page(request, "base.html", 403, title="not allowed", error=str(exc))
    except JointdbError as exc:  # the same one-line, scrubbed message the API would give
        from jointdb.server._safety import client_error

        status, text = client_error(exc, request.scope.get("state", {}).get("request_id"))
        resp = _page(request, "signin.html" if status == 401 else "base.html", status, error=text)
    if getattr(request.state, "stale_session", False):
        resp.delete_cookie(SESSION_COOKIE, path="/", httponly=True, samesite="strict",
                           secure=request.app.state.settings.cookie_secure)
    return resp


def _float(text: str | None, what: str) -> float | None:
    if text is None or text.strip() == "":
        return None
    try:
        return float(text)
    except ValueError:
        raise InputError(f"{what}: {text[:40]!r} is not a number") from None
