"""The web catalogue under ``/ui``: server-rendered pages (Jinja2), SVG plots drawn on the
server, CSS bundled in the package (works with no internet).

Sign-in: the token is posted once from a form and kept in a cookie that is HttpOnly,
SameSite=Strict and scoped to ``/ui`` (Secure when ``JOINTDB_SECURE_COOKIES``); it never
appears in a URL. Every form that writes carries a CSRF token derived from the session
(HMAC of the token's hash), checked before anything is done.
"""

from __future__ import annotations

import hashlib
import hmac
from pathlib import Path
from typing import Any
from urllib.parse import parse_qs, urlencode, quote

from fastapi import APIRouter, Request
from fastapi.responses import HTMLResponse, RedirectResponse, Response
from fastapi.staticfiles import StaticFiles
from fastapi.templating import Jinja2Templates

from jointdb.errors import InputError, JointdbError
from jointdb.server._deps import SESSION_COOKIE, version_json
from jointdb.store._tokens import authenticate, token_sha256

HERE = Path(__file__).parent
templates = Jinja2Templates(directory=str(HERE / "templates"))
router = APIRouter(prefix="/ui", include_in_schema=False)


def _session(request: Request):
    token = request.cookies.get(SESSION_COOKIE)
    info = authenticate(request.app.state.repo, token) if token else None
    if info is not None:
        request.state.actor = info.name
    return token if info else None, info


def _csrf(token: str | None) -> str:
    if not token:
        return ""
    return hmac.new(token_sha256(token).encode(), b"jointdb-csrf", hashlib.sha256).hexdigest()


class _NeedSignIn(Exception):
    pass


def _page(request: Request, template: str, status: int = 200, **ctx: Any) -> HTMLResponse:
    token, who = _session(request)
    ctx.setdefault("title", template.split(".")[0])
    return templates.TemplateResponse(request, template, {"who": who, "csrf": _csrf(token), **ctx},
                                      status_code=status)


def _reader(request: Request):
    token, who = _session(request)
    if who is None and not request.app.state.settings.open_reads:
        raise _NeedSignIn()
    return who


async def _form(request: Request) -> dict[str, str]:
    body = (await request.body()).decode("utf-8", "replace")
    return {k: v[-1] for k, v in parse_qs(body, keep_blank_values=True).items()}


def _writer_form(request: Request, form: dict[str, str]):
    token, who = _session(request)
    if who is None:
        raise _NeedSignIn()
    if not hmac.compare_digest(form.get("csrf", ""), _csrf(token)):
        raise InputError("the form's CSRF token does not match your session; reload the page and try again")
    if not who.allows("writer"):
        raise PermissionError(f"the token of {who.name} has role {who.role}; this needs writer")
    return who


def _handle(fn):
    """Map errors of a page to the page with a one-line message (or to the sign-in page)."""
    import functools

    @functools.wraps(fn)
    async def wrapper(request: Request, *args, **kwargs):
        try:
            return await fn(request, *args, **kwargs)
        except _NeedSignIn:
            return RedirectResponse("/ui/signin", status_code=303)
        except PermissionError as exc:
            return _page(request, "signin.html", 403, error=str(exc))
        except JointdbError as exc:
            status = exc.http_status if exc.http_status < 500 else 500
            return _page(request, "signin.html" if status == 401 else "base.html", status, error=str(exc))

    return wrapper


def _float(text: str | None, what: str) -> float | None:
    if text is None or text.strip() == "":
        return None
    try:
        return float(text)
    except ValueError:
        raise InputError(f"{what}: {text[:40]!r} is not a number") from None


@router.get("")
@router.get("/")
async def home() -> RedirectResponse:
    return RedirectResponse("/ui/joints", status_code=303)


@router.get("/signin")
@_handle
async def signin_page(request: Request):
    return _page(request, "signin.html", title="sign in")


@router.post("/signin")
@_handle
async def signin(request: Request):
    form = await _form(request)
    token = form.get("token", "").strip()
    if authenticate(request.app.state.repo, token) is None:
        return _page(request, "signin.html", 401, error="token not accepted (unknown, revoked or expired)")
    resp = RedirectResponse("/ui/joints", status_code=303)
    resp.set_cookie(SESSION_COOKIE, token, httponly=True, samesite="strict", path="/ui",
                    secure=request.app.state.settings.secure_cookies, max_age=12 * 3600)
    return resp


@router.post("/signout")
@_handle
async def signout(request: Request):
    form = await _form(request)
    token, _ = _session(request)
    if token and not hmac.compare_digest(form.get("csrf", ""), _csrf(token)):
        raise InputError("the form's CSRF token does not match your session")
    resp = RedirectResponse("/ui/signin", status_code=303)
    resp.delete_cookie(SESSION_COOKIE, path="/ui")
    return resp


@router.get("/joints")
@_handle
async def joints(request: Request):
    from jointdb.server.routes_joints import filter_versions

    _reader(request)
    p = request.query_params
    f = {k: p.get(k) for k in ("type", "material", "torque_min", "torque_max", "q", "active_only")}
    offset = max(0, int(p.get("offset", "0") or 0)) if (p.get("offset", "0") or "0").isdigit() else 0
    found = filter_versions(request.app.state.repo, f["type"] or None,
                            [m for m in (f["material"] or "").replace("+", ",").split(",") if m.strip()], None,
                            not f["active_only"], _float(f["torque_min"], "torque from"),
                            _float(f["torque_max"], "torque to"), None, None, f["q"] or None)
    limit = 50
    items = [version_json(v) for v in found[offset:offset + limit]]
    query = {k: v for k, v in f.items() if v}
    nxt = f"/ui/joints?{urlencode({**query, 'offset': offset + limit})}" if offset + limit < len(found) else None
    prev = f"/ui/joints?{urlencode({**query, 'offset': max(0, offset - limit)})}" if offset else None
    return _page(request, "joints.html", title="joints", items=items, total=len(found), offset=offset, f=f,
                 next=nxt, prev=prev)


@router.get("/joints/{name}")
@_handle
async def joint(request: Request, name: str):
    from jointdb.server._svg import frf_svg
    from jointdb.server.routes_joints import joint_name

    _reader(request)
    r = request.app.state.repo
    version = request.query_params.get("version")
    jv = r.get(joint_name(name), int(version) if version and version.isdigit() else None)
    svg = frf_svg([(f"v{jv.version}", r.load_frf(jv))], f"{jv.name} v{jv.version} ({jv.quantity})")
    return _page(request, "joint.html", title=jv.name, v=version_json(jv), svg=svg,
                 history=[version_json(h) for h in r.history(jv.name)], audit=r.audit(jv.name, limit=200),
                 notice=request.query_params.get("notice"))


@router.get("/joints/{name}/overlay")
@_handle
async def overlay(request: Request, name: str):
    from jointdb.server._svg import frf_svg
    from jointdb.server.routes_joints import joint_name

    _reader(request)
    r = request.app.state.repo
    try:
        a, b = int(request.query_params.get("a", "")), int(request.query_params.get("b", ""))
    except ValueError:
        raise InputError("choose two version numbers a and b") from None
    name = joint_name(name)
    va, vb = r.get(name, a), r.get(name, b)
    svg = frf_svg([(f"v{a}", r.load_frf(va)), (f"v{b}", r.load_frf(vb))], f"{name}: v{a} (solid) and v{b} (dashed)")
    return _page(request, "overlay.html", title=f"{name} overlay", name=name, a=a, b=b, svg=svg,
                 diff=r.diff(name, a, b))


@router.get("/joints/{name}/versions/{version}/frf")
@_handle
async def download(request: Request, name: str, version: int):
    from jointdb.server.routes_frf import FORMATS, _cached, etag
    from jointdb.server.routes_joints import joint_name

    _reader(request)
    r = request.app.state.repo
    fmt = request.query_params.get("format", "hdf5")
    if fmt not in FORMATS:
        raise InputError(f"format {fmt[:20]!r} must be one of {', '.join(FORMATS)}")
    jv = r.get(joint_name(name), version)
    media, suffix = FORMATS[fmt]
    safe = "".join(ch if ch.isalnum() or ch in "-_." else "_" for ch in jv.name)
    return Response(_cached(r, jv.name, version, jv.record_sha256, fmt), media_type=media,
                    headers={"ETag": etag(jv.record_sha256, fmt), "Cache-Control": "private, max-age=31536000, immutable",
                             "Content-Disposition": f'attachment; filename="{safe}-v{version}{suffix}"'})


@router.post("/joints/{name}/{action}")
@_handle
async def write(request: Request, name: str, action: str):
    from jointdb.server.routes_joints import joint_name

    form = await _form(request)
    who = _writer_form(request, form)
    r = request.app.state.repo
    name = joint_name(name)
    version = form.get("version", "").strip()
    if version and not version.isdigit():
        raise InputError(f"version {version[:20]!r} must be a number")
    if action == "label":
        r.label(name, int(version or 0), form.get("label", ""), author=who.name)
        notice = f"label {form.get('label')} now points at v{version}"
    elif action == "deprecate":
        r.deprecate(name, int(version) if version else None, reason=form.get("reason", ""), author=who.name)
        notice = f"deprecated {'v' + version if version else 'the joint'}"
    else:
        raise InputError(f"unknown action {action[:20]!r}")
    return RedirectResponse(f"/ui/joints/{quote(name, safe='')}?{urlencode({'notice': notice})}", status_code=303)


@router.get("/nearest")
@_handle
async def nearest(request: Request):
    from jointdb.server._schemas import ConditionsIn, NearestIn
    from jointdb.server.routes_query import match_json, run_nearest

    _reader(request)
    p = request.query_params
    q = {"joint_type": p.get("joint_type", ""), "materials": p.get("materials", ""),
         "torque_nm": p.get("torque_nm", ""), "preload_n": p.get("preload_n", ""), "k": p.get("k", "3")}
    matches, notes = None, []
    if q["joint_type"]:
        k = q["k"] if q["k"].isdigit() else "3"
        body = NearestIn(joint_type=q["joint_type"], k=max(1, min(50, int(k))), conditions=ConditionsIn(
            materials=[m for m in q["materials"].replace("+", ",").split(",") if m.strip()],
            torque_nm=_float(q["torque_nm"], "torque"), preload_n=_float(q["preload_n"], "preload")))
        found, notes = run_nearest(request.app.state.repo, body)
        matches = [match_json(m) for m in found]
    return _page(request, "nearest.html", title="nearest joint", q=q, matches=matches, warnings=notes)


def mount(app) -> None:
    """Add the pages and the bundled static files to ``app``."""
    app.include_router(router)
    app.mount("/ui/static", StaticFiles(directory=str(HERE / "static")), name="static")
