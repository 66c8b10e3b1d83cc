"""Opening a database: what is refused (one line, exit code, nothing created) and what is created."""

from __future__ import annotations

import multiprocessing as mp
import sqlite3
import subprocess
import sys

import pytest
from store_helpers import assert_one_line_error, count_rows, planar_conditions, run_main, spring_joint, tree_state

from jointdb.errors import InputError, IntegrityError, NotFoundError
from jointdb.store import Repository, current_revision, head_revision, write_frf_file

READS = (["joints", "list"], ["joints", "show", "T1"], ["query", "--type", "tool-holder", "--torque", "3"],
         ["db", "check"], ["db", "info"], ["db", "audit"], ["db", "gc", "--dry-run"])


@pytest.fixture
def joint_file(tmp_path):
    path = tmp_path / "in" / "j.h5"
    path.parent.mkdir()
    write_frf_file(path, spring_joint())
    return path


def _writes(joint_file, db):
    return (["catalogue", joint_file, "--name", "T1", "--type", "tool-holder", "--model-kind",
             "spring-damper-planar", "--db", db], ["db", "upgrade", "--db", db],
            ["db", "downgrade", "--yes", "--db", db])


def _foreign_sqlite(path):
    conn = sqlite3.connect(path)
    conn.execute("CREATE TABLE customers (id INTEGER PRIMARY KEY, name TEXT)")
    conn.execute("INSERT INTO customers VALUES (1, 'ACME')")
    conn.commit()
    conn.close()


def _empty_sqlite(path):
    conn = sqlite3.connect(path)
    conn.execute("PRAGMA user_version = 1")  # writes the header: a valid database with no tables
    conn.commit()
    conn.close()


@pytest.mark.parametrize("kind, make, code, says", [
    ("empty", lambda p: p.write_bytes(b""), InputError.exit_code, "empty file (0 bytes)"),
    ("text", lambda p: p.write_text("hello\n"), InputError.exit_code, "not a SQLite database"),
    ("foreign", _foreign_sqlite, InputError.exit_code, "not a jointdb database (tables: customers)"),
    ("empty-sqlite", _empty_sqlite, InputError.exit_code, "not a jointdb database (no tables)"),
    ("bad-header", lambda p: p.write_bytes(b"SQLite format 3\x00" + b"\xff" * 4080), IntegrityError.exit_code,
     "is damaged"),
    ("directory", lambda p: p.mkdir(), InputError.exit_code, "is a directory"),
])
def test_a_file_that_is_not_a_jointdb_database_is_refused_and_left_alone(tmp_path, capsys, joint_file, kind,
                                                                           make, code, says):
    db = tmp_path / "target.sqlite"
    make(db)
    before = tree_state(tmp_path)
    for args in [[*a, "--db", db] for a in READS] + list(_writes(joint_file, db)):
        assert_one_line_error(run_main(capsys, *args), code, says)
    assert tree_state(tmp_path) == before  # never re-created, nothing written beside it


def test_missing_database_is_created_only_by_writing_commands(tmp_path, capsys, joint_file):
    db = tmp_path / "new.sqlite"
    for args in [[*a, "--db", db] for a in READS] + [["db", "downgrade", "--yes", "--db", db]]:
        assert_one_line_error(run_main(capsys, *args), NotFoundError.exit_code, "does not exist")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in"]
    code, _, err = run_main(capsys, *_writes(joint_file, db)[0])
    assert code == 0, err
    assert current_revision(db) == head_revision()
    assert sorted(p.name for p in tmp_path.iterdir() if not p.name.endswith(("-wal", "-shm"))) == [
        "in", "new.sqlite", "new.sqlite.blobs"]


def test_unreachable_postgres_is_one_line(tmp_path, capsys, monkeypatch):
    url = "postgresql+psycopg://nobody:secret@127.0.0.1:1/jointdb"
    monkeypatch.setenv("JOINTDB_BLOBS", str(tmp_path / "b"))
    for args in (["joints", "list"], ["db", "upgrade"], ["db", "downgrade", "--yes"], ["db", "check"]):
        line = assert_one_line_error(run_main(capsys, *args, "--db", url),
                                     InputError.exit_code, "cannot open database postgresql+psycopg://nobody:***@")
        assert "127.0.0.1" in line and "secret" not in line
    assert not (tmp_path / "b").exists()


def test_postgres_url_without_psycopg_says_which_extra_to_install(tmp_path):
    code = ("import sys; sys.modules['psycopg'] = None; sys.modules['psycopg2'] = None\n"
            "from jointdb.cli import main\n"
            "sys.argv = ['jointdb', 'joints', 'list', '--db', sys.argv[1], '--blobs', sys.argv[2]]\nmain()")
    for url in ("postgresql+psycopg://u@127.0.0.1:1/j", "postgresql://u@127.0.0.1:1/j"):
        out = subprocess.run([sys.executable, "-c", code, url, str(tmp_path / "b")], capture_output=True, text=True)
        assert_one_line_error((out.returncode, out.stdout, out.stderr), InputError.exit_code,
                              'pip install "jointdb[postgres]"')


def test_destructive_downgrades_need_yes_whatever_the_spelling(tmp_path, capsys):
    db = tmp_path / "d.sqlite"
    repo = Repository(db)
    repo.catalogue("T1", "tool-holder", spring_joint(), planar_conditions(), "spring-damper-planar")
    repo.close()
    head = head_revision()
    for to in ("-1", "-2", "-3", "0001", "0002", "base"):
        assert_one_line_error(run_main(capsys, "db", "downgrade", "--to", to, "--db", db),
                              InputError.exit_code, "add --yes")
        assert current_revision(db) == head
    code, _, err = run_main(capsys, "db", "downgrade", "--to", "0001", "--yes", "--db", db)
    assert code == 0 and current_revision(db) == "0001", err
    assert_one_line_error(run_main(capsys, "db", "downgrade", "--to", "-1", "--db", db), InputError.exit_code,
                          "0001: every table and all data")
    assert current_revision(db) == "0001"
    assert_one_line_error(run_main(capsys, "db", "downgrade", "--to", "-5", "--yes", "--db", db),
                          InputError.exit_code, "cannot go 5 steps down")
    assert_one_line_error(run_main(capsys, "db", "downgrade", "--to", "0003", "--yes", "--db", db),
                          InputError.exit_code, "not below the current revision")
    assert_one_line_error(run_main(capsys, "db", "downgrade", "--to", "bogus", "--yes", "--db", db),
                          InputError.exit_code, "unknown revision 'bogus'")
    assert current_revision(db) == "0001"
    code, _, err = run_main(capsys, "db", "upgrade", "--db", db)
    assert code == 0, err
    assert Repository(db).get("T1").version == 1  # the data survived every refused downgrade


def test_gc_without_dry_run_needs_yes(tmp_path, capsys):
    db = tmp_path / "g.sqlite"
    repo = Repository(db)
    repo.blobs.put(spring_joint(k=(9e6, 8e4)))  # an orphan
    before = tree_state(tmp_path)
    assert_one_line_error(run_main(capsys, "db", "gc", "--min-age", "0", "--db", db), InputError.exit_code,
                          "--yes")
    assert tree_state(tmp_path) == before
    code, out, err = run_main(capsys, "db", "gc", "--min-age", "0", "--yes", "--json", "--db", db)
    assert code == 0 and len(repo.blobs.temporaries()) == 0 and list(repo.blobs.walk()) == [], err
    repo.close()


def test_catalogue_with_a_bad_label_writes_nothing(tmp_path, capsys, joint_file):
    new = tmp_path / "new.sqlite"
    args = ["catalogue", joint_file, "--name", "T1", "--type", "tool-holder", "--model-kind", "spring-damper-planar"]
    assert_one_line_error(run_main(capsys, *args, "--label", "a b/c", "--db", new), InputError.exit_code, "label")
    assert not new.exists() and not (tmp_path / "new.sqlite.blobs").exists()
    db = tmp_path / "old.sqlite"
    repo = Repository(db)
    rows, files = count_rows(repo), tree_state(repo.blobs.root)
    assert_one_line_error(run_main(capsys, *args, "--label", "a b/c", "--db", db), InputError.exit_code, "label")
    assert count_rows(repo) == rows and tree_state(repo.blobs.root) == files
    with pytest.raises(InputError, match="label"):  # the library checks before writing a blob, too
        repo.catalogue("T1", "tool-holder", spring_joint(), planar_conditions(), "spring-damper-planar",
                       label="'; DROP TABLE labels; --")
    assert count_rows(repo) == rows and tree_state(repo.blobs.root) == files
    jv = repo.catalogue("T1", "tool-holder", spring_joint(), planar_conditions(), "spring-damper-planar",
                        label="released")
    assert jv.labels == ("released",) and repo.get("T1", label="released").version == 1
    assert [a["action"] for a in repo.audit("T1")] == ["label", "catalogue"]
    repo.close()


def _open_new(path, queue):
    try:
        repo = Repository(path)
        repo.catalogue(f"J{mp.current_process().pid}", "tool-holder", spring_joint(), planar_conditions(),
                       "spring-damper-planar")
        repo.close()
        queue.put(None)
    except BaseException as exc:  # report to the parent
        queue.put(repr(exc))


def test_processes_creating_one_new_database_at_once_all_succeed(tmp_path):
    ctx = mp.get_context("fork")
    queue = ctx.Queue()
    path = tmp_path / "race.sqlite"
    procs = [ctx.Process(target=_open_new, args=(path, queue)) for _ in range(6)]
    for p in procs:
        p.start()
    results = [queue.get(timeout=120) for _ in procs]
    for p in procs:
        p.join(timeout=60)
    assert results == [None] * 6
    repo = Repository(path)
    assert len(repo.list_joints()) == 6 and repo.check().ok
    assert [p.name for p in tmp_path.iterdir() if ".tmp-" in p.name] == []
    repo.close()
