"""`jointdb query` on PostgreSQL: psycopg directly (no SQLAlchemy, no Alembic), the same answers as
the library, the same refusals, and the candidate query's read transaction with its own work_mem."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
from store_helpers import assert_one_line_error, planar_conditions, run_main, spring_joint

from jointdb.errors import InputError
from jointdb.store import Repository

SELECTIONS = [
    ((), {}),
    (("--label", "released"), {"label": "released"}),
    (("--all-versions",), {"all_versions": True}),
    (("--include-deprecated",), {"include_deprecated": True}),
    (("--all-versions", "--include-deprecated"), {"all_versions": True, "include_deprecated": True}),
]


@pytest.fixture
def pg_empty(tmp_path):
    """A fresh PostgreSQL schema without tables (skipped without a server)."""
    from conftest import Backend, _pg_schema, drop_pg_schema, pg_base_url

    engine, schema, url = _pg_schema(pg_base_url())
    try:
        yield Backend("postgresql", url, tmp_path / "pgblobs")
    finally:
        drop_pg_schema(engine, schema)
        engine.dispose()


@pytest.fixture
def pg(pg_empty):
    from jointdb.store import upgrade

    upgrade(pg_empty.url)
    backend = pg_empty
    with Repository(backend.url, blobs=backend.blobs) as repo:
        for name, torques in (("A", (10.0, 30.0)), ("B", (20.0,)), ("C", (40.0, 25.0, 60.0))):
            for t in torques:
                repo.catalogue(name, "tool-holder", spring_joint(), planar_conditions(torque=t),
                               "spring-damper-planar", force=True)
        repo.label("A", 1, "released")
        repo.label("C", 2, "released")
        repo.deprecate("C", 3, reason="bad fit")
        repo.deprecate("B", reason="withdrawn")
    return backend


@pytest.mark.parametrize("opts, kw", SELECTIONS)
def test_postgres_fast_path_equals_the_library(capsys, pg, tmp_path, monkeypatch, opts, kw):
    monkeypatch.setenv("JOINTDB_QUERY_CACHE", str(tmp_path / "cache"))
    code, out, err = run_main(capsys, "query", "--type", "tool-holder", "--torque", "24", "-k", "9", "--json",
                              "--db", pg.url, *opts)
    assert code == 0, err
    got = [(r["name"], r["version"], r["state"], r["distance"]) for r in json.loads(out)]
    with Repository(pg.url, blobs=pg.blobs) as repo:
        want = [(m.version.name, m.version.version, m.version.state, m.distance)
                for m in repo.nearest("tool-holder", planar_conditions(torque=24.0, materials=()), k=9, **kw)]
    assert got == want and len(got) >= 2


def test_query_on_postgres_imports_neither_sqlalchemy_nor_alembic(pg, tmp_path):
    code = ("import sys; from jointdb.cli import main\n"
            f"sys.argv = ['jointdb', 'query', '--type', 'tool-holder', '--torque', '24', '--db', {pg.url!r}]\n"
            "try:\n    main()\nexcept SystemExit as e:\n    assert not e.code, e.code\n"
            "print('LOADED', sorted(m for m in ('sqlalchemy', 'alembic', 'h5py', 'scipy') if m in sys.modules))")
    env = {**__import__("os").environ, "JOINTDB_QUERY_CACHE": str(tmp_path / "cache")}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, env=env)
    assert out.returncode == 0, out.stderr
    assert "LOADED []" in out.stdout and "A" in out.stdout


def test_refusals_are_the_repositorys(capsys, pg_empty):
    args = ("query", "--type", "tool-holder", "--torque", "3", "--db")
    assert_one_line_error(run_main(capsys, *args, pg_empty.url), InputError.exit_code,
                          "no jointdb schema yet; run `jointdb db upgrade")
    from jointdb.store import upgrade

    upgrade(pg_empty.url, "0010")
    assert_one_line_error(run_main(capsys, *args, pg_empty.url), InputError.exit_code, "jointdb db upgrade")
    dead = "postgresql+psycopg://postgres@127.0.0.1:9/postgres?connect_timeout=2"
    line = assert_one_line_error(run_main(capsys, *args, dead), InputError.exit_code, "cannot open database")
    assert "127.0.0.1:9" in line


def test_connection_settings_match_the_engines():
    from jointdb.store import _db, _light

    assert _light.PG_CONNECT_TIMEOUT_S == _db.PG_CONNECT_TIMEOUT_S
    info, kw = _light._libpq("postgresql+psycopg://u:p%40w@h:5/db?options=-csearch_path%3Dx&sslmode=disable")
    assert info == ""  # keywords only: libpq never parses (and never quotes back) the URL
    assert kw == {"user": "u", "password": "p@w", "host": "h", "port": "5", "dbname": "db", "sslmode": "disable",
                  "connect_timeout": "10", "options": "-csearch_path=x -c jit=off"}
    assert _light._libpq("postgresql://h/db?connect_timeout=3")[1]["connect_timeout"] == "3"
    assert _light.postgres_target("postgresql+psycopg2://h/db") is None  # another driver: the Repository


def test_a_password_libpq_cannot_parse_is_not_shown(capsys):
    """A password with a stray ``%`` (``50%of``) made libpq's URI parser quote it back in its error."""
    from jointdb.errors import InputError

    url = "postgresql+psycopg://bob:50%offsecret@127.0.0.1:9/postgres?connect_timeout=2"
    line = assert_one_line_error(run_main(capsys, "query", "--db", url, "--type", "tool-holder", "--torque", "40"),
                                 InputError.exit_code, "cannot open database")
    assert "offsecret" not in line and "50%" not in line


def test_the_candidate_fetch_has_its_own_work_mem(pg):
    from jointdb.store._light import open_postgres_reader
    from jointdb.store._nearest import WORK_MEM, Selection, _fetch

    reader = open_postgres_reader(pg.url)
    try:
        default = reader.rows("SHOW work_mem")[0][0]
        with reader.snapshot():
            assert _fetch(reader, Selection("tool-holder"), ["diameter_m"]).version_id.size == 2
            assert reader.rows("SHOW work_mem")[0][0] == WORK_MEM
        assert reader.rows("SHOW work_mem")[0][0] == default != WORK_MEM  # SET LOCAL: that transaction only
    finally:
        reader.conn.close()
