"""CLI for database administration: ``db upgrade | downgrade | check | gc | audit | info``.

Thin like :mod:`jointdb.cli._store`; the ``--db``/``--blobs``/``--json`` options and the repository
opening are :mod:`jointdb.cli._target`'s.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated, Optional

import typer

from jointdb.cli._output import emit, message
from jointdb.cli._target import BlobsOpt, DbOpt, JsonOpt, check_db_target, open_repo
from jointdb.errors import InputError, IntegrityError

YesOpt = Annotated[bool, typer.Option("--yes", help="Confirm an operation that removes data or guards.")]


def db_upgrade(
    to: Annotated[str, typer.Option("--to", help="Target revision.")] = "head",
    app_role: Annotated[Optional[str], typer.Option(
        "--app-role", help="PostgreSQL: grant this role the service's minimal privileges.")] = None,
    create_role: Annotated[bool, typer.Option("--create-role", help="Create the --app-role (LOGIN) if missing.")] = False,
    db: DbOpt = None, as_json: JsonOpt = False,
) -> None:
    """Create or migrate the schema (Alembic). A missing SQLite file is created; an existing
    file must be a jointdb database. PostgreSQL: run it as the owner role, with --app-role for
    the role the service connects as (SELECT/INSERT on history, nothing that rewrites it).

    Example: jointdb db upgrade --db postgresql+psycopg://owner@host/jointdb --app-role jointdb_app --create-role
    """
    from jointdb.store import upgrade
    from jointdb.store._db import resolve_url, safe_url

    if create_role and not app_role:
        raise InputError("--create-role needs --app-role NAME")
    if app_role:
        from jointdb.store._db import is_sqlite
        from jointdb.store._roles import check_role_name

        check_role_name(app_role)
        if is_sqlite(resolve_url(db)):
            raise InputError("--app-role is for PostgreSQL; a SQLite file has no roles (whoever can write "
                             "the file can rewrite it: docs/service.md, threat model)")
    check_db_target(db, create=True)
    rev = upgrade(db, to)
    out = {"database": safe_url(resolve_url(db)), "revision": rev}
    out |= _job_queue_schema(resolve_url(db))
    if app_role:
        from jointdb.store import _db
        from jointdb.store._roles import grant_app_role

        url = resolve_url(db)
        _, write = _db.make_engines(url)
        try:
            with _db.db_errors(url), write.begin() as conn:
                grant_app_role(conn, app_role, create=create_role)
                if out.get("job_queue"):
                    from jointdb.jobs._pg import grant_queue

                    grant_queue(conn, app_role)  # the service and the workers write the queue's tables
        finally:
            write.dispose()
        out["app_role"] = app_role
    emit(out, as_json=as_json)


def _job_queue_schema(url: str) -> dict:
    """PostgreSQL: the job queue's tables (procrastinate's schema and ``jointdb_jobs``), applied here by
    the owner role so that the application role needs no CREATE (docs/service.md, Jobs)."""
    from jointdb.store._db import is_sqlite

    if is_sqlite(url):
        return {}
    try:
        import procrastinate  # noqa: F401 - the postgres extra
    except ImportError:  # procrastinate not installed: the job routes answer 503 until it is
        return {"job_queue": None}
    from jointdb.jobs._pg import ensure_schema
    from jointdb.store import _db

    _, write = _db.make_engines(url)
    try:
        with _db.db_errors(url):
            ensure_schema(write)
    finally:
        write.dispose()
    return {"job_queue": "procrastinate"}


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


def db_check(
    quick: Annotated[bool, typer.Option("--quick", help="Only check blobs exist (do not read and hash them).")] = False,
    checkpoint: Annotated[Optional[Path], typer.Option(
        "--checkpoint", help="A signed checkpoint (`db checkpoint`, GET /api/v1/checkpoint) the history must extend.")] = None,
    trust: Annotated[Optional[list[Path]], typer.Option(
        "--trust", help="Public key (.pub) the checkpoint must be signed with (repeatable).")] = None,
    db: DbOpt = None, blobs: BlobsOpt = None, as_json: JsonOpt = False,
) -> None:
    """Walk every row, the history chain and every blob; report missing, corrupt or rewritten
    data (exit code 5 on problems). With --checkpoint, the history recomputed from the rows
    must extend the signed checkpoint (same head at its size).

    Example: jointdb db check --checkpoint lab.checkpoint --trust lab.pub
    """
    from jointdb.store._maintenance import check

    verified = None
    if trust and checkpoint is None:
        raise InputError("--trust needs --checkpoint FILE")
    if checkpoint is not None:
        from jointdb.store._chain import parse_checkpoint, read_checkpoint_file
        from jointdb.store._signing import load_public_key

        keys = [load_public_key(k) for k in trust or ()]
        verified, signer = parse_checkpoint(read_checkpoint_file(checkpoint), keys)
        message(f"checkpoint: {verified['tree_size']} entries at {verified['time']}, signature verified "
                f"({'trusted key' if keys else 'key named in the checkpoint'} {signer})")
    report = check(open_repo(db, blobs), verify_blobs=not quick, checkpoint=verified)
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


def db_checkpoint(
    sign: Annotated[Path, typer.Option("--sign", help="Ed25519 private key (`jointdb keys create`).")],
    out: Annotated[Optional[Path], typer.Option("--out", help="Write the checkpoint here (else stdout).")] = None,
    db: DbOpt = None, blobs: BlobsOpt = None,
) -> None:
    """Sign a checkpoint of the history chain (tree size, head, time) after recomputing the chain
    from the rows; keep it away from the database and verify later with `db check --checkpoint`.

    Example: jointdb db checkpoint --sign lab.key --out /safe/place/jointdb.checkpoint
    """
    from jointdb.store._chain import signed_checkpoint
    from jointdb.store._maintenance import snapshot
    from jointdb.store._signing import load_private_key

    key = load_private_key(sign)
    with snapshot(open_repo(db, blobs)) as s:
        cp = signed_checkpoint(s.connection(), key)
    text = json.dumps(cp, indent=1) + "\n"
    if out is None:
        typer.echo(text, nl=False)
        return
    from jointdb.io._atomic import atomic_path

    with atomic_path(out) as tmp:
        tmp.write_bytes(text.encode())
    message(f"checkpoint of {cp['tree_size']} entries written to {out}")


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
    removed = open_repo(db, blobs).gc(min_age_s=min_age, dry_run=dry_run)
    if as_json:  # always a list for machines (empty when nothing was removed)
        emit([{"removed" if not dry_run else "would_remove": r} for r in removed], as_json=True)
    else:
        emit([{"removed" if not dry_run else "would_remove": r} for r in removed] if removed else
             "nothing to remove")


def db_audit(
    joint: Annotated[Optional[str], typer.Option("--joint", help="Only entries of this joint.")] = None,
    limit: Annotated[int, typer.Option("--limit", help="Newest N entries.")] = 50,
    db: DbOpt = None, blobs: BlobsOpt = None, as_json: JsonOpt = False,
) -> None:
    """The append-only audit log: who catalogued, labelled, deprecated, imported what. Example: jointdb db audit --joint T1"""
    if limit < 1:
        raise InputError(f"--limit must be >= 1, got {limit}")
    rows = open_repo(db, blobs).audit(joint, limit)
    if not as_json:
        rows = [{**r, "details": json.dumps(r["details"], default=str)} for r in rows]
    emit(rows, as_json=as_json, title="audit log", columns=["at", "actor", "action", "joint", "version", "details"])


def db_info(db: DbOpt = None, blobs: BlobsOpt = None, as_json: JsonOpt = False) -> None:
    """Where the database and blobs are, and the schema revision. Example: jointdb db info"""
    from jointdb.store import current_revision, head_revision

    repo = open_repo(db, blobs)
    from jointdb.store._db import safe_url

    emit({"database": safe_url(repo.url), "blobs": str(repo.blobs.root), "revision": current_revision(repo.url),
          "head": head_revision()}, as_json=as_json)


def register(app: typer.Typer) -> None:
    """Add ``db ...`` to the app."""
    db_app = typer.Typer(help="Database administration: migrations, integrity check, garbage collection.",
                         no_args_is_help=True)
    app.add_typer(db_app, name="db")

    db_app.command("upgrade")(db_upgrade)
    db_app.command("downgrade")(db_downgrade)
    db_app.command("check")(db_check)
    db_app.command("checkpoint")(db_checkpoint)
    db_app.command("gc")(db_gc)
    db_app.command("audit")(db_audit)
    db_app.command("info")(db_info)
