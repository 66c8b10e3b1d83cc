"""Read routes: joints list/filter, one version, history, diff, audit (all paginated lists)."""

from __future__ import annotations

import dataclasses
import json
import math
from typing import Annotated, Any, Optional

from fastapi import APIRouter, Depends, Path, Query

from jointdb.errors import InputError, NotFoundError
from jointdb.server._deps import Page, reader, repo, version_json
from jointdb.store._types import check_name, normalise_material

router = APIRouter(tags=["joints"])

#: a joint name in a URL: the catalogue's own rule (no '/'), checked again by check_name
Name = Annotated[str, Path(min_length=1, max_length=200, description="Joint name.")]


def joint_name(name: str) -> str:
    """The catalogue's name rule, applied to a path parameter (a path-like name is a 422)."""
    if name in (".", "..") or "\\" in name:
        raise InputError(f"joint name {name[:60]!r} must not be a path")
    return check_name(name)


def _in_range(value: float | None, lo: float | None, hi: float | None) -> bool:
    if lo is None and hi is None:
        return True
    if value is None:
        return False
    return (lo is None or value >= lo) and (hi is None or value <= hi)


def filter_versions(r, joint_type=None, material=None, label=None, include_deprecated=True, torque_min=None,
                    torque_max=None, preload_min=None, preload_max=None, q=None) -> list:
    """The current version of every joint that passes the filters (shared by the API and the web pages)."""
    for name, lo, hi in (("torque", torque_min, torque_max), ("preload", preload_min, preload_max)):
        for x in (lo, hi):
            if x is not None and not math.isfinite(x):
                raise InputError(f"{name} bounds must be finite numbers, got {x}")
    mats = {normalise_material(m) for m in material or [] if m.strip()}
    out = []
    for v in r.list_joints(joint_type or None, include_deprecated=include_deprecated):
        c = v.conditions
        if mats and not mats <= set(c.materials):
            continue
        if not _in_range(c.torque_nm, torque_min, torque_max) or not _in_range(c.preload_n, preload_min, preload_max):
            continue
        if q and q.lower() not in v.name.lower():
            continue
        if label:
            try:
                v = r.get(v.name, label=label)
            except NotFoundError:
                continue
        out.append(v)
    return out


@router.get("/joints", summary="List and filter joints (current version of each)")
def list_joints(
    page: Page = Depends(),
    joint_type: Optional[str] = Query(None, alias="type", max_length=100, description="Joint type, e.g. tool-holder."),
    material: Optional[list[str]] = Query(None, description="Interface material (repeat: all must be present)."),
    label: Optional[str] = Query(None, max_length=100, description="Only joints with this label (shows that version)."),
    include_deprecated: bool = Query(True, description="Also list deprecated joints."),
    torque_min: Optional[float] = Query(None, description="Lowest torque [N·m]."),
    torque_max: Optional[float] = Query(None, description="Highest torque [N·m]."),
    preload_min: Optional[float] = Query(None, description="Lowest preload [N]."),
    preload_max: Optional[float] = Query(None, description="Highest preload [N]."),
    q: Optional[str] = Query(None, max_length=200, description="Part of the joint name."),
    r=Depends(repo), _who=reader,
) -> dict[str, Any]:
    found = filter_versions(r, joint_type, material, label, include_deprecated, torque_min, torque_max,
                            preload_min, preload_max, q)
    return page.of([version_json(v) for v in found])


@router.get("/joints/{name}", summary="One version: current (default), by label or at a time")
def show(name: Name, label: Optional[str] = Query(None, max_length=100),
         at: Optional[str] = Query(None, max_length=40, description="ISO 8601 time."),
         r=Depends(repo), _who=reader) -> dict[str, Any]:
    return version_json(r.get(joint_name(name), at=at, label=label))


@router.get("/joints/{name}/versions/{version}", summary="One pinned version")
def show_version(name: Name, version: Annotated[int, Path(ge=1, le=2**31 - 1)], r=Depends(repo),
                 _who=reader) -> dict[str, Any]:
    return version_json(r.get(joint_name(name), version))


@router.get("/joints/{name}/history", summary="All versions of a joint, oldest first")
def history(name: Name, page: Page = Depends(), r=Depends(repo), _who=reader) -> dict[str, Any]:
    return page.of([version_json(v) for v in r.history(joint_name(name))])


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
def audit(page: Page = Depends(), joint: Optional[str] = Query(None, max_length=200), r=Depends(repo),
          _who=reader) -> dict[str, Any]:
    rows = r.audit(joint_name(joint) if joint else None, limit=page.offset + page.limit + 1)
    part = rows[page.offset:page.offset + page.limit]
    more = len(rows) > page.offset + page.limit
    return {"items": _plain(part), "offset": page.offset, "limit": page.limit,
            "next_offset": page.offset + len(part) if more else None}
