"""`jointdb query`: the SQLite fast path (no SQLAlchemy) equals the library; selection options;
the schema check is one SELECT against a head revision a test keeps equal to the scripts."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
from store_helpers import assert_one_line_error, planar_conditions, run_main, spring_joint

from jointdb.errors import InputError, NotFoundError
from jointdb.store import Repository, upgrade


def test_head_revision_constant_is_the_newest_migration_script():
    from jointdb.store._db import _script
    from jointdb.store._sqlitefile import HEAD_REVISION

    assert _script().get_current_head() == HEAD_REVISION


@pytest.fixture
def db(tmp_path):
    path = tmp_path / "q.sqlite"
    repo = Repository(path)
    for name, torques in (("A", (10.0, 30.0)), ("B", (20.0,)), ("C", (40.0, 25.0, 60.0))):
        for t in torques:
            repo.catalogue(name, "tool-holder", spring_joint(), planar_conditions(torque=t), "spring-damper-planar", force=True)
    repo.label("A", 1, "released")
    repo.label("C", 2, "released")
    repo.deprecate("C", 3, reason="bad fit")  # C's current version is v2 (25 N·m)
    repo.deprecate("B", reason="withdrawn")
    repo.close()
    return path


def _query(capsys, db, *opts):
    code, out, err = run_main(capsys, "query", "--type", "tool-holder", "--torque", "24", "-k", "9", "--json",
                              "--db", db, *opts)
    assert code == 0, err
    return [(r["name"], r["version"], r["state"], r["distance"]) for r in json.loads(out)]


@pytest.mark.parametrize("opts, kw", [
    ((), {}),
    (("--label", "released"), {"label": "released"}),
    (("--all-versions",), {"all_versions": True}),
    (("--include-deprecated",), {"include_deprecated": True}),
    (("--all-versions", "--include-deprecated"), {"all_versions": True, "include_deprecated": True}),
    (("--label", "released", "--include-deprecated"), {"label": "released", "include_deprecated": True}),
])
def test_cli_fast_path_equals_the_library(capsys, db, opts, kw):
    got = _query(capsys, db, *opts)
    with Repository(db) as repo:
        want = [(m.version.name, m.version.version, m.version.state, m.distance)
                for m in repo.nearest("tool-holder", planar_conditions(torque=24.0, materials=()), k=9, **kw)]
    assert got == want


def test_selection_semantics_on_a_small_catalogue(capsys, db):
    names = lambda rows: sorted((n, v) for n, v, _, _ in rows)  # noqa: E731
    assert names(_query(capsys, db)) == [("A", 2), ("C", 2)]  # newest not deprecated; B withdrawn
    assert names(_query(capsys, db, "--include-deprecated")) == [("A", 2), ("B", 1), ("C", 3)]
    assert names(_query(capsys, db, "--all-versions")) == [("A", 1), ("A", 2), ("C", 1), ("C", 2)]
    assert names(_query(capsys, db, "--label", "released")) == [("A", 1), ("C", 2)]
    rows = _query(capsys, db, "--all-versions", "--include-deprecated")
    assert len(rows) == 6 and {s for n, v, s, _ in rows if (n, v) in {("B", 1), ("C", 3)}} == {"deprecated"}


def test_errors_are_one_line(capsys, db, tmp_path):
    assert_one_line_error(run_main(capsys, "query", "--type", "tool-holder", "--torque", "3", "--label", "nope",
                                   "--db", db), NotFoundError.exit_code, "labelled 'nope'")
    assert_one_line_error(run_main(capsys, "query", "--type", "tool-holder", "--torque", "3", "--db",
                                   tmp_path / "missing.sqlite"), NotFoundError.exit_code, "does not exist")
    (tmp_path / "junk.sqlite").write_bytes(b"not a database at all")
    assert_one_line_error(run_main(capsys, "query", "--type", "tool-holder", "--torque", "3", "--db",
                                   tmp_path / "junk.sqlite"), InputError.exit_code, "not a SQLite database")
    old = tmp_path / "old.sqlite"
    upgrade(old, "0003")
    assert_one_line_error(run_main(capsys, "query", "--type", "tool-holder", "--torque", "3", "--db", old),
                          InputError.exit_code, "run `jointdb db upgrade`")
    assert not (tmp_path / "missing.sqlite").exists()


def test_query_on_sqlite_imports_neither_sqlalchemy_nor_alembic(db):
    code = ("import sys; from jointdb.cli import main\n"
            f"sys.argv = ['jointdb', 'query', '--type', 'tool-holder', '--torque', '24', '--db', {str(db)!r}]\n"
            "try:\n    main()\nexcept SystemExit as e:\n    assert not e.code, e.code\n"
            "print('LOADED', sorted(m for m in ('sqlalchemy', 'alembic', 'h5py', 'scipy') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert "LOADED []" in out.stdout and "A" in out.stdout


def test_disk_cache_is_used_only_while_exactly_current(db, tmp_path, monkeypatch):
    from jointdb.store import _nearest

    monkeypatch.setenv("JOINTDB_QUERY_CACHE", str(tmp_path / "cache"))
    req = planar_conditions(torque=24.0, materials=())

    def fresh_process_query(**kw):
        _nearest._cache.clear()  # what a new process starts with
        with Repository(db) as repo:
            return [(m.version.name, m.version.version, m.distance) for m in repo.nearest("tool-holder", req, k=9, **kw)]

    first = fresh_process_query()
    files = list((tmp_path / "cache").glob("*.npz"))
    assert len(files) == 1
    assert fresh_process_query() == first  # served from the file
    with Repository(db) as repo:  # another writer: the stamp's generation goes up
        repo.catalogue("D", "tool-holder", spring_joint(), planar_conditions(torque=24.0), "spring-damper-planar")
    after = fresh_process_query()
    assert after[0][:2] == ("D", 1) and after[0][2] == 0.0
    assert [p.name for p in (tmp_path / "cache").glob("*.npz")] != [f.name for f in files]  # replaced
    for p in (tmp_path / "cache").glob("*.npz"):
        p.write_bytes(b"garbage")  # a damaged cache file is ignored, never trusted
    assert fresh_process_query() == after
    monkeypatch.setenv("JOINTDB_QUERY_CACHE", "off")
    assert fresh_process_query() == after
    assert fresh_process_query(all_versions=True)[0][:2] == ("D", 1)
