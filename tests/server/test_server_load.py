"""Several uvicorn workers on one PostgreSQL database (blobs in the database) behave as one:
16 clients x 50 catalogue writes + read-backs through HTTP lose and duplicate nothing; a
worker killed with SIGKILL in the middle of uploads leaves nothing half-written."""

from __future__ import annotations

import os
import signal
import threading
import time

import pytest

from server_helpers import _pg_schema, drop_pg_schema, make_tokens, pg_base_url, run_load, start_server, stop_server

pytestmark = pytest.mark.postgres


@pytest.fixture
def pg_server(tmp_path):
    from jointdb.store import upgrade

    engine, schema, url = _pg_schema(pg_base_url())
    try:
        upgrade(url)
        tokens = make_tokens(url, "database")
        srv = start_server(url, "database", tmp_path / "server.log", workers=2)
        srv.tokens = tokens
        yield srv
        stop_server(srv)
    finally:
        drop_pg_schema(engine, schema)
        engine.dispose()


def _workers(pid: int) -> list[int]:
    """Child processes of the uvicorn supervisor (its workers)."""
    out = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/stat") as f:
                    fields = f.read().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[1]) == pid:
                out.append(int(entry))
    return out


def test_two_workers_lose_and_duplicate_nothing(pg_server, tmp_path):
    assert len(_workers(pg_server.proc.pid)) >= 2
    result = run_load(pg_server, clients=16, writes=50, tmp=tmp_path)
    assert result["acknowledged"] == 800 and result["distinct_acknowledged"] == 800, result
    assert result["lost"] == 0 and result["duplicated"] == 0 and result["extra_in_db"] == 0, result
    assert result["stored"] == 800 and result["check_ok"], result
    with pg_server.repo() as repo:
        for name in ("L0-0", "L3-4"):
            assert [v.version for v in repo.history(name)] == list(range(1, 41))  # 1..n, no gap


def test_worker_killed_mid_upload_leaves_nothing_half_written(pg_server, tmp_path):
    workers = _workers(pg_server.proc.pid)
    killed = []

    def killer():
        time.sleep(1.5)  # uploads are under way
        os.kill(workers[0], signal.SIGKILL)
        killed.append(workers[0])

    t = threading.Thread(target=killer)
    t.start()
    result = run_load(pg_server, clients=8, writes=15, tmp=tmp_path, tolerate_errors=True)
    t.join()
    assert killed
    assert result["lost"] == 0 and result["duplicated"] == 0, result
    assert result["check_ok"], result  # every row's blob present and intact, numbering 1..n
    with pg_server.repo() as repo:
        for j in repo.list_joints():
            for v in repo.history(j.name):
                repo.load_frf(v)  # every stored version reads back verified
