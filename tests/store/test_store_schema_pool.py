"""A PostgreSQL test schema used again (tests/store/pg_schema_pool.py) is the schema the migrations make."""

from __future__ import annotations

import uuid

import pytest
import sqlalchemy as sa
from conftest import drop_pg_schema, pg_base_url
from pg_schema_pool import FreshState, fingerprint
from store_helpers import alter_version_row, planar_conditions, spring_joint

from jointdb.store import Repository, upgrade
from jointdb.store._guards import missing_guards


def _catalogue_two(url, blobs):
    with Repository(url, blobs=blobs) as repo:
        for name in ("T1", "T2"):
            repo.catalogue(name, "tool-holder", spring_joint(), planar_conditions(), "spring-damper-planar")
        repo.label("T1", 1, "released")


def _rows(engine, schema, table):
    with engine.connect() as conn:
        return [tuple(r) for r in conn.exec_driver_sql(f'SELECT * FROM "{schema}"."{table}" ORDER BY 1')]


@pytest.fixture
def pg(tmp_path):
    base = pg_base_url()
    engine = sa.create_engine(base)
    yield base, engine
    engine.dispose()


def test_a_used_schema_is_emptied_to_the_freshly_migrated_one(pg, pg_schema_pool, tmp_path):
    base, engine = pg
    schema, url = pg_schema_pool.take(base)
    fresh = pg_schema_pool.fresh[schema]
    stamp = _rows(engine, schema, "query_stamp")
    _catalogue_two(url, tmp_path / "blobs")
    pg_schema_pool.give_back(base, schema, url)
    assert (schema, url) in pg_schema_pool.free

    # the same catalogue as a schema migrated now, the schema's own name aside
    new = "jt_" + uuid.uuid4().hex[:12]
    with engine.begin() as conn:
        conn.exec_driver_sql(f"CREATE SCHEMA {new}")
    try:
        upgrade(f"{base}?options=-csearch_path%3D{new}")
        with engine.connect() as conn:
            migrated = FreshState(conn, new)
            assert fingerprint(conn, schema).replace(schema, "<s>") == migrated.fingerprint.replace(new, "<s>")
    finally:
        drop_pg_schema(engine, new)
    assert len(migrated.fingerprint.splitlines()) > 100  # tables, columns, indexes, triggers, event triggers
    for table in fresh.tables:
        got = _rows(engine, schema, table)
        if table == "query_stamp":  # the migrations' row, with a token of its own (the query cache keys on it)
            assert [(i, g) for i, _, g in got] == [(i, g) for i, _, g in stamp] and got[0][1] != stamp[0][1]
        else:
            assert len(got) == len(migrated.rows.get(table, [])), table

    # usable as new: numbering starts again, and every guard is there and refuses
    _catalogue_two(url, tmp_path / "blobs2")
    with engine.connect() as conn:
        conn.exec_driver_sql(f"SET search_path = {schema}")
        assert conn.exec_driver_sql("SELECT min(id), max(id) FROM joints").first() == (1, 2)
        assert missing_guards(conn)[0] == []
    for sql in ("UPDATE joint_versions SET torque_nm = 999", "TRUNCATE labels"):
        with pytest.raises(sa.exc.DBAPIError), engine.begin() as conn:
            conn.exec_driver_sql(f"SET search_path = {schema}")
            conn.exec_driver_sql(sql)


def test_a_schema_whose_guards_a_test_removed_is_dropped(pg, pg_schema_pool, tmp_path):
    base, engine = pg
    schema, url = pg_schema_pool.take(base)
    _catalogue_two(url, tmp_path / "blobs")
    alter_version_row(url, "UPDATE joint_versions SET torque_nm = 999")  # drops the DDL guard, disables a trigger
    pg_schema_pool.give_back(base, schema, url)
    assert all(s != schema for s, _ in pg_schema_pool.free)
    with engine.connect() as conn:
        assert conn.exec_driver_sql("SELECT count(*) FROM pg_namespace WHERE nspname = %s", (schema,)).scalar() == 0
