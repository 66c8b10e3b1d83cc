"""Read routes: joints list/filter, one version, history, diff, audit (all paginated lists)."""

from __future__ import annotations

import dataclasses
import json
from typing import Annotated, Any, Optional

from fastapi import APIRouter, Depends, Path, Query
from fastapi.responses import JSONResponse

from jointdb.errors import InputError
from jointdb.server._deps import Page, page, reader, repo, version_json
from jointdb.store._types import check_name

router = APIRouter(tags=["joints"])

#: a joint name in a URL: the catalogue's own rule (no '/'), checked again by check_name
Name = Annotated[str, Path(min_length=1, max_length=200, description="Joint name.")]


def joint_name(name: str) -> str:
    """The catalogue's name rule, applied to a path parameter (a path-like name is a 422)."""
    if name in (".", "..") or "\\" in name:
        raise InputError(f"joint name {name[:60]!r} must not be a path")
    return check_name(name)


def filter_versions(r, joint_type=None, material=None, label=None, include_deprecated=True, torque_min=None,
                    torque_max=None, preload_min=None, preload_max=None, q=None) -> list:
    """The current version of every joint that passes the filters (shared by the API and the web pages):
    :meth:`Repository.list_page` without a page limit (one SQL statement); damaged rows are left out."""
    page = r.list_page(joint_type or None, materials=material or (), label=label or None,
                       include_deprecated=include_deprecated, torque_min=torque_min, torque_max=torque_max,
                       preload_min=preload_min, preload_max=preload_max, name_contains=q or None, limit=None)
    return list(page.items)


def damaged_json(damaged) -> list[dict[str, Any]]:
    """Versions a list skipped because their stored rows are damaged: name, version, reason."""
    return [{"name": d.name, "version": d.version, "error": d.reason} for d in damaged]


@router.get("/joints", summary="List and filter joints (current version of each)")
def list_joints(
    page: Page = Depends(page),
    joint_type: Optional[str] = Query(None, alias="type", max_length=100, description="Joint type, e.g. tool-holder."),
    material: Optional[list[str]] = Query(None, description="Interface material (repeat: all must be present)."),
    label: Optional[str] = Query(None, max_length=100, description="Only joints with this label (shows that version)."),
    include_deprecated: bool = Query(True, description="Also list deprecated joints."),
    state: Optional[str] = Query(None, pattern="^(active|deprecated)$", description="Only listed versions in this state."),
    torque_min: Optional[float] = Query(None, description="Lowest torque [N·m]."),
    torque_max: Optional[float] = Query(None, description="Highest torque [N·m]."),
    preload_min: Optional[float] = Query(None, description="Lowest preload [N]."),
    preload_max: Optional[float] = Query(None, description="Highest preload [N]."),
    q: Optional[str] = Query(None, max_length=200, description="Part of the joint name."),
    after: Optional[str] = Query(None, max_length=400, description="The `next` cursor of the previous page."),
    r=Depends(repo), _who=reader,
) -> JSONResponse:
    """One page, by joint name, in one SQL statement that reads O(page) index rows. Continue with
    ``after=<next>`` (keyset) or ``offset=<next_offset>`` (given only to a page asked for without
    ``after``: an offset counts from the start of the list); ``damaged`` lists versions of this page
    whose stored rows are damaged (left out of ``items``). ``total``: the matches when the listing
    started — read from maintained counts without a filter (or with only type / state), else
    counted on the first page and carried in ``next`` (see docs/service.md)."""
    found = r.list_page(joint_type or None, materials=material or (), label=label or None,
                        include_deprecated=include_deprecated, state=state, torque_min=torque_min,
                        torque_max=torque_max, preload_min=preload_min, preload_max=preload_max,
                        name_contains=q or None, after=after, offset=page.offset, limit=page.limit)
    shown = len(found.items) + len(found.damaged)
    # an offset counts from the start of the list; after a cursor it would not, so only `next` continues
    next_offset = page.offset + shown if found.next and after is None else None
    # plain JSON already (version_json): encoded directly, without FastAPI's generic re-encoding pass
    return JSONResponse({"items": [version_json(v) for v in found.items], "total": found.total,
                         "offset": page.offset, "limit": page.limit,
                         "next_offset": next_offset, "next": found.next,
                         "damaged": damaged_json(found.damaged)})


@router.get("/joints/{name}", summary="One version: current (default), by label or at a time")
def show(name: Name, label: Optional[str] = Query(None, max_length=100),
         at: Optional[str] = Query(None, max_length=40, description="ISO 8601 time."),
         r=Depends(repo), _who=reader) -> JSONResponse:
    return JSONResponse(version_json(r.get(joint_name(name), at=at, label=label)))


@router.get("/joints/{name}/versions/{version}", summary="One pinned version")
def show_version(name: Name, version: Annotated[int, Path(ge=1, le=2**31 - 1)], r=Depends(repo),
                 _who=reader) -> JSONResponse:
    # plain JSON already: encoded as it is (no response-model validation pass over a dict we built)
    return JSONResponse(version_json(r.get(joint_name(name), version)))


@router.get("/joints/{name}/history", summary="All versions of a joint, oldest first")
def history(name: Name, page: Page = Depends(page), r=Depends(repo), _who=reader) -> dict[str, Any]:
    damaged: list = []
    out = page.of([version_json(v) for v in r.history(joint_name(name), damaged=damaged)])
    out["damaged"] = damaged_json(damaged)
    return out


def _plain(value: Any) -> Any:
    return json.loads(json.dumps(value, default=str))


@router.get("/joints/{name}/diff", summary="Differences between two versions")
def diff(name: Name, a: int = Query(..., ge=1, le=2**31 - 1, description="First version."),
         b: Optional[int] = Query(None, ge=1, le=2**31 - 1, description="Second version (default: current)."),
         other: Optional[str] = Query(None, max_length=200, description="Joint the second version belongs to."),
         r=Depends(repo), _who=reader) -> dict[str, Any]:
    d = r.diff(joint_name(name), a, b, joint_name(other) if other else None)
    out = dataclasses.asdict(d)
    out["conditions"] = {k: {"a": x, "b": y} for k, (x, y) in d.conditions.items()}
    out["fields"] = {k: {"a": x, "b": y} for k, (x, y) in d.fields.items()}
    return _plain(out)


@router.get("/audit", summary="The audit log, newest first (optionally of one joint)")
def audit(page: Page = Depends(page), joint: Optional[str] = Query(None, max_length=200), r=Depends(repo),
          _who=reader) -> dict[str, Any]:
    rows = r.audit(joint_name(joint) if joint else None, limit=page.offset + page.limit + 1)
    part = rows[page.offset:page.offset + page.limit]
    more = len(rows) > page.offset + page.limit
    return {"items": _plain(part), "offset": page.offset, "limit": page.limit,
            "next_offset": page.offset + len(part) if more else None}
