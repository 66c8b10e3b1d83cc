"""Suite-wide settings: the tests never write into the user's own cache directory; one loader for the
repository's scripts (fixture generators under fixtures/, validation helpers under bench/)."""

from __future__ import annotations

import importlib.util
import os
import sys
import tempfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

# The nearest-query cache (jointdb.store._qcache) goes to a directory of this test run, inherited by the
# `python -m jointdb` subprocesses the CLI tests start; a test that sets its own value still wins.
os.environ.setdefault("JOINTDB_QUERY_CACHE", tempfile.mkdtemp(prefix="jointdb-test-query-cache-"))
# the server's cache of encoded FRF downloads (jointdb.server._encoded), likewise
os.environ.setdefault("JOINTDB_CACHE_DIR", tempfile.mkdtemp(prefix="jointdb-test-download-cache-"))


def _own_pg_database() -> None:
    """Under pytest-xdist, each worker process runs its PostgreSQL tests in a database of its own.

    The migrations install DDL guards as event triggers, which are per database: a worker dropping a
    test schema (and its guard) while another runs DDL in the same database would make the other's
    statement fail ("cache lookup failed for function"). ``JOINTDB_TEST_PG_URL`` is rewritten to the
    worker's database (created when missing), which every test and server subprocess then inherits.
    """
    worker, url = os.environ.get("PYTEST_XDIST_WORKER"), os.environ.get("JOINTDB_TEST_PG_URL")
    if not worker or not url:
        return
    import sqlalchemy as sa
    from sqlalchemy.engine import make_url

    name = "jointdb_test_" + "".join(ch for ch in worker if ch.isalnum())
    engine = sa.create_engine(url, isolation_level="AUTOCOMMIT")
    try:
        with engine.connect() as conn:
            if conn.execute(sa.text("SELECT 1 FROM pg_database WHERE datname = :n"), {"n": name}).first() is None:
                conn.exec_driver_sql(f'CREATE DATABASE "{name}"')
    except sa.exc.OperationalError:
        return  # no server: the PostgreSQL tests say so themselves
    finally:
        engine.dispose()
    os.environ["JOINTDB_TEST_PG_URL"] = make_url(url).set(database=name).render_as_string(hide_password=False)


_own_pg_database()

# New SQLite catalogues of this process start as a copy of one built by the real migrations (see
# tests/sqlite_template.py); tests marked `real_migrations` run Alembic for every database.
import sqlite_template  # noqa: E402  (tests/ is on sys.path: pytest puts a conftest's directory there)

sqlite_template.install()


def _load_script(relative: str):
    """The repository script ``relative`` (e.g. ``fixtures/make_catalogue.py``) imported as a module under its
    file name (registered in ``sys.modules``, so dataclasses and pickling inside it work)."""
    path = ROOT / relative
    spec = importlib.util.spec_from_file_location(path.stem, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[path.stem] = module
    spec.loader.exec_module(module)
    return module


#: Test files that keep one worker busy longest, longest first (per-file wall time of a full `-n 2 --dist loadfile`
#: run, 2026-11-26 14:00Z, on the quiet machine; only their order matters here).
#: `make test` hands out whole files (`--dist loadfile`) in collection order (`--no-loadscope-reorder`): started
#: first, these run while the other worker takes the many short files, instead of one of them starting near the
#: end and leaving the other worker idle. Files not listed follow in pytest's order. Only the order changes:
#: every test still runs. A new slow file belongs here.
LONGEST_FIRST = (
    "tests/diagnose/test_diagnose_concealed.py",
    "tests/test_readme.py",
    "tests/diagnose/test_diagnose_stack_joints.py",
    "tests/server/test_server_jobs.py",
    "tests/diagnose/test_diagnose_cli.py",
    "tests/store/test_store_chain.py",
    "tests/server/test_web_flow.py",
    "tests/optimize/test_optimize_catalogue.py",
    "tests/store/test_store_crash.py",
    "tests/server/test_server_optimize_job.py",
    "tests/store/test_store_query_selection.py",
    "tests/server/test_server_load.py",
    "tests/store/test_store_concurrency.py",
    "tests/stack/test_spindle_band.py",
    "tests/diagnose/test_diagnose_artefacts.py",
    "tests/security/test_attack_suite.py",
    "tests/diagnose/test_diagnose_bench_cases.py",
    "tests/optimize/test_optimize.py",
    "tests/optimize/test_simulate.py",
    "tests/stack/test_band_truth_b.py",
    "tests/server/test_server_browser.py",
    "tests/server/test_server_web_security.py",
    "tests/cli/test_cli_output.py",
    "tests/test_campaign_walk.py",
    "tests/server/test_server_idempotency.py",
    "tests/stack/test_stack_validation.py",
    "tests/optimize/test_optimize_job.py",
    "tests/cli/test_cli_campaign_from_parts.py",
    "tests/server/test_server_cli.py",
)


def pytest_collection_modifyitems(session, config, items):
    """Files of ``LONGEST_FIRST`` first, in that order; the order of tests inside a file is kept."""
    rank = {path: k for k, path in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.nodeid.split("::", 1)[0], len(rank)))


def _blas_pools() -> dict[str, int]:
    from threadpoolctl import threadpool_info
    return {i["filepath"]: i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"}


@pytest.fixture(autouse=True, scope="module")
def _blas_pools_unchanged():
    """A test module must leave this process's BLAS thread pools as it found them.

    One test once raised them to 2 threads as a side effect; every later test in the same
    pytest worker then ran its small solves 15-45x slower on a busy 2-core machine, and the
    suite's time depended on which worker drew that file.
    """
    before = _blas_pools()
    yield
    after = _blas_pools()
    changed = {path: (before[path], n) for path, n in after.items() if path in before and before[path] != n}
    if changed:
        pytest.fail(f"this module changed the process's BLAS threads (before, after): {changed}")


def pytest_runtest_setup(item):
    """A test marked ``real_migrations`` creates its SQLite databases with every Alembic migration."""
    sqlite_template.ENABLED["on"] = item.get_closest_marker("real_migrations") is None


@pytest.fixture(scope="session")
def load_script():
    """``load_script("fixtures/make_catalogue.py")``: a repository script as a module (not an installed package)."""
    return _load_script


@pytest.fixture
def run_cli(monkeypatch, capsys):
    """``run_cli("identify", path, "--out", out)``: ``jointdb ARGS`` run in this process (``main()`` with
    ``sys.argv`` set); ``(exit code, stdout, stderr)``."""
    from jointdb.cli import main

    def run(*args):
        monkeypatch.setattr(sys, "argv", ["jointdb", *map(str, args)])
        code = 0
        try:
            main()
        except SystemExit as exc:
            code = exc.code or 0
        out = capsys.readouterr()
        return code, out.out, out.err

    return run


@pytest.fixture
def cli(run_cli):
    """``cli("identify", path)``: ``jointdb ARGS`` in this process as :func:`run_cli` runs it, the result shaped as
    ``subprocess.run``'s (``returncode``, ``stdout``, ``stderr``) for tests written against a subprocess: for a
    command under test, not for what only a real process shows (exit by signal, environment, start-up)."""
    from types import SimpleNamespace

    def call(*args):
        code, out, err = run_cli(*args)
        return SimpleNamespace(returncode=code, stdout=out, stderr=err)

    return call
