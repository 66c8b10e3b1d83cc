"""The catalogue pages under ``/ui``: the joint list with facets built from the data, a joint's
page (k, c ± σ, verdict, conditions in engineering units, interactive plots, versions, labels),
the overlay of two versions, downloads, label / deprecate with a confirmation step and an
undo, and the nearest-joint form. Sessions, CSRF and error pages: :mod:`jointdb.server.web_core`.
"""

from __future__ import annotations

import json
from typing import Any
from urllib.parse import quote, urlencode

from fastapi import Request
from fastapi.responses import RedirectResponse, Response

from jointdb.errors import InputError, NotPermittedError
from jointdb.server import web_format as wf
from jointdb.server._deps import version_json
from jointdb.server.web_core import _float, _form, _handle, _page, _reader, _writer_form, router
from jointdb.store._listing import listing_facets
from jointdb.store._tokens import check_may_change

PAGE = 50
#: The facets of the list: query parameter -> (label, unit shown, factor from the unit to SI).
RANGES = {"torque": ("clamping torque", "N·m", 1.0), "force": ("drawbar force / preload", "kN", 1000.0),
          "diameter": ("diameter", "mm", 1e-3)}


def _diameter(c: dict) -> float | None:
    """The first diameter the conditions give (shank or taper), in m."""
    for key, value in sorted((c.get("geometry") or {}).items()):
        if "diameter" in key:
            return float(value)
    return None


def _catalogue_facets(r) -> dict[str, list[str]]:
    """The values of the catalogue to choose from (types, materials, combos, tapers, labels), read in
    SQL and kept per query stamp (:func:`jointdb.store._listing.listing_facets`)."""
    with r.read_engine.connect() as conn:
        return listing_facets(conn, r.url)


def _unknown_material(chosen: list[str], facets: dict) -> str | None:
    """A friendly message for a material no catalogued joint has (None when all are known)."""
    unknown = [m for m in chosen if m not in facets["materials"]]
    if not unknown:
        return None
    return (f"no catalogued joint has the material {unknown[0][:40]!r}; choose among "
            f"{', '.join(facets['materials']) or 'none yet'}")


def _range(p, key: str) -> tuple[float | None, float | None]:
    label, unit, factor = RANGES[key]
    lo, hi = (_float(p.get(f"{key}_{end}"), f"{label} {end} [{unit}]") for end in ("min", "max"))
    return (None if lo is None else lo * factor), (None if hi is None else hi * factor)


def _row(v: dict) -> dict[str, str]:
    """A version as the cells of the list (engineering units, empty when not recorded)."""
    c = v["conditions"]
    d = _diameter(c)
    return {"torque": wf.num(c["torque_nm"]) if c.get("torque_nm") is not None else "",
            "force": wf.num(c["preload_n"] / 1000.0) if c.get("preload_n") is not None else "",
            "diameter": wf.num(d * 1000.0) if d is not None else "",
            "taper": str((c.get("extra") or {}).get("taper") or ""), "materials": " + ".join(c["materials"])}


def _in(x: float | None, lo: float | None, hi: float | None) -> bool:
    if lo is None and hi is None:
        return True
    return x is not None and (lo is None or x >= lo) and (hi is None or x <= hi)


def _list_filters(p) -> dict[str, Any]:
    """The form's filters that the listing's SQL applies (everything but diameter and taper)."""
    torque, force = _range(p, "torque"), _range(p, "force")
    state = p.get("state") or ""
    return dict(joint_type=p.get("type") or None, materials=[m for m in p.getlist("material") if m.strip()],
                label=p.get("label") or None, include_deprecated=state != "active",
                state=state if state in ("active", "deprecated") else None, torque_min=torque[0],
                torque_max=torque[1], preload_min=force[0], preload_max=force[1], name_contains=p.get("q") or None)


def _scanned(r, p, offset: int) -> tuple[list[dict], int, bool]:
    """A page filtered on diameter or taper too: those are not index columns, so the listing's
    matches are read whole and filtered here; ``(page, total, more)``."""
    diameter, taper = _range(p, "diameter"), p.get("taper") or ""
    found = [version_json(v) for v in r.list_page(**_list_filters(p), limit=None).items]
    found = [v for v in found if _in(_diameter(v["conditions"]), *diameter)
             and (not taper or (v["conditions"].get("extra") or {}).get("taper") == taper)]
    return found[offset:offset + PAGE], len(found), offset + PAGE < len(found)


def _listed(r, p, facets: dict, offset: int) -> tuple[list[dict], int, str | None, str | None]:
    """One page of the list: ``(versions, total, next cursor, message)``. Without a diameter or taper
    filter a page is one keyset page of the listing (O(page) rows); with one, see :func:`_scanned`."""
    chosen = [m for m in p.getlist("material") if m.strip()]
    if _unknown_material(chosen, facets):
        return [], 0, None, _unknown_material(chosen, facets)
    if any(p.get(k) for k in ("taper", "diameter_min", "diameter_max")):
        found, total, more = _scanned(r, p, offset)
        return found, total, ("" if more else None), None
    page = r.list_page(**_list_filters(p), after=p.get("after") or None, limit=PAGE)
    return [version_json(v) for v in page.items], page.total, page.next, None


@router.get("/joints")
@_handle
def joints(request: Request):
    _reader(request)
    r, p = request.app.state.repo, request.query_params
    facets = _catalogue_facets(r)
    f = {k: p.get(k, "") for k in ("type", "taper", "label", "state", "q", "torque_min", "torque_max", "force_min",
                                    "force_max", "diameter_min", "diameter_max")}
    f["material"] = p.getlist("material")
    offset = int(p["offset"]) if (p.get("offset") or "").isdigit() else 0
    error = None
    try:
        found, total, cursor, error = _listed(r, p, facets, offset)
    except InputError as exc:  # a range that is not a number, a stale cursor: the form stays, with the message
        found, total, cursor, error = [], 0, None, str(exc)
    items = [(v, _row(v)) for v in found]
    query = [(k, v) for k, v in p.multi_items() if v and k not in ("offset", "after")]
    after = [("after", cursor)] if cursor else []  # keyset (or, for a scanned page, the offset alone)
    nxt = f"/ui/joints?{urlencode(query + after + [('offset', offset + PAGE)])}" if cursor is not None else None
    first = f"/ui/joints?{urlencode(query)}" if offset else None
    return _page(request, "joints.html", 422 if error else 200, title="joints", items=items, total=total,
                 offset=offset, f=f, facets=facets, next=nxt, prev=first, error=error, ranges=RANGES)


def _plots_json(plots: list[dict]) -> list[str]:
    """Plot specs as JSON text safe inside ``<script type="application/json">``."""
    return [json.dumps(p, separators=(",", ":")).replace("<", "\\u003c") for p in plots]


def _provenance_rows(v: dict) -> list[tuple[str, str]]:
    p = v["provenance"]
    params = p.get("parameters") or {}
    rows = [("method", p.get("method") or "–"), ("author", p.get("author") or "–"),
            ("software", f"jointdb {p.get('software_version') or '–'}"), ("catalogued", v["created_at"][:19].replace("T", " ") + " UTC")]
    if params.get("campaign"):
        rows.append(("campaign", str(params["campaign"])))
    if params.get("job"):
        rows.append(("identify job", str(params["job"])))
    iface = params.get("interface") or {}
    if iface:
        rows.append(("interface", f"{iface.get('a')} {' '.join(iface.get('a_dofs', []))} ↔ "
                                  f"{iface.get('b')} {' '.join(iface.get('b_dofs', []))}"))
    settings = params.get("settings") or {}
    if settings:
        rows.append(("settings", ", ".join(f"{k} = {wf.num(x) if isinstance(x, (int, float)) else x}"
                                           for k, x in settings.items())))
    for name, sha in (p.get("input_files") or {}).items():
        rows.append((f"input file {name}", f"SHA-256 {str(sha)[:16]}…"))
    return rows


def _label_history(r, name: str) -> list[dict[str, str]]:
    """Labels and deprecations of a joint, newest first, as sentences."""
    out = []
    for e in r.audit(name, limit=200):
        d, ver = e.get("details") or {}, e.get("version")
        what = {"label": lambda: f"label {d.get('label')} → v{ver}" + (
                    f" (was v{d['previous_version']})" if d.get("previous_version") else " (new)"),
                "unlabel": lambda: f"label {d.get('label')} removed (was v{d.get('previous_version')})",
                "deprecate": lambda: f"deprecated {'v' + str(ver) if ver else 'the joint'}"
                                     + (f": {d.get('reason')}" if d.get("reason") else ""),
                "undeprecate": lambda: f"deprecation undone for {'v' + str(ver) if ver else 'the joint'}"}.get(e["action"])
        if what is not None:
            out.append({"at": e["at"].replace("T", " ")[:19], "actor": e["actor"], "what": what()})
    return out


def _refusal(r, who, name: str) -> str | None:
    """Why a signed-in writer may not label or deprecate this joint (None: they may)."""
    if who is None or not who.allows("writer"):
        return None
    try:
        check_may_change(r, who, name, "label or deprecate")
    except NotPermittedError as exc:
        return str(exc)
    return None


@router.get("/joints/{name}")
@_handle
def joint(request: Request, name: str):
    from jointdb.server.routes_joints import joint_name

    who = _reader(request)
    r, p = request.app.state.repo, request.query_params
    version = p.get("version")
    jv = r.get(joint_name(name), int(version) if version and version.isdigit() else None)
    v, frf = version_json(jv), r.load_frf(jv)
    kc, kc_source = wf.kc_rows(v, frf)
    ok, verdict = wf.verdict(v)
    plots = wf.frf_plots([(f"v{jv.version}", frf)], f"{jv.name} v{jv.version}") + wf.kc_plots(frf, f"v{jv.version}")
    history = [(h, _row(h)) for h in map(version_json, r.history(jv.name))]
    undo = p.get("undo", "")
    return _page(request, "joint.html", title=jv.name, v=v, conditions=wf.condition_rows(v["conditions"], v["joint_type"]),
                 kc=kc, kc_source=kc_source, ok=ok, verdict=verdict, plots=_plots_json(plots), history=history,
                 labels=_label_history(r, jv.name), provenance=_provenance_rows(v), undo=_undo_form(undo),
                 notice=p.get("notice"), refusal=_refusal(r, who, jv.name), force_name=wf.force_name(v["joint_type"]))


def _undo_form(undo: str) -> dict | None:
    """The hidden fields of the undo button after a change (``undo`` = ``label:NAME:PREV`` or
    ``deprecate:VERSION``); None when there is nothing to undo."""
    parts = undo.split(":")
    if parts[0] == "label" and len(parts) == 3:
        if parts[2].isdigit():
            return {"action": "label", "fields": {"label": parts[1], "version": parts[2]},
                    "text": f"undo: point {parts[1]} back at v{parts[2]}"}
        return {"action": "unlabel", "fields": {"label": parts[1]}, "text": f"undo: remove label {parts[1]}"}
    if parts[0] == "deprecate" and len(parts) == 2 and (parts[1].isdigit() or parts[1] == ""):
        return {"action": "undeprecate", "fields": {"version": parts[1]},
                "text": f"undo: make {'v' + parts[1] if parts[1] else 'the joint'} active again"}
    return None


@router.get("/joints/{name}/overlay")
@_handle
def overlay(request: Request, name: str):
    from jointdb.server.routes_joints import joint_name

    _reader(request)
    r = request.app.state.repo
    try:
        a, b = int(request.query_params.get("a", "")), int(request.query_params.get("b", ""))
    except ValueError:
        raise InputError("choose two version numbers a and b") from None
    name = joint_name(name)
    va, vb = r.get(name, a), r.get(name, b)
    fa, fb = r.load_frf(va), r.load_frf(vb)
    plots = wf.frf_plots([(f"v{a}", fa), (f"v{b}", fb)], f"{name} v{a} and v{b}")
    d = r.diff(name, a, b)
    ja, jb = version_json(va), version_json(vb)
    conds = _merge_rows(wf.condition_rows(ja["conditions"], ja["joint_type"]),
                        wf.condition_rows(jb["conditions"], jb["joint_type"]))
    return _page(request, "overlay.html", title=f"{name} overlay", name=name, a=a, b=b, plots=_plots_json(plots),
                 diff=d, conds=conds, provenance=_merge_rows(_provenance_rows(ja), _provenance_rows(jb)),
                 kc=_merge_kc(wf.kc_rows(ja, fa)[0], wf.kc_rows(jb, fb)[0]), colours=wf.COLOURS)


def _merge_kc(a: list[dict], b: list[dict]) -> list[tuple[str, str, str, bool]]:
    rows = lambda kc: [(f"{p} {r['dof']}", f"{r[p]} {r[p + '_sigma']}") for r in kc for p in ("k", "c")]  # noqa: E731
    return _merge_rows(rows(a), rows(b))


def _merge_rows(a: list[tuple[str, str]], b: list[tuple[str, str]]) -> list[tuple[str, str, str, bool]]:
    """``(what, value in a, value in b, differs)`` for the union of two row lists, in order."""
    da, db = dict(a), dict(b)
    keys = list(dict.fromkeys([k for k, _ in a] + [k for k, _ in b]))
    return [(k, da.get(k, "–"), db.get(k, "–"), da.get(k) != db.get(k)) for k in keys]


@router.get("/joints/{name}/versions/{version}/frf")
@_handle
def download(request: Request, name: str, version: int):
    from jointdb.server.routes_frf import FORMATS, encoded_frf, etag
    from jointdb.server.routes_joints import joint_name

    _reader(request)
    r = request.app.state.repo
    fmt = request.query_params.get("format", "hdf5")
    if fmt not in FORMATS:
        raise InputError(f"format {fmt[:20]!r} must be one of {', '.join(FORMATS)}")
    jv = r.get(joint_name(name), version)
    media, suffix = FORMATS[fmt]
    safe = "".join(ch if ch.isalnum() or ch in "-_." else "_" for ch in jv.name)
    # a signed-in download is not kept in the browser's cache (a shared computer would still
    # have it after sign-out); open reads are public and never change: cached for a year
    cache = "public, max-age=31536000, immutable" if request.app.state.settings.open_reads else "no-store"
    return Response(encoded_frf(request, r, jv, fmt), media_type=media,
                    headers={"ETag": etag(jv.record_sha256, fmt), "Cache-Control": cache,
                             "Content-Disposition": f'attachment; filename="{safe}-v{version}{suffix}"'})


def _version_field(form: dict[str, str]) -> int | None:
    version = form.get("version", "").strip()
    if version and not version.isdigit():
        raise InputError(f"version {version[:20]!r} must be a number")
    return int(version) if version else None


def _confirm_text(r, name: str, action: str, version: int | None, form: dict[str, str]) -> str:
    """What a change will do, in one sentence (the confirmation step)."""
    if action == "label":
        current = {lab: v for v, lab in ((h.version, lab) for h in r.history(name) for lab in h.labels)}
        was = current.get(form.get("label", ""))
        return (f"Point label {form.get('label', '')!r} of {name} at v{version}"
                + (f" (it now points at v{was})?" if was else " (a new label)?"))
    if action == "deprecate":
        what = f"v{version} of {name}" if version else f"the whole joint {name} (all its versions)"
        return f"Deprecate {what}? It stays in the catalogue but is no longer chosen by nearest-joint queries."
    if action == "unlabel":
        return f"Remove label {form.get('label', '')!r} of {name}?"
    return f"Make {'v' + str(version) if version else name} active again?"


@router.post("/joints/{name}/{action}")
@_handle
def write(request: Request, name: str, action: str):
    from jointdb.server.routes_joints import joint_name

    form = _form(request)
    who = _writer_form(request, form)
    r = request.app.state.repo
    name = joint_name(name)
    version = _version_field(form)
    if action not in ("label", "deprecate", "undeprecate", "unlabel"):
        raise InputError(f"unknown action {action[:20]!r}")
    check_may_change(r, who, name, action)
    if action == "label" and version is None:
        raise InputError("give the version the label should point at")
    if form.get("confirm") != "1":  # the confirmation step: nothing is written yet
        return _page(request, "confirm.html", title=f"confirm: {action}", name=name, action=action,
                     question=_confirm_text(r, name, action, version, form),
                     fields={k: x for k, x in form.items() if k not in ("csrf", "confirm")})
    if action == "label":
        label = form.get("label", "")
        before = {lab: h.version for h in r.history(name) for lab in h.labels}.get(label)
        r.label(name, version, label, author=who.name)
        notice, undo = f"label {label} now points at v{version}", f"label:{label}:{before or ''}"
    elif action == "unlabel":
        r.unlabel(name, form.get("label", ""), author=who.name)
        notice, undo = f"label {form.get('label', '')} removed", ""
    else:
        r.deprecate(name, version, reason=form.get("reason", ""), author=who.name, undo=action == "undeprecate")
        what = f"v{version}" if version else "the joint"
        notice = f"{'deprecated' if action == 'deprecate' else 'made active again:'} {what}"
        undo = f"deprecate:{version or ''}" if action == "deprecate" else ""
    query = {"notice": notice, **({"undo": undo} if undo else {})}
    return RedirectResponse(f"/ui/joints/{quote(name, safe='')}?{urlencode(query)}", status_code=303)


def _nearest_body(q: dict[str, str], p):
    from jointdb.server._schemas import ConditionsIn, NearestIn

    geometry = {}
    if q["diameter_mm"].strip():
        key = q["diameter_key"] if q["diameter_key"] in ("shank_diameter_m", "taper_diameter_m") else "shank_diameter_m"
        geometry[key] = _float(q["diameter_mm"], "diameter [mm]") / 1000.0
    force = _float(q["force_kn"], "drawbar force / preload [kN]")
    k = q["k"] if q["k"].isdigit() else "3"
    return NearestIn(joint_type=q["joint_type"], k=max(1, min(50, int(k))), conditions=ConditionsIn(
        materials=[m.strip() for m in q["materials"].split("+") if m.strip()], torque_nm=_float(q["torque_nm"], "torque [N·m]"),
        preload_n=None if force is None else force * 1000.0, geometry=geometry))


@router.get("/nearest")
@_handle
def nearest(request: Request):
    from jointdb.server.routes_query import match_json, run_nearest

    _reader(request)
    r, p = request.app.state.repo, request.query_params
    facets = _catalogue_facets(r)
    q = {k: p.get(k, d) for k, d in (("joint_type", ""), ("torque_nm", ""), ("force_kn", ""), ("diameter_mm", ""),
                                     ("diameter_key", "shank_diameter_m"), ("k", "3"))}
    q["materials"] = p.get("materials", "")
    matches, notes, error = None, [], None
    if q["joint_type"]:
        unknown = _unknown_material([m.strip() for m in q["materials"].split("+") if m.strip()], facets)
        try:
            if unknown:
                raise InputError(unknown)
            found, notes = run_nearest(r, _nearest_body(q, p))
            notes = [wf.humanise_text(n) for n in notes]
            matches = [(match_json(m), _row(version_json(m.version)), per_condition_text(m.per_condition)) for m in found]
        except InputError as exc:  # the form stays, with the message
            error = str(exc)
    return _page(request, "nearest.html", 422 if error else 200, title="nearest joint", q=q, matches=matches,
                 warnings=notes, facets=facets, error=error, force_name=wf.force_name(q["joint_type"]))


def per_condition_text(per: dict[str, Any]) -> str:
    """The per-condition distance terms as readable text."""
    return ", ".join(f"{wf.humanise(k)} {wf.num(x, 3)}" for k, x in per.items())
