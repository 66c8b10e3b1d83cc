"""CLI: ``jointdb worker`` — run the jobs that ``jointdb serve`` queues on PostgreSQL."""

from __future__ import annotations

from typing import Annotated, Optional

import typer

from jointdb.cli._target import BlobsOpt, DbOpt
from jointdb.errors import InputError


def worker(
    concurrency: Annotated[int, typer.Option("--concurrency", help="Jobs run at the same time (threads).")] = 1,
    queues: Annotated[Optional[str], typer.Option(
        "--queues", help="Comma-separated procrastinate queues to take jobs from (default: jointdb).")] = None,
    heartbeat: Annotated[float, typer.Option("--heartbeat", help="Seconds between the worker's heartbeats.")] = 10.0,
    stalled_after: Annotated[float, typer.Option(
        "--stalled-after", help="Seconds without a heartbeat after which another worker's running jobs are "
        "resumed (or failed after the last attempt); workers look for such jobs every half of it "
        "(at most 10 s).")] = 30.0,
    init_schema: Annotated[bool, typer.Option(
        "--init-schema", help="Only apply the job queue's schema (procrastinate's and jointdb_jobs) and exit; "
        "run as the owner role.")] = False,
    db: DbOpt = None,
    blobs: BlobsOpt = None,
) -> None:
    """Run jobs of the HTTP service (predict, lobes, diagnose, identify) from the PostgreSQL queue.

    On PostgreSQL `jointdb serve` only queues jobs (procrastinate, in the same database);
    start one or more `jointdb worker` processes, on this host or others, with the same
    --db and a blob store they share (--blobs database, or one shared folder). On the
    SQLite default the server runs its jobs itself and no worker is needed. A worker
    killed mid-job is noticed by the others within 1.5 × --stalled-after seconds: its job is run
    again (or failed with the reason after the last attempt). Linear algebra runs on one
    BLAS thread per job unless the root option --blas-threads says otherwise.
    Stops on SIGTERM/SIGINT after the jobs in progress.

    Example: jointdb worker --db postgresql+psycopg://jointdb_app@dbhost/jointdb --blobs database --concurrency 2
    """
    from jointdb.cli._target import open_repo

    if not 1 <= concurrency <= 64:
        raise InputError(f"--concurrency must be 1..64, got {concurrency}")
    if not (0 < heartbeat < stalled_after):
        raise InputError("need 0 < --heartbeat < --stalled-after (seconds)")
    repo = open_repo(db, blobs)
    if getattr(repo, "write_engine", None) is None or repo.write_engine.dialect.name != "postgresql":
        raise InputError("jointdb worker runs the PostgreSQL job queue; on SQLite `jointdb serve` runs its jobs "
                         "itself (give --db postgresql+psycopg://...)")
    from jointdb.jobs._pg import ensure_schema, run_worker

    if init_schema:
        applied = ensure_schema(repo.write_engine)
        typer.echo("job queue schema applied" if applied else "job queue schema already present")
        return
    names = [q.strip() for q in queues.split(",") if q.strip()] if queues else None
    import logging

    from jointdb.io._jsonlog import configure

    configure("info")
    logging.getLogger("jointdb.jobs").setLevel(logging.INFO)
    run_worker(repo, concurrency=concurrency, queues=names, heartbeat_s=heartbeat, stalled_after_s=stalled_after)


def register(app: typer.Typer) -> None:
    """Add ``worker`` to the app."""
    app.command("worker")(worker)
