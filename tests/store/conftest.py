"""Fixtures of the storage tests: one suite, two backends (SQLite and PostgreSQL).

PostgreSQL tests use ``JOINTDB_TEST_PG_URL`` (e.g.
``postgresql+psycopg://postgres@127.0.0.1:54329/postgres``) and a fresh schema
per test (``search_path`` set through the URL); they are skipped, with the
reason, when the variable is unset or the server does not answer.
"""

from __future__ import annotations

import os
import uuid
from dataclasses import dataclass
from pathlib import Path

import pytest

from jointdb.frf import FRF  # noqa: F401

PG_ENV = "JOINTDB_TEST_PG_URL"
_pg_status: dict[str, str | None] = {}


def pg_base_url() -> str:
    """The server URL, or pytest.skip with the reason."""
    url = os.environ.get(PG_ENV)
    if not url:
        pytest.skip(f"{PG_ENV} is not set; PostgreSQL tests need a server URL")
    if url not in _pg_status:
        import sqlalchemy as sa

        try:
            engine = sa.create_engine(url, connect_args={"connect_timeout": 3})
            with engine.connect() as conn:
                conn.exec_driver_sql("select 1")
            engine.dispose()
            _pg_status[url] = None
        except Exception as exc:  # noqa: BLE001 - any failure means: skip with the reason
            _pg_status[url] = f"PostgreSQL at {PG_ENV} is unreachable: {str(exc).splitlines()[0]}"
    if _pg_status[url]:
        pytest.skip(_pg_status[url])
    return url


@dataclass
class Backend:
    name: str
    url: str
    blobs: Path

    def repo(self, **kw):
        from jointdb.store import Repository

        return Repository(self.url, blobs=self.blobs, **kw)


def _pg_schema(base: str):
    import sqlalchemy as sa

    schema = "jt_" + uuid.uuid4().hex[:12]
    engine = sa.create_engine(base)
    with engine.begin() as conn:
        conn.exec_driver_sql(f"CREATE SCHEMA {schema}")
    sep = "&" if "?" in base else "?"
    return engine, schema, f"{base}{sep}options=-csearch_path%3D{schema}"


@pytest.fixture(params=["sqlite", "postgresql"])
def empty_backend(request, tmp_path):
    """A backend with no schema yet (SQLite file does not exist; PG schema empty)."""
    if request.param == "sqlite":
        yield Backend("sqlite", f"sqlite:///{tmp_path / 'j.sqlite'}", tmp_path / "j.sqlite.blobs")
        return
    base = pg_base_url()
    engine, schema, url = _pg_schema(base)
    try:
        yield Backend("postgresql", url, tmp_path / "pgblobs")
    finally:
        drop_pg_schema(engine, schema)
        engine.dispose()


def drop_pg_schema(engine, schema: str) -> None:
    """Drop a test schema: first the DDL guard (event triggers) a superuser migration installed,
    which would refuse it, then the schema."""
    from jointdb.store._guards import event_trigger_names, guard_function

    with engine.begin() as conn:
        for name in event_trigger_names(schema):
            conn.exec_driver_sql(f'DROP EVENT TRIGGER IF EXISTS "{name}"')
        conn.exec_driver_sql(f"DROP FUNCTION IF EXISTS {guard_function(schema)}()")
        conn.exec_driver_sql(f"DROP SCHEMA {schema} CASCADE")


@pytest.fixture
def backend(empty_backend):
    """A migrated backend."""
    from jointdb.store import upgrade

    upgrade(empty_backend.url)
    return empty_backend


@pytest.fixture
def repo(backend):
    r = backend.repo()
    yield r
    r.close()
