"""Shared pieces of the routes: the repository of the running app, who is asking
(token -> owner and role), pagination, and the JSON form of versions and FRFs."""

from __future__ import annotations

import hashlib
import hmac
from typing import Any
from urllib.parse import urlsplit

from fastapi import Depends, HTTPException, Query, Request, Security
from fastapi.security import HTTPBearer
from starlette.concurrency import run_in_threadpool

from jointdb.store._tokens import TokenInfo, authenticate, check_may_change

SESSION_COOKIE = "jointdb_session"
#: The header that carries a browser session's CSRF token on the API's writes (the pages send it).
CSRF_HEADER = "x-csrf-token"
_SAFE_METHODS = ("GET", "HEAD", "OPTIONS")
#: The OpenAPI security scheme of the API (the header itself is read by :func:`bearer`).
BEARER = HTTPBearer(auto_error=False, scheme_name="bearer", bearerFormat="jdb_<id>_<secret>",
                    description="An API token (`jointdb tokens create`), sent as `Authorization: Bearer <token>`.")


async def repo(request: Request):
    """The app's :class:`jointdb.store.Repository` (one per worker process).

    ``async`` because it does no I/O: FastAPI runs a plain ``def`` dependency in its thread pool,
    one thread hop per request for nothing."""
    return request.app.state.repo


async def settings(request: Request):
    """The app's settings (no I/O, hence ``async``: no thread hop)."""
    return request.app.state.settings


def bearer(request: Request) -> str | None:
    """The token of an ``Authorization: Bearer`` header (API) — never read from a URL."""
    header = request.headers.get("authorization")
    if not header:
        return None
    scheme, _, value = header.partition(" ")
    if scheme.lower() != "bearer" or not value.strip():
        raise HTTPException(401, "the Authorization header must be 'Bearer <token>'",
                            headers={"WWW-Authenticate": "Bearer"})
    return value.strip()


def identify(request: Request, token: str | None) -> TokenInfo | None:
    """The active token's info (and the request's actor for the log), or None."""
    if token is None:
        return None
    info = authenticate(request.app.state.repo, token)
    if info is None:
        raise HTTPException(401, "token not accepted (unknown, revoked or expired)",
                            headers={"WWW-Authenticate": "Bearer"})
    request.state.actor = info.name
    return info


def session_csrf(session_id: str | None) -> str:
    """The CSRF token of a web session (HMAC keyed with the session id, which only the HttpOnly
    cookie holds): the pages' forms carry it, and their scripts send it as ``X-CSRF-Token``."""
    return hmac.new(session_id.encode(), b"jointdb-csrf", hashlib.sha256).hexdigest() if session_id else ""


def same_origin(request: Request) -> bool:
    """False for a browser request sent from another site (``Origin`` of another host, or ``null``)."""
    origin = request.headers.get("origin")
    if origin is None:
        return True
    hosts = {request.headers.get("host"), request.headers.get("x-forwarded-host", "").split(",")[0].strip()}
    return origin != "null" and urlsplit(origin).netloc in hosts - {None, ""}


def session_identity(request: Request) -> TokenInfo | None:
    """The signed-in user of a browser session (the pages' scripts call the API with it), or None.

    A write (any method but GET/HEAD/OPTIONS) must carry the session's CSRF token in
    ``X-CSRF-Token`` and come from this site: a cross-site page can send the cookie
    (not with SameSite=Strict, but defence in depth) but can neither read nor set that header."""
    from jointdb.store._tokens import session_user

    sid = request.cookies.get(SESSION_COOKIE)
    if not sid:
        return None
    info = session_user(request.app.state.repo, sid, request.app.state.settings.session_idle_s)
    if info is None:
        return None
    if request.method not in _SAFE_METHODS:
        if not same_origin(request):
            raise HTTPException(403, "this request was sent from another site")
        if not hmac.compare_digest(request.headers.get(CSRF_HEADER, ""), session_csrf(sid)):
            raise HTTPException(403, "a browser session's write needs its CSRF token in the X-CSRF-Token header")
    request.state.actor = info.name
    return info


def need(role: str, anonymous_reads: bool = True):
    """A dependency: the caller (API token, or browser session with CSRF on writes) must have ``role``.

    ``anonymous_reads``: with the server's open reads, a reader needs no identity (the
    dependency gives None); False for what belongs to somebody (jobs), which always needs one.
    """

    async def dependency(request: Request, _scheme=Security(BEARER)) -> TokenInfo | None:
        # async: a request without credentials is answered here on the event loop; only a token or a
        # session (a database read) goes to the thread pool - a plain ``def`` would cost every request a hop
        token = bearer(request)
        if token is not None:
            info = await run_in_threadpool(identify, request, token)
        elif request.cookies.get(SESSION_COOKIE):
            info = await run_in_threadpool(session_identity, request)
        else:
            info = None
        if info is None:
            if anonymous_reads and role == "reader" and request.app.state.settings.open_reads:
                return None
            raise HTTPException(401, f"this request needs a {role} token (Authorization: Bearer <token>)",
                                headers={"WWW-Authenticate": "Bearer"})
        if not info.allows(role):
            raise HTTPException(403, f"the token of {info.name} has role {info.role}; this request needs {role}")
        return info

    return dependency


def may_change(r, who: TokenInfo, name: str, action: str) -> None:
    """The ownership rule of labels and deprecations (403 otherwise): see
    :func:`jointdb.store._tokens.check_may_change`."""
    check_may_change(r, who, name, action)


reader = Depends(need("reader"))
writer = Depends(need("writer"))
admin = Depends(need("admin"))


class Page:
    """``offset``/``limit`` query parameters of every list (limit 1..500, default 50)."""

    def __init__(self, offset: int = Query(0, ge=0, le=10**9), limit: int = Query(50, ge=1, le=500)):
        self.offset, self.limit = offset, limit

    def of(self, items: list) -> dict[str, Any]:
        part = items[self.offset:self.offset + self.limit]
        end = self.offset + len(part)
        return {"items": part, "total": len(items), "offset": self.offset, "limit": self.limit,
                "next_offset": end if end < len(items) else None}


async def page(offset: int = Query(0, ge=0, le=10**9), limit: int = Query(50, ge=1, le=500)) -> Page:
    """The :class:`Page` of a request, as a dependency (``Depends(page)``): ``async`` because it does
    no I/O (a class dependency would cost a thread-pool hop per request)."""
    return Page(offset, limit)


def version_json(v) -> dict[str, Any]:
    """Everything of a :class:`jointdb.store.JointVersion` as JSON."""
    p = v.provenance
    return {
        "name": v.name, "joint_type": v.joint_type, "version": v.version, "uuid": v.uuid,
        "created_at": v.created_at.isoformat(), "state": v.state, "labels": list(v.labels),
        "conditions": v.conditions.to_dict(), "model_kind": v.model_kind, "dofs": list(v.dofs),
        "quantity": v.quantity, "n_freq": v.n_freq, "freq_min_hz": v.freq_min_hz, "freq_max_hz": v.freq_max_hz,
        "blob_sha256": v.blob_sha256, "record_sha256": v.record_sha256, "parent_version": v.parent_version,
        "provenance": {"method": p.method, "parameters": dict(p.parameters), "input_files": dict(p.input_files),
                       "software_version": p.software_version, "author": p.author},
        "quality": dict(v.quality), "raw_measurements": sorted(v.raw_blobs),
    }
