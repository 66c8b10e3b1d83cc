"""PostgreSQL deployments: the queue is procrastinate's, in the same database.

``jointdb serve`` only enqueues (:class:`ProcrastinateQueue`): it writes the job's row
(``jointdb_jobs``) and defers the procrastinate task ``jointdb.run_job`` with the row's id.
``jointdb worker`` processes (:func:`run_worker`), on this host or others, run
procrastinate workers that execute those tasks. A worker killed mid-job stops sending
heartbeats; every worker looks for such *stalled* jobs at start-up and every few seconds
(procrastinate's ``get_stalled_jobs``) and retries them (the row is queued again,
attempt n+1) or, after the last attempt, fails them with the reason.

Schema: procrastinate's own schema (``procrastinate.schema.SchemaManager.get_schema``) and the
``jointdb_jobs`` table, applied by :func:`ensure_schema` — as the owner role by ``jointdb db
upgrade`` or ``jointdb worker --init-schema``, or on first use by a role that may create
tables. The application role then needs DML on these tables (docs/service.md, "Jobs").
"""

from __future__ import annotations

import asyncio
import json
import logging

from sqlalchemy import text

from jointdb.errors import InputError
from jointdb.jobs._table import JobRows, RowReads, ensure_table, one_line, worker_name

log = logging.getLogger("jointdb.jobs")
TASK = "jointdb.run_job"
QUEUE = "jointdb"
#: procrastinate's tables the application role writes (docs/service.md, "Jobs")
QUEUE_TABLES = ("procrastinate_jobs", "procrastinate_events", "procrastinate_periodic_defers",
                "procrastinate_workers", "jointdb_jobs")
_LOCK_KEY = 0x6A6F627371756575  # pg_advisory_xact_lock: one schema applier at a time


def conninfo(url: str) -> str:
    """A libpq URI from a SQLAlchemy URL (``postgresql+psycopg://…?options=…`` keeps its options)."""
    from sqlalchemy.engine import make_url

    return make_url(url).set(drivername="postgresql").render_as_string(hide_password=False)


def schema_present(conn) -> bool:
    return conn.execute(text("SELECT to_regclass('procrastinate_jobs') IS NOT NULL "
                             "AND to_regclass('jointdb_jobs') IS NOT NULL")).scalar()


def ensure_schema(engine) -> bool:
    """Apply procrastinate's schema and the ``jointdb_jobs`` table when missing; returns whether it
    applied anything. Serialised by an advisory lock (a server and workers may start together).

    Raises
    ------
    InputError
        The role may not create tables: run ``jointdb db upgrade`` (or ``jointdb worker
        --init-schema``) as the owner role.
    """
    from procrastinate.schema import SchemaManager

    with engine.connect() as conn:
        if schema_present(conn):
            return False
    try:
        with engine.begin() as conn:
            conn.execute(text("SELECT pg_advisory_xact_lock(:k)"), {"k": _LOCK_KEY})
            if schema_present(conn):
                return False
            if conn.execute(text("SELECT to_regclass('procrastinate_jobs') IS NULL")).scalar():
                with conn.connection.dbapi_connection.cursor() as cur:  # no parameters: '%' is literal SQL
                    cur.execute(SchemaManager.get_schema())
        ensure_table(engine)
    except Exception as exc:
        if "permission denied" in str(exc).lower() or "InsufficientPrivilege" in type(exc.__cause__ or exc).__name__:
            raise InputError("the job queue's tables are missing and this database role may not create them: "
                             "run `jointdb db upgrade` as the owner role (docs/service.md, Jobs)") from None
        raise
    return True


def grant_queue(conn, role: str) -> None:
    """Give ``role`` what the service and the workers need on the queue's tables (run as the owner)."""
    for table in QUEUE_TABLES:
        if conn.execute(text("SELECT to_regclass(:t) IS NOT NULL"), {"t": table}).scalar():
            conn.exec_driver_sql(f'GRANT SELECT, INSERT, UPDATE, DELETE ON "{table}" TO "{role}"')


def make_app(url: str, repo=None, sync: bool = False):
    """The procrastinate app over ``url`` with the task ``jointdb.run_job`` (run with ``repo``);
    ``sync``: a synchronous connector (the server's request threads defer and cancel)."""
    import procrastinate

    connector = (procrastinate.SyncPsycopgConnector(conninfo=conninfo(url), min_size=1, max_size=4) if sync else
                 procrastinate.PsycopgConnector(conninfo=conninfo(url), min_size=1, max_size=4))
    app = procrastinate.App(connector=connector)

    @app.task(name=TASK, queue=QUEUE)
    def run_job(job_id: str) -> None:  # runs in a worker thread of `jointdb worker`
        from jointdb.jobs._execute import execute

        execute(JobRows(repo.write_engine), job_id, repo)

    return app


class ProcrastinateQueue(RowReads):
    """A :class:`jointdb.jobs.JobQueue` whose jobs run in ``jointdb worker`` processes (PostgreSQL)."""

    backend = "procrastinate"

    def __init__(self, repo):
        self.repo = repo
        self.rows = JobRows(repo.write_engine)
        self.app = None

    def start(self) -> None:
        ensure_schema(self.repo.write_engine)
        self.app = make_app(self.repo.url, self.repo, sync=True).open()

    def stop(self) -> None:
        if self.app is not None:
            self.app.close()

    def submit(self, kind: str, owner: str, payload: dict, upload: bytes | None = None) -> str:
        job_id = self.rows.insert(kind, owner, payload, upload)
        try:
            queue_id = self.app.configure_task(TASK, queue=QUEUE).defer(job_id=job_id)
        except Exception as exc:
            self.rows.finish(job_id, "failed", error=f"could not be queued ({type(exc).__name__})")
            raise
        self.rows.set(job_id, queue_id=queue_id)
        return job_id

    def cancel(self, job_id: str) -> str:
        state = self.rows.request_cancel(job_id)
        queue_id = self.rows.row(job_id)._mapping["queue_id"]
        if state == "cancelled" and queue_id is not None:
            try:  # the procrastinate job too (the row's state alone already stops it from running)
                self.app.job_manager.cancel_job_by_id(queue_id)
            except Exception as exc:  # noqa: BLE001
                log.warning(json.dumps({"event": "job_cancel_queue", "job": job_id, "error": type(exc).__name__}))
        return state


async def recover_stalled(app, rows: JobRows, stalled_after_s: float) -> list[tuple[str, str]]:
    """Retry the jobs of workers that stopped sending heartbeats (or fail them after the last attempt)."""
    from procrastinate.jobs import Status

    out = []
    for job in await app.job_manager.get_stalled_jobs(seconds_since_heartbeat=stalled_after_s):
        job_id = job.task_kwargs.get("job_id")
        if not job_id:
            continue
        try:
            row = rows.row(job_id)._mapping
        except InputError:
            continue
        except Exception:  # noqa: BLE001 - not found: nothing of ours
            continue
        why = f"the worker ({row['worker'] or 'unknown'}) stopped while running the job"
        state = rows.recover(job_id, int(row["attempts"] or 0), why) if row["state"] == "running" else row["state"]
        if state == "queued":
            await app.job_manager.retry_job(job)
        else:
            await app.job_manager.finish_job_by_id_async(job.id, status=Status.FAILED, delete_job=False)
        log.warning(json.dumps({"event": "job_recovered", "job": job_id, "state": state}))
        out.append((job_id, state))
    return out


def run_worker(repo, *, concurrency: int = 1, queues: list[str] | None = None, heartbeat_s: float = 10.0,
               stalled_after_s: float = 30.0, recover_every_s: float | None = None, name: str | None = None) -> None:
    """Run a procrastinate worker for jointdb's jobs until SIGTERM/SIGINT (``jointdb worker``).

    A job of a worker that stopped heart-beating for ``stalled_after_s`` is taken back at the next recovery
    round, every ``recover_every_s`` seconds (default: half of ``stalled_after_s``, at most 10 s), so it
    waits at most about 1.5 × ``stalled_after_s`` before it runs again.
    """
    if recover_every_s is None:
        recover_every_s = min(10.0, stalled_after_s / 2)
    recover_every_s = max(0.5, float(recover_every_s))  # never a loop polling the database
    ensure_schema(repo.write_engine)
    app = make_app(repo.url, repo)
    rows = JobRows(repo.write_engine)

    async def recover_loop():
        while True:
            try:
                await recover_stalled(app, rows, stalled_after_s)
            except Exception as exc:  # noqa: BLE001 - retried at the next round
                log.warning(json.dumps({"event": "job_recover_error", "error": one_line(exc, 200)}))
            await asyncio.sleep(recover_every_s)

    async def main():
        async with app.open_async():
            recovering = asyncio.create_task(recover_loop())
            try:
                await app.run_worker_async(queues=queues or [QUEUE], concurrency=concurrency,
                                           name=name or worker_name(), update_heartbeat_interval=heartbeat_s,
                                           stalled_worker_timeout=stalled_after_s, install_signal_handlers=True,
                                           delete_jobs="never")
            finally:
                recovering.cancel()

    asyncio.run(main())
