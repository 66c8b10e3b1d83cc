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


class _SchemaPool:
    """Migrated PostgreSQL schemas of this process that a finished test left as migrated (tests/store/pg_schema_pool.py)."""

    def __init__(self):
        self.free: list[tuple[str, str]] = []  # (schema, url)
        self.fresh: dict[str, object] = {}  # schema -> FreshState
        self.engines: dict[str, object] = {}  # base url -> engine

    def engine(self, base: str):
        import sqlalchemy as sa

        if base not in self.engines:
            self.engines[base] = sa.create_engine(base)
        return self.engines[base]

    def take(self, base: str) -> tuple[str, str]:
        """A migrated schema: a used one emptied again, else a new one migrated by Alembic."""
        for k, (schema, url) in enumerate(self.free):
            if url.startswith(base):
                return self.free.pop(k)
        from pg_schema_pool import FreshState

        from jointdb.store import upgrade

        engine, schema, url = _pg_schema(base)
        try:
            upgrade(url)
            with engine.connect() as conn:
                self.fresh[schema] = FreshState(conn, schema)
        finally:
            engine.dispose()
        return schema, url

    def give_back(self, base: str, schema: str, url: str) -> None:
        """Empty ``schema`` for the next test, or drop it when the test changed more than its rows."""
        from pg_schema_pool import empty_again

        engine = self.engine(base)
        if empty_again(engine, schema, self.fresh[schema]):
            self.free.append((schema, url))
        else:
            self.fresh.pop(schema)
            drop_pg_schema(engine, schema)

    def close(self) -> None:
        for schema, url in self.free:
            base = next(b for b in self.engines if url.startswith(b))
            drop_pg_schema(self.engines[base], schema)
        self.free.clear()
        for engine in self.engines.values():
            engine.dispose()


@pytest.fixture(scope="session")
def pg_schema_pool():
    pool = _SchemaPool()
    yield pool
    pool.close()


@pytest.fixture(params=["sqlite", "postgresql"])
def backend(request, tmp_path):
    """A migrated backend (on PostgreSQL a schema of the process's pool, as freshly migrated)."""
    if request.param == "sqlite":
        from jointdb.store import upgrade

        b = Backend("sqlite", f"sqlite:///{tmp_path / 'j.sqlite'}", tmp_path / "j.sqlite.blobs")
        upgrade(b.url)
        yield b
        return
    base = pg_base_url()
    pool = request.getfixturevalue("pg_schema_pool")
    schema, url = pool.take(base)
    try:
        yield Backend("postgresql", url, tmp_path / "pgblobs")
    finally:
        pool.give_back(base, schema, url)


@pytest.fixture
def repo(backend):
    r = backend.repo()
    yield r
    r.close()
