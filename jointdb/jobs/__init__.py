"""Jobs: long work (identify an uploaded campaign, predict a stack, lobes, diagnose) run on a queue.

The application layer's :class:`JobQueue` has two implementations with one interface:

- :class:`~jointdb.jobs._pg.ProcrastinateQueue` (PostgreSQL): the queue is procrastinate's,
  in the same database; ``jointdb worker`` processes, on any host that reaches the database,
  run the jobs (:func:`~jointdb.jobs._pg.run_worker`).
- :class:`~jointdb.jobs._local.LocalQueue` (the SQLite default): threads of the ``jointdb
  serve`` process run the jobs; the queue is the ``jointdb_jobs`` table of the SQLite file.

Either way a job is a row of ``jointdb_jobs`` (:mod:`jointdb.jobs._table`): kind, owner,
state (queued, running, succeeded, failed, cancelled), progress 0..1, a message, a one-line
error, the result. A job whose worker was killed is resumed (run again) or, after
:data:`~jointdb.jobs._table.MAX_ATTEMPTS` runs, failed with the reason — never lost.
"""

from __future__ import annotations

from typing import Any, Protocol

from jointdb.jobs._run import KINDS
from jointdb.jobs._table import FINAL, MAX_ATTEMPTS, STATES, job_json


class JobQueue(Protocol):
    """What the service needs of a job queue."""

    backend: str

    def start(self) -> None:
        """Create what is missing and start working (in-process) or connect (procrastinate)."""

    def stop(self) -> None:
        """Stop the in-process workers (running jobs are resumed at the next start)."""

    def submit(self, kind: str, owner: str, payload: dict[str, Any], upload: bytes | None = None) -> str:
        """Queue a job; returns its id at once."""

    def get(self, job_id: str) -> Any:
        """The job's row (NotFoundError when unknown)."""

    def list(self, owner: str | None, kind: str | None = None, state: str | None = None) -> list:
        """Rows of ``owner``'s jobs (every owner's: None), newest first."""

    def cancel(self, job_id: str) -> str:
        """Cancel a queued job, ask a running one to stop; returns the state after."""


def open_queue(repo, concurrency: int = 1) -> JobQueue:
    """The queue for ``repo``'s database: procrastinate on PostgreSQL, in-process on SQLite
    (not started: call ``start()``)."""
    if repo.write_engine.dialect.name == "postgresql":
        from jointdb.jobs._pg import ProcrastinateQueue

        return ProcrastinateQueue(repo)
    from jointdb.jobs._local import LocalQueue

    return LocalQueue(repo, concurrency)


__all__ = ["FINAL", "JobQueue", "KINDS", "MAX_ATTEMPTS", "STATES", "job_json", "open_queue"]
