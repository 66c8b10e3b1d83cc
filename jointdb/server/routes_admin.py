"""Admin routes (admin token): tokens, garbage collection, integrity check, migrations."""

from __future__ import annotations

import dataclasses
from typing import Any

from fastapi import APIRouter, Depends, Path

from jointdb.server._deps import admin, repo
from jointdb.server._schemas import GcIn, TokenIn
from jointdb.store import _tokens

router = APIRouter(prefix="/admin", tags=["admin"])


@router.get("/tokens", summary="List tokens (never the secrets)")
def list_tokens(r=Depends(repo), who=admin) -> dict[str, Any]:
    return {"items": [t.to_dict() for t in _tokens.list_tokens(r)]}


@router.post("/tokens", status_code=201, summary="Create a token (shown once)")
def create_token(body: TokenIn, r=Depends(repo), who=admin) -> dict[str, Any]:
    token, info = _tokens.create_token(r, body.name, body.role, body.expires, created_by=who.name)
    return {"token": token, **info.to_dict()}


@router.delete("/tokens/{token_id}", summary="Revoke a token")
def revoke_token(token_id: str = Path(..., max_length=20), r=Depends(repo), who=admin) -> dict[str, Any]:
    return _tokens.revoke_token(r, token_id, revoked_by=who.name).to_dict()


@router.post("/gc", summary="Remove unreferenced blobs (dry run by default)")
def gc(body: GcIn, r=Depends(repo), who=admin) -> dict[str, Any]:
    removed = r.gc(min_age_s=body.min_age_s, dry_run=body.dry_run)
    return {"dry_run": body.dry_run, "blobs": removed}


@router.get("/check", summary="Integrity check of every row and blob")
def check(verify_blobs: bool = True, r=Depends(repo), who=admin) -> dict[str, Any]:
    report = r.check(verify_blobs=verify_blobs)
    return {"ok": report.ok, **dataclasses.asdict(report)}


@router.get("/migrations", summary="Schema revision of the database and of this jointdb")
def migrations(r=Depends(repo), who=admin) -> dict[str, Any]:
    from jointdb.store import head_revision
    from jointdb.store._db import current_revision

    return {"revision": current_revision(r.read_engine), "head": head_revision()}


@router.post("/migrations/upgrade", summary="Migrate the database to this jointdb's schema")
def upgrade(r=Depends(repo), who=admin) -> dict[str, Any]:
    from jointdb.store import _db

    # through the app's own engine: opening and closing the SQLite file beside the app's
    # connections would drop the process's file locks (other processes then miss its commits)
    with _db.db_errors(r.url):
        _db.upgrade(r.write_engine, "head")
        return {"revision": _db.current_revision(r.read_engine)}
