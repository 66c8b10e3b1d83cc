#!/usr/bin/env python
"""Benchmark: one 50-row page of the catalogue listing at 100,000 versions (issue 23).

For each backend (SQLite always; PostgreSQL at ``$JOINTDB_BENCH_PG_URL``, else the dev
server ``postgresql+psycopg://postgres@127.0.0.1:54330/postgres`` when it answers) the
catalogue is filled in bulk through the real tables (:mod:`_bulk`; 100,000 versions,
``--per-joint`` of them per joint) and the same random pages are asked for, interleaved,
three ways in one process:

- **bare SQL** (the reference): the page's one SELECT (:func:`jointdb.store._listing.page_statement`:
  one range of the head index, the total read from ``query_counts`` on a first page and carried
  in the cursor after it) executed and its rows fetched, nothing else;
- ``Repository.list_page``: the same statement plus argument checks, record-hash verification
  and the :class:`JointVersion` of each row;
- ``GET /api/v1/joints?limit=50&after=…`` called straight into the ASGI app (:mod:`_asgi`: no socket
  and no HTTP client; the middleware, routing, validation, the thread-pool hop and JSON encoding are
  in; uvicorn's parsing, ~0.2 ms with httptools, and a client's work are not).

Pages start after a random joint (keyset cursor), every 4th is the first page, every 5th is
filtered on a joint type. Reported: p50 and p99 in ms and each path's p50 over the bare SQL's.
Goal: p99 <= 50 ms for ``list_page`` and for the HTTP page, on both backends.

Run: ``PYTHONPATH=. .venv/bin/python bench/bench_listing.py [--requests 300] [--per-joint 1] [--no-pg] [--no-sqlite]``;
``--pg-versions 1000000`` lists the kept 1M schema of ``bench/bench_store_rows.py --pg`` instead.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import statistics
import sys
import tempfile
import time
import uuid
from pathlib import Path
from urllib.parse import urlencode

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _asgi import call  # noqa: E402
from _bulk import TYPES, bulk_fill  # noqa: E402

DEV_PG = "postgresql+psycopg://postgres@127.0.0.1:54330/postgres"
N_VERSIONS = 100_000
PAGE = 50


def _pct(values: list[float], q: float) -> float:
    return float(np.percentile(np.asarray(values) * 1e3, q))


def _requests(repo, n_joints: int, n: int, seed: int = 11) -> list[dict]:
    """The pages asked for: ``after`` a random joint (None: the first page), sometimes one type.
    A cursor carries the listing's total, as the ``next`` of a real first page does."""
    from jointdb.store._listing import encode_cursor

    totals = {t: repo.list_page(t, limit=1).total for t in (None, *TYPES)}
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        joint_type = TYPES[i % 2] if i % 5 == 0 else None
        after = None if i % 4 == 0 else encode_cursor(f"bulk-{int(rng.integers(n_joints)):07d}", totals[joint_type])
        out.append({"after": after, "joint_type": joint_type})
    return out


def _bare_sql(repo, req: dict) -> int:
    """The page's one SELECT, rows fetched: what the database does for a page."""
    from jointdb.store._listing import page_statement, read_cursor

    filters = dict(joint_type=req["joint_type"], materials=(), label=None, include_deprecated=True, state=None,
                   torque=(None, None), preload=(None, None), name_contains=None)
    after, total = read_cursor(req["after"]) if req["after"] else (None, None)
    with repo.read_engine.connect() as conn:
        rows = conn.execute(page_statement(conn.dialect.name, after=after, offset=0, limit=PAGE,
                                           with_total=total is None, **filters)).all()
    return len(rows)


async def _measure(repo, requests: list[dict]) -> dict[str, list[float]]:
    from jointdb.server import create_app
    from jointdb.server._settings import Settings

    app = create_app(Settings(bind_host="127.0.0.1", open_reads=True), repo=repo)
    times: dict[str, list[float]] = {"bare SQL": [], "Repository.list_page": [], "GET /api/v1/joints": []}
    for warm in requests[:10]:  # connections, caches, first compilation of the statement
        _bare_sql(repo, warm)
        repo.list_page(warm["joint_type"], after=warm["after"], limit=PAGE)
        await call(app, "GET", "/api/v1/joints", urlencode({"limit": PAGE}))
    for req in requests:
        query = urlencode({"limit": PAGE, **({"after": req["after"]} if req["after"] else {}),
                           **({"type": req["joint_type"]} if req["joint_type"] else {})})
        t0 = time.perf_counter()
        n_sql = _bare_sql(repo, req)
        t1 = time.perf_counter()
        page = repo.list_page(req["joint_type"], after=req["after"], limit=PAGE)
        t2 = time.perf_counter()
        status, body = await call(app, "GET", "/api/v1/joints", query)
        t3 = time.perf_counter()
        got = json.loads(body)["items"] if status == 200 else []
        if status != 200 or [x["name"] for x in got] != [v.name for v in page.items] or n_sql != len(
                page.items) + (1 if page.next else 0):
            raise RuntimeError(f"the three paths disagree on {req}: HTTP {status}, {n_sql} SQL rows, "
                               f"{len(page.items)} listed")
        times["bare SQL"].append(t1 - t0)
        times["Repository.list_page"].append(t2 - t1)
        times["GET /api/v1/joints"].append(t3 - t2)
    return times


def run_backend(label: str, url: str, per_joint: int, n_requests: int, blobs: Path,
                kept: tuple[int, str] | None = None) -> list[str]:
    """One backend's rows; ``kept``: ``(versions, note)`` of an already filled database (no fill)."""
    from jointdb.store import Repository

    repo = Repository(url, blobs=blobs, auto_create=kept is None)  # no blob is read: a listing touches rows only
    n_versions = kept[0] if kept else N_VERSIONS
    try:
        t0 = time.perf_counter()
        if kept is None:
            bulk_fill(repo, N_VERSIONS, per_joint)
        filled = kept[1] if kept else f"filled in {time.perf_counter() - t0:.0f} s"
        times = asyncio.run(_measure(repo, _requests(repo, n_versions // per_joint, n_requests)))
    finally:
        repo.close()
    ref = statistics.median(times["bare SQL"])
    lines = [f"{label}: {n_versions} versions, {per_joint} per joint ({n_versions // per_joint} joints), "
             f"{filled}; {n_requests} pages of {PAGE}"]
    for path, values in times.items():
        ratio = "" if path == "bare SQL" else f"  p50 ratio to bare SQL {statistics.median(values) / ref:.2f}"
        goal = "" if path == "bare SQL" else ("  (goal p99 <= 50 ms: met)" if _pct(values, 99) <= 50
                                              else "  (goal p99 <= 50 ms: NOT met)")
        lines.append(f"  {path:<22} p50 {_pct(values, 50):7.2f} ms  p99 {_pct(values, 99):7.2f} ms{ratio}{goal}")
    return lines


def _pg_url(args) -> str | None:
    if args.no_pg:
        return None
    url = os.environ.get("JOINTDB_BENCH_PG_URL") or DEV_PG
    import sqlalchemy as sa

    try:
        with sa.create_engine(url).connect() as conn:
            conn.exec_driver_sql("SELECT 1")
    except sa.exc.OperationalError:
        print(f"PostgreSQL at {url.split('@')[-1]} does not answer: skipped")
        return None
    return url


def run_pg(base: str, per_joint: int, n_requests: int, blobs: Path) -> list[str]:
    """The PostgreSQL row in a schema of its own, dropped afterwards."""
    import sqlalchemy as sa

    from jointdb.store._guards import event_trigger_names, guard_function

    schema = "bench_listing_" + uuid.uuid4().hex[:10]
    admin = sa.create_engine(base)
    with admin.begin() as conn:
        conn.exec_driver_sql(f"CREATE SCHEMA {schema}")
    sep = "&" if "?" in base else "?"
    try:
        return run_backend("PostgreSQL", f"{base}{sep}options=-csearch_path%3D{schema}", per_joint, n_requests, blobs)
    finally:
        with admin.begin() as conn:  # the DDL guard a migration installed would refuse the drop: it goes first
            for name in event_trigger_names(schema):
                conn.exec_driver_sql(f'DROP EVENT TRIGGER IF EXISTS "{name}"')
            conn.exec_driver_sql(f"DROP FUNCTION IF EXISTS {guard_function(schema)}()")
            conn.exec_driver_sql(f"DROP SCHEMA {schema} CASCADE")
        admin.dispose()


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--requests", type=int, default=300)
    ap.add_argument("--per-joint", type=int, default=1, help="versions per joint (1: 100,000 joints)")
    ap.add_argument("--no-pg", action="store_true")
    ap.add_argument("--no-sqlite", action="store_true")
    ap.add_argument("--pg-versions", type=int, default=None,
                    help="PostgreSQL only: list the kept bench schema of bench_store_rows.py with this many "
                         "versions, 1 per joint (filled by COPY when missing), e.g. 1000000")
    args = ap.parse_args(argv)
    if args.pg_versions:
        from _bench_pg_rows import prepare

        url, note = prepare(_pg_url(args) or DEV_PG, args.pg_versions, refill=False, check_index=False)
        with tempfile.TemporaryDirectory() as tmp:
            for line in run_backend("PostgreSQL", url, 1, args.requests, Path(tmp) / "blobs",
                                    kept=(args.pg_versions, note)):
                print(line, flush=True)
        return
    print(f"bench_listing  {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}  load average "
          f"{' '.join(f'{x:.1f}' for x in os.getloadavg())} on {os.cpu_count()} cores")
    with tempfile.TemporaryDirectory() as tmp:
        sqlite = [] if args.no_sqlite else run_backend("SQLite", f"sqlite:///{Path(tmp) / 'cat.sqlite'}",
                                                       args.per_joint, args.requests, Path(tmp) / "blobs")
        for line in sqlite:
            print(line, flush=True)
        pg = _pg_url(args)
        if pg:
            for line in run_pg(pg, args.per_joint, args.requests, Path(tmp) / "pg-blobs"):
                print(line, flush=True)


if __name__ == "__main__":
    main()
