"""CLI for database administration: ``db upgrade | downgrade | check | gc | audit | info``.

Thin like :mod:`jointdb.cli._store`, whose ``--db``/``--blobs``/``--json`` options
and repository opening it shares.
"""

from __future__ import annotations

import json
from typing import Annotated, Optional

import typer

from jointdb._output import emit, message
from jointdb.cli._store import BlobsOpt, DbOpt, JsonOpt, _repo, check_db_target
from jointdb.errors import InputError, IntegrityError

YesOpt = Annotated[bool, typer.Option("--yes", help="Confirm an operation that removes data or guards.")]


def register(app: typer.Typer) -> None:
    """Add ``db ...`` to the app."""
    db_app = typer.Typer(help="Database administration: migrations, integrity check, garbage collection.",
                         no_args_is_help=True)
    app.add_typer(db_app, name="db")

    @db_app.command("upgrade")
    def db_upgrade(
        to: Annotated[str, typer.Option("--to", help="Target revision.")] = "head",
        db: DbOpt = None, as_json: JsonOpt = False,
    ) -> None:
        """Create or migrate the schema (Alembic). A missing SQLite file is created; an existing
        file must be a jointdb database. Example: jointdb db upgrade --db postgresql+psycopg://host/jointdb"""
        from jointdb.store import upgrade
        from jointdb.store._db import resolve_url, safe_url

        check_db_target(db, create=True)
        rev = upgrade(db, to)
        emit({"database": safe_url(resolve_url(db)), "revision": rev}, as_json=as_json)

    @db_app.command("downgrade")
    def db_downgrade(
        to: Annotated[str, typer.Option("--to", help="Target: -N (N steps), a revision id, or base (drops all tables).")] = "-1",
        yes: YesOpt = False,
        db: DbOpt = None, as_json: JsonOpt = False,
    ) -> None:
        """Revert schema migrations. Every step drops data or immutability guards, so --yes is required.

        Example: jointdb db downgrade --to -1 --yes
        """
        from jointdb.store import current_revision, downgrade
        from jointdb.store._db import DOWNGRADE_DROPS, check_existing, downgrade_plan, resolve_url, safe_url

        check_existing(resolve_url(db))  # never creates a database; refuses a foreign one
        current = current_revision(db)
        target, steps = downgrade_plan(current, to)
        if steps and not yes:
            drops = "; ".join(f"{r}: {DOWNGRADE_DROPS.get(r, 'changes of revision ' + r)}" for r in steps)
            raise InputError(f"downgrading {current} -> {target or 'base'} drops {drops}; add --yes if you mean it")
        rev = downgrade(db, target or "base") if steps else current
        emit({"database": safe_url(resolve_url(db)), "revision": rev}, as_json=as_json)

    @db_app.command("check")
    def db_check(
        quick: Annotated[bool, typer.Option("--quick", help="Only check blobs exist (do not read and hash them).")] = False,
        db: DbOpt = None, blobs: BlobsOpt = None, as_json: JsonOpt = False,
    ) -> None:
        """Walk every row and blob; report missing or corrupt data (exit code 5 on problems).

        Example: jointdb db check
        """
        report = _repo(db, blobs).check(verify_blobs=not quick)
        data = {"ok": report.ok, "versions_checked": report.versions_checked, "blobs_checked": report.blobs_checked,
                "problems": list(report.problems), "orphan_blobs": len(report.orphan_blobs),
                "temporaries": len(report.temporaries), "notes": list(report.notes)}
        if as_json:
            emit(data, as_json=True)
        else:
            emit({k: v for k, v in data.items() if k not in ("problems", "notes")}, title="db check")
            for p in report.problems:
                message(f"problem: {p}")
            for n in report.notes:
                message(f"note: {n}")
        if not report.ok:
            raise IntegrityError(f"db check found {len(report.problems)} problem(s)")

    @db_app.command("gc")
    def db_gc(
        min_age: Annotated[float, typer.Option("--min-age", help="Only remove files older than this many seconds.")] = 3600.0,
        dry_run: Annotated[bool, typer.Option("--dry-run", help="List what would be removed.")] = False,
        yes: YesOpt = False,
        db: DbOpt = None, blobs: BlobsOpt = None, as_json: JsonOpt = False,
    ) -> None:
        """Remove blobs no row references (and stale temporary files); --yes unless --dry-run.

        Example: jointdb db gc --dry-run ; jointdb db gc --yes
        """
        if not min_age >= 0:
            raise InputError(f"--min-age must be >= 0 seconds, got {min_age:g}")
        if not dry_run and not yes:
            raise InputError("db gc deletes unreferenced blob files; look first with --dry-run, then add --yes")
        removed = _repo(db, blobs).gc(min_age_s=min_age, dry_run=dry_run)
        if as_json:  # always a list for machines (empty when nothing was removed)
            emit([{"removed" if not dry_run else "would_remove": r} for r in removed], as_json=True)
        else:
            emit([{"removed" if not dry_run else "would_remove": r} for r in removed] if removed else
                 "nothing to remove")

    @db_app.command("audit")
    def db_audit(
        joint: Annotated[Optional[str], typer.Option("--joint", help="Only entries of this joint.")] = None,
        limit: Annotated[int, typer.Option("--limit", help="Newest N entries.")] = 50,
        db: DbOpt = None, blobs: BlobsOpt = None, as_json: JsonOpt = False,
    ) -> None:
        """The append-only audit log: who catalogued, labelled, deprecated, imported what. Example: jointdb db audit --joint T1"""
        if limit < 1:
            raise InputError(f"--limit must be >= 1, got {limit}")
        rows = _repo(db, blobs).audit(joint, limit)
        if not as_json:
            rows = [{**r, "details": json.dumps(r["details"], default=str)} for r in rows]
        emit(rows, as_json=as_json, title="audit log", columns=["at", "actor", "action", "joint", "version", "details"])

    @db_app.command("info")
    def db_info(db: DbOpt = None, blobs: BlobsOpt = None, as_json: JsonOpt = False) -> None:
        """Where the database and blobs are, and the schema revision. Example: jointdb db info"""
        from jointdb.store import current_revision, head_revision

        repo = _repo(db, blobs)
        from jointdb.store._db import safe_url

        emit({"database": safe_url(repo.url), "blobs": str(repo.blobs.root), "revision": current_revision(repo.url),
              "head": head_revision()}, as_json=as_json)
