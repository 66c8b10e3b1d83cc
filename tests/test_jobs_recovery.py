"""The in-process queue's recovery rules on a real SQLite database (no threads started): a running
job whose worker process is gone is queued again with the reason, and after the last attempt it is
failed with the reason — never left running, never lost. The live kill -9 tests are in
tests/server/test_server_jobs.py."""

from __future__ import annotations

import socket
import subprocess
import sys

import pytest


@pytest.fixture
def queue(tmp_path):
    from jointdb.jobs._local import LocalQueue
    from jointdb.jobs._table import ensure_table
    from jointdb.store import Repository, upgrade

    url = f"sqlite:///{tmp_path / 'j.sqlite'}"
    upgrade(url)
    repo = Repository(url, auto_create=False)
    ensure_table(repo.write_engine)
    yield LocalQueue(repo)
    repo.close()


def _dead_pid() -> int:
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    return p.pid


def _as_running(q, job_id: str, attempts: int, pid: int) -> None:
    from jointdb.jobs._table import now

    q.rows.set(job_id, state="running", attempts=attempts, worker=f"{socket.gethostname()}:{pid}",
               heartbeat=now(), started=now())


def test_a_job_of_a_dead_worker_is_resumed_then_failed_with_the_reason(queue):
    from jointdb.jobs._table import MAX_ATTEMPTS

    job_id = queue.submit("lobes", "alice", {"frf": None})
    _as_running(queue, job_id, 1, _dead_pid())
    assert queue.recover() == [(job_id, "queued")]
    row = queue.get(job_id)._mapping
    assert row["state"] == "queued" and row["message"].startswith("resumed: the worker") and row["worker"] is None
    _as_running(queue, job_id, MAX_ATTEMPTS, _dead_pid())
    assert queue.recover() == [(job_id, "failed")]
    row = queue.get(job_id)._mapping
    assert row["state"] == "failed" and row["finished"] is not None
    assert "stopped while running the job" in row["error"] and f"gave up after {MAX_ATTEMPTS} attempts" in row["error"]


def test_a_live_workers_job_is_left_alone_and_cancel_is_seen(queue):
    import os

    job_id = queue.submit("lobes", "alice", {"frf": None})
    _as_running(queue, job_id, 1, os.getpid())  # this process: alive, fresh heartbeat
    assert queue.recover() == []
    assert queue.cancel(job_id) == "running"  # a running job is asked to stop ...
    assert queue.rows.progress(job_id, 0.5, "half way") is True  # ... and sees it at its next step
    other = queue.submit("lobes", "alice", {"frf": None})
    assert queue.cancel(other) == "cancelled"  # a queued one is cancelled at once
    from jointdb.jobs._execute import execute

    assert execute(queue.rows, other, queue.repo) is None  # and never runs


def test_a_job_runs_to_a_one_line_error(queue):
    from jointdb.jobs._execute import execute

    job_id = queue.submit("lobes", "alice", {"frf": {"freq_hz": [1.0, 2.0], "outputs": ["1x"], "inputs": ["1x"],
                                                      "real": [[[1.0]], [[1.0, 2.0]]], "imag": [[[0.0]], [[0.0]]]}})
    assert execute(queue.rows, job_id, queue.repo) == "failed"
    row = queue.get(job_id)._mapping
    assert row["error"].startswith("frf.real:") and "\n" not in row["error"] and row["attempts"] == 1
