"""Running one job from its row: the same on the in-process worker and a procrastinate worker."""

from __future__ import annotations

import json
import logging

from jointdb.errors import JointdbError
from jointdb.jobs._run import Cancelled, Progress, run
from jointdb.jobs._table import JobRows, one_line

log = logging.getLogger("jointdb.jobs")


def _shown_error(job_id: str, exc: Exception) -> str:
    """The job's error as its owner sees it: a user's error (a jointdb error with a 4xx status) or damaged
    data keeps its message; any other failure (database, blob store, a bug) is "internal error" here, its
    text (which may name server folders) and traceback only in the worker's log."""
    from jointdb.errors import IntegrityError

    if isinstance(exc, IntegrityError) or (isinstance(exc, JointdbError) and exc.http_status < 500):
        return str(exc)
    log.error(json.dumps({"event": "job_error", "job": job_id, "error": one_line(f"{type(exc).__name__}: {exc}")}),
              exc_info=exc)
    return f"internal error ({type(exc).__name__}); the worker's log has the details"


def execute(rows: JobRows, job_id: str, repo) -> str | None:
    """Claim the queued job ``job_id`` and run it to a final state; returns that state, or None
    when the job was not queued (cancelled before it ran, or taken by another worker)."""
    if not rows.start(job_id):
        return None
    row = rows.row(job_id)._mapping
    progress = Progress(lambda fraction, message: rows.progress(job_id, fraction, message))
    log.info(json.dumps({"event": "job_start", "job": job_id, "kind": row["kind"], "attempt": row["attempts"]}))
    try:
        result, artifact = run(row["kind"], json.loads(row["payload"]), row["upload"], repo, progress)
    except Cancelled:
        rows.finish(job_id, "cancelled", message="cancelled while running")
        state = "cancelled"
    except Exception as exc:  # noqa: BLE001 - any failure of a job is its one-line error, logged in full
        rows.finish(job_id, "failed", error=_shown_error(job_id, exc), message="failed")
        state = "failed"
    else:
        rows.finish(job_id, "succeeded", result=result, artifact=artifact, message="done")
        state = "succeeded"
    log.info(json.dumps({"event": "job_end", "job": job_id, "state": state}))
    return state
