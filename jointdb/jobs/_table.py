"""The ``jointdb_jobs`` table: one row per job, the same on SQLite and PostgreSQL.

It holds what the job queue itself does not: who submitted the job, its kind and
input, its progress, result or one-line error, and — for identify jobs — the uploaded
campaign and the identified joint file, so that ``catalogue`` can run later from
the row. On PostgreSQL procrastinate's own tables hold the queue (which worker runs
what, retries, aborts); this row is the job as users see it and is linked to the
procrastinate job by ``queue_id``. On SQLite this row is the queue as well (the
in-process worker claims rows with a conditional UPDATE).

The table is kept outside the Alembic history (see docs/service.md, "Jobs"): it is
created by :func:`ensure_table` (``CREATE TABLE IF NOT EXISTS``) on first use, or
on PostgreSQL by ``jointdb db upgrade`` as the owner role.
"""

from __future__ import annotations

import json
import os
import socket
import uuid
from datetime import datetime, timedelta, timezone
from typing import Any

from sqlalchemy import (BigInteger, Boolean, Column, DateTime, Float, Integer, LargeBinary, MetaData, String,
                        Table, Text, and_, select, update)

from jointdb.errors import InputError, NotFoundError

METADATA = MetaData()
JOBS = Table(
    "jointdb_jobs", METADATA,
    Column("id", String(32), primary_key=True),
    Column("kind", String(20), nullable=False),
    Column("owner", String(100), nullable=False),
    Column("state", String(12), nullable=False, index=True),
    Column("progress", Float, nullable=False, default=0.0),
    Column("message", Text, nullable=False, default=""),
    Column("error", Text),
    Column("payload", Text, nullable=False),
    Column("upload", LargeBinary),
    Column("result", Text),
    Column("artifact", LargeBinary),
    Column("outcome", Text),
    Column("attempts", Integer, nullable=False, default=0),
    Column("queue_id", BigInteger),
    Column("worker", String(200)),
    Column("heartbeat", DateTime(timezone=True)),
    Column("cancel_requested", Boolean, nullable=False, default=False),
    Column("created", DateTime(timezone=True), nullable=False),
    Column("started", DateTime(timezone=True)),
    Column("finished", DateTime(timezone=True)),
)
STATES = ("queued", "running", "succeeded", "failed", "cancelled")
FINAL = ("succeeded", "failed", "cancelled")
#: a job is run at most this many times (a worker killed mid-job: the next run resumes it)
MAX_ATTEMPTS = 3


def now() -> datetime:
    return datetime.now(timezone.utc)


def worker_name() -> str:
    """``host:pid`` of this process (the running job's worker)."""
    return f"{socket.gethostname()}:{os.getpid()}"


def one_line(text: object, limit: int = 300) -> str:
    line = " ".join(str(text).split())
    return line if len(line) <= limit else line[: limit - 3] + "..."


def ensure_table(engine) -> None:
    """Create ``jointdb_jobs`` when it is missing (idempotent)."""
    METADATA.create_all(engine, checkfirst=True)


def _iso(value: datetime | None) -> str | None:
    if value is None:
        return None
    if value.tzinfo is None:  # SQLite returns naive datetimes: they were written in UTC
        value = value.replace(tzinfo=timezone.utc)
    return value.isoformat().replace("+00:00", "Z")


def job_json(row) -> dict[str, Any]:
    """The job as the API shows it (no upload or artifact bytes)."""
    m = row._mapping
    return {"id": m["id"], "url": f"/api/v1/jobs/{m['id']}", "kind": m["kind"], "owner": m["owner"],
            "state": m["state"], "progress": float(m["progress"] or 0.0), "message": m["message"] or "",
            "error": m["error"], "attempts": int(m["attempts"] or 0), "created": _iso(m["created"]),
            "started": _iso(m["started"]), "finished": _iso(m["finished"]),
            "result": json.loads(m["result"]) if m["result"] else None,
            "outcome": json.loads(m["outcome"]) if m["outcome"] else None}


class JobRows:
    """The row operations both queues share (an SQLAlchemy engine over the jobs table)."""

    def __init__(self, engine):
        self.engine = engine

    def insert(self, kind: str, owner: str, payload: dict, upload: bytes | None = None) -> str:
        job_id = uuid.uuid4().hex
        with self.engine.begin() as conn:
            conn.execute(JOBS.insert().values(
                id=job_id, kind=kind, owner=owner, state="queued", progress=0.0, message="queued",
                payload=json.dumps(payload), upload=upload, attempts=0, cancel_requested=False, created=now()))
        return job_id

    def row(self, job_id: str):
        with self.engine.connect() as conn:
            found = conn.execute(select(JOBS).where(JOBS.c.id == job_id)).first()
        if found is None:
            raise NotFoundError(f"no job {job_id}")
        return found

    def list(self, owner: str | None, kind: str | None = None, state: str | None = None, limit: int = 200):
        cols = [c for c in JOBS.c if c.name not in ("upload", "artifact", "payload")]
        q = select(*cols).order_by(JOBS.c.created.desc()).limit(limit)
        if owner is not None:
            q = q.where(JOBS.c.owner == owner)
        if kind:
            q = q.where(JOBS.c.kind == kind)
        if state:
            if state not in STATES:
                raise InputError(f"state must be one of {', '.join(STATES)}, got {state!r}")
            q = q.where(JOBS.c.state == state)
        with self.engine.connect() as conn:
            return list(conn.execute(q))

    def set(self, job_id: str, only_if: tuple[str, ...] | None = None, **values) -> bool:
        q = update(JOBS).where(JOBS.c.id == job_id)
        if only_if is not None:
            q = q.where(JOBS.c.state.in_(only_if))
        with self.engine.begin() as conn:
            return conn.execute(q.values(**values)).rowcount == 1

    def start(self, job_id: str) -> bool:
        """Mark a queued job running in this process (False: it is not queued: cancelled or taken)."""
        q = (update(JOBS).where(and_(JOBS.c.id == job_id, JOBS.c.state == "queued"))
             .values(state="running", started=now(), heartbeat=now(), worker=worker_name(), progress=0.0,
                     message="running", attempts=JOBS.c.attempts + 1))
        with self.engine.begin() as conn:
            return conn.execute(q).rowcount == 1

    def progress(self, job_id: str, fraction: float, message: str) -> bool:
        """Record progress and a heartbeat; returns whether a cancel was asked for."""
        with self.engine.begin() as conn:
            conn.execute(update(JOBS).where(JOBS.c.id == job_id).values(
                progress=max(0.0, min(1.0, float(fraction))), message=one_line(message), heartbeat=now()))
            asked = conn.execute(select(JOBS.c.cancel_requested).where(JOBS.c.id == job_id)).scalar()
        return bool(asked)

    def finish(self, job_id: str, state: str, *, result: dict | None = None, error: str | None = None,
               artifact: bytes | None = None, message: str | None = None) -> bool:
        values: dict[str, Any] = {"state": state, "finished": now(), "heartbeat": now(),
                                  "message": message or state, "error": one_line(error) if error else None}
        if state == "succeeded":
            values["progress"] = 1.0
        if result is not None:
            values["result"] = json.dumps(result)
        if artifact is not None:
            values["artifact"] = artifact
        return self.set(job_id, only_if=("queued", "running"), **values)

    def request_cancel(self, job_id: str) -> str:
        """Cancel a queued job at once, ask a running one to stop; returns the state after."""
        self.set(job_id, only_if=("queued",), state="cancelled", finished=now(), message="cancelled before it ran",
                 cancel_requested=True)
        self.set(job_id, only_if=("running",), cancel_requested=True, message="cancel requested")
        return self.row(job_id)._mapping["state"]

    def stale_running(self, older_than_s: float, host_dead_pids: bool = True) -> list:
        """Running jobs whose worker is gone: its heartbeat is older than ``older_than_s`` or,
        on this host, its process no longer exists."""
        cutoff = now() - timedelta(seconds=older_than_s)
        host = socket.gethostname()
        with self.engine.connect() as conn:
            rows = list(conn.execute(select(JOBS.c.id, JOBS.c.worker, JOBS.c.heartbeat, JOBS.c.attempts)
                                     .where(JOBS.c.state == "running")))
        out = []
        for r in rows:
            beat = r.heartbeat if r.heartbeat is None or r.heartbeat.tzinfo else r.heartbeat.replace(tzinfo=timezone.utc)
            w_host, _, w_pid = (r.worker or ":").rpartition(":")
            dead = host_dead_pids and w_host == host and w_pid.isdigit() and not _alive(int(w_pid))
            if dead or beat is None or beat < cutoff:
                out.append(r)
        return out

    def recover(self, job_id: str, attempts: int, why: str) -> str:
        """A job whose worker stopped mid-run: queued again (resumed) or, after
        :data:`MAX_ATTEMPTS` runs, failed with the reason. Returns the new state."""
        if self.row(job_id)._mapping["cancel_requested"]:  # it was being cancelled: it stays cancelled
            self.set(job_id, only_if=("running",), state="cancelled", finished=now(),
                     message=one_line(f"cancelled ({why})"))
            return "cancelled"
        if attempts >= MAX_ATTEMPTS:
            self.set(job_id, only_if=("running",), state="failed", finished=now(),
                     error=one_line(f"{why}; gave up after {attempts} attempts"), message="failed")
            return "failed"
        self.set(job_id, only_if=("running",), state="queued", worker=None,
                 message=one_line(f"resumed: {why} (attempt {attempts} of {MAX_ATTEMPTS})"))
        return "queued"


class RowReads:
    """What both queues read the same way: a job's row and the owner's jobs (``self.rows``)."""

    rows: JobRows

    def get(self, job_id: str):
        return self.rows.row(job_id)

    def list(self, owner: str | None, kind: str | None = None, state: str | None = None):
        return self.rows.list(owner, kind, state)


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True
