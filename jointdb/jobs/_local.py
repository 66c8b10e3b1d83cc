"""The in-process job worker of the SQLite default: threads of the server process, the queue
being the ``jointdb_jobs`` table of the SQLite file itself.

A thread claims the oldest queued row with a conditional UPDATE (so several server
processes on one file never run a job twice), runs it, and records progress and a
heartbeat. A job whose worker died (``kill -9`` of the server: its process is gone, or its
heartbeat is older than :data:`STALE_AFTER_S`) is found at start-up and every
:data:`RECOVER_EVERY_S` seconds and queued again — resumed from the start, attempt n+1 —
or, after :data:`jointdb.jobs._table.MAX_ATTEMPTS` runs, failed with the reason.
"""

from __future__ import annotations

import json
import logging
import threading
import time

from sqlalchemy import select, update

from jointdb.jobs._execute import execute
from jointdb.jobs._table import JOBS, JobRows, RowReads, ensure_table, now, worker_name

log = logging.getLogger("jointdb.jobs")
STALE_AFTER_S = 120.0
RECOVER_EVERY_S = 10.0
HEARTBEAT_EVERY_S = 5.0


class LocalQueue(RowReads):
    """A :class:`jointdb.jobs.JobQueue` run by threads of this process (SQLite).

    Parameters
    ----------
    repo
        The open :class:`jointdb.store.Repository`; the jobs table lives in its database.
    concurrency
        Jobs run at the same time (threads).
    """

    backend = "in-process"

    def __init__(self, repo, concurrency: int = 1, poll_s: float = 1.0):
        self.repo = repo
        self.rows = JobRows(repo.write_engine)
        self.concurrency = max(1, int(concurrency))
        self.poll_s = poll_s
        self._wake = threading.Event()
        self._stop = threading.Event()
        self._threads: list[threading.Thread] = []
        self._running: set[str] = set()
        self._lock = threading.Lock()

    # ------------------------------------------------------------------ interface
    def submit(self, kind: str, owner: str, payload: dict, upload: bytes | None = None) -> str:
        job_id = self.rows.insert(kind, owner, payload, upload)
        self._wake.set()
        return job_id

    def cancel(self, job_id: str) -> str:
        return self.rows.request_cancel(job_id)

    def start(self) -> None:
        """Create the table if needed, recover jobs of dead workers, start the threads."""
        ensure_table(self.repo.write_engine)
        self.recover()
        for k in range(self.concurrency):
            t = threading.Thread(target=self._loop, name=f"jointdb-job-{k}", daemon=True)
            t.start()
            self._threads.append(t)
        t = threading.Thread(target=self._beat, name="jointdb-job-heartbeat", daemon=True)
        t.start()
        self._threads.append(t)

    def stop(self, timeout: float = 5.0) -> None:
        self._stop.set()
        self._wake.set()
        for t in self._threads:
            t.join(timeout)

    # ------------------------------------------------------------------ work
    def recover(self) -> list[tuple[str, str]]:
        """Queue again (or fail, after the last attempt) the running jobs whose worker is gone."""
        out = []
        for r in self.rows.stale_running(STALE_AFTER_S):
            if r.id in self._running:
                continue
            why = f"the worker ({r.worker or 'unknown'}) stopped while running the job"
            state = self.rows.recover(r.id, int(r.attempts or 0), why)
            log.warning(json.dumps({"event": "job_recovered", "job": r.id, "state": state}))
            out.append((r.id, state))
        if out:
            self._wake.set()
        return out

    def _next(self) -> str | None:
        with self.repo.write_engine.connect() as conn:
            return conn.execute(select(JOBS.c.id).where(JOBS.c.state == "queued")
                                .order_by(JOBS.c.created).limit(1)).scalar()

    def _loop(self) -> None:
        last_recover = time.monotonic()
        while not self._stop.is_set():
            try:
                if time.monotonic() - last_recover > RECOVER_EVERY_S:
                    last_recover = time.monotonic()
                    self.recover()
                job_id = self._next()
                if job_id is None:
                    self._wake.wait(self.poll_s)
                    self._wake.clear()
                    continue
                with self._lock:
                    self._running.add(job_id)
                try:
                    execute(self.rows, job_id, self.repo)
                finally:
                    with self._lock:
                        self._running.discard(job_id)
            except Exception as exc:  # noqa: BLE001 - the loop must outlive a database hiccup
                log.error(json.dumps({"event": "job_loop_error", "error": f"{type(exc).__name__}: {exc}"[:300]}))
                self._stop.wait(self.poll_s)

    def _beat(self) -> None:
        """Heartbeats of the jobs this process runs (a long step reports no progress)."""
        me = worker_name()
        while not self._stop.wait(HEARTBEAT_EVERY_S):
            with self._lock:
                ids = list(self._running)
            if not ids:
                continue
            try:
                with self.repo.write_engine.begin() as conn:
                    conn.execute(update(JOBS).where(JOBS.c.id.in_(ids), JOBS.c.worker == me,
                                                    JOBS.c.state == "running").values(heartbeat=now()))
            except Exception as exc:  # noqa: BLE001 - a missed heartbeat is retried
                log.warning(json.dumps({"event": "job_heartbeat_error", "error": type(exc).__name__}))
