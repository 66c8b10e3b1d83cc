"""Concurrent writers: 8 processes × 100 versions into one database → 800, no dups, none lost."""

from __future__ import annotations

import multiprocessing as mp
import sys
from collections import defaultdict

import pytest
import sqlalchemy as sa
from store_helpers import spring_joint

N_PROC = 8
N_EACH = 100
SHARED = 3  # every writer appends versions to the same 3 joints: maximal contention on numbering


def _writer(url: str, blobs: str, proc: int, n: int, queue) -> None:
    try:
        from jointdb.store import Conditions, Repository

        repo = Repository(url, blobs=blobs)
        for j in range(n):
            repo.catalogue(
                f"shared-{j % SHARED}",
                "tool-holder",
                spring_joint(k=(1e6 + 1000 * proc + j, 8e4), n=8),
                Conditions(("steel",), torque_nm=10.0 + j, extra={"writer": proc, "seq": j}),
                "spring-damper-planar",
                author=f"writer-{proc}",
                force=True,
            )
        repo.close()
        queue.put((proc, None))
    except BaseException as exc:  # report any failure to the parent
        queue.put((proc, repr(exc)))


def _run_writers(backend, blobs: str, n_proc: int, n_each: int):
    """``n_proc`` forked writers of ``n_each`` versions each; the repository to check them in."""
    ctx = mp.get_context("fork")
    queue = ctx.Queue()
    procs = [ctx.Process(target=_writer, args=(backend.url, blobs, p, n_each, queue)) for p in range(n_proc)]
    for p in procs:
        p.start()
    results = dict(queue.get(timeout=600) for _ in procs)
    for p in procs:
        p.join(timeout=60)
    assert results == {p: None for p in range(n_proc)}
    from jointdb.store import Repository

    return Repository(backend.url, blobs=blobs)


def _check_written(repo, n_proc: int, n_each: int) -> None:
    """Every writer's versions are there once, numbered without gaps, audited, and ``check`` passes."""
    seen = set()
    total = 0
    for j in range(SHARED):
        hist = repo.history(f"shared-{j}")
        assert [v.version for v in hist] == list(range(1, len(hist) + 1))  # gapless, unique
        assert [v.parent_version for v in hist] == [None] + list(range(1, len(hist)))
        for v in hist:
            seen.add((v.conditions.extra["writer"], v.conditions.extra["seq"]))
        total += len(hist)
    assert total == n_proc * n_each
    assert seen == {(p, j) for p in range(n_proc) for j in range(n_each)}  # none lost, none doubled
    with repo.read_engine.connect() as conn:
        n_uuid = conn.execute(sa.text("SELECT count(DISTINCT uuid) FROM joint_versions")).scalar_one()
        n_joints = conn.execute(sa.text("SELECT count(*) FROM joints")).scalar_one()
    assert n_uuid == n_proc * n_each and n_joints == SHARED
    per_writer = defaultdict(int)
    for a in repo.audit(limit=10_000):
        if a["action"] == "catalogue":
            per_writer[a["actor"]] += 1
    assert per_writer == {f"writer-{p}": n_each for p in range(n_proc)}
    report = repo.check()
    assert report.ok, report.problems
    assert report.versions_checked == n_proc * n_each


@pytest.mark.skipif(sys.platform == "win32", reason="uses fork")
def test_eight_processes_hundred_versions_each(backend):
    _check_written(_run_writers(backend, str(backend.blobs), N_PROC, N_EACH), N_PROC, N_EACH)


@pytest.mark.skipif(sys.platform == "win32", reason="uses fork")
def test_four_processes_with_database_blobs(backend):
    """The same with the blobs in the database (blob and rows in one transaction; on PostgreSQL
    the joint row is locked in one SELECT and its latest version read in the next)."""
    repo = _run_writers(backend, "database", 4, 30)
    try:
        _check_written(repo, 4, 30)
        with repo.read_engine.connect() as conn:
            assert conn.execute(sa.text("SELECT count(*) FROM frf_blobs")).scalar_one() == 4 * 30
    finally:
        repo.close()


N_MOVERS = 8
N_MOVES = 60


def _mover(url: str, blobs: str, proc: int, n: int, queue) -> None:
    try:
        import random

        from jointdb.store import Repository

        repo = Repository(url, blobs=blobs)
        rng = random.Random(proc)
        for _ in range(n):
            repo.label("L", rng.randint(1, 5), "released", author=f"mover-{proc}")
        repo.close()
        queue.put((proc, None))
    except BaseException as exc:  # report any failure to the parent
        queue.put((proc, repr(exc)))


@pytest.mark.skipif(sys.platform == "win32", reason="uses fork")
def test_concurrent_label_moves_record_the_true_previous_version(backend):
    """8 processes x 60 moves of one label: read in commit order, each audit row's previous
    version is the version the row before it set (the label row is locked while it is moved)."""
    repo = backend.repo()
    for i in range(5):
        repo.catalogue("L", "tool-holder", spring_joint(k=(1e6 + i, 8e4), n=8), None, "spring-damper-planar")
    repo.close()
    ctx = mp.get_context("fork")
    queue = ctx.Queue()
    procs = [ctx.Process(target=_mover, args=(backend.url, str(backend.blobs), p, N_MOVES, queue))
             for p in range(N_MOVERS)]
    for p in procs:
        p.start()
    results = dict(queue.get(timeout=600) for _ in procs)
    for p in procs:
        p.join(timeout=60)
    assert results == {p: None for p in range(N_MOVERS)}
    repo = backend.repo()
    moves = [a for a in reversed(repo.audit("L", limit=10_000)) if a["action"] == "label"]
    assert len(moves) == N_MOVERS * N_MOVES
    previous = None
    wrong = 0
    for a in moves:
        wrong += a["details"]["previous_version"] != previous
        previous = a["version"]
    assert wrong == 0, f"{wrong} of {len(moves)} audit rows record a wrong previous version"
    assert repo.get("L", label="released").version == previous
    repo.close()
