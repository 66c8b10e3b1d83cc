"""The test copy of a migrated SQLite catalogue (tests/sqlite_template.py) is the database the migrations make."""

from __future__ import annotations

import sqlite3

import pytest
import sqlite_template

from jointdb.store import Repository, current_revision, head_revision
from jointdb.store import _db


def _token(path) -> str:
    conn = sqlite3.connect(path)
    try:
        return conn.execute("SELECT token FROM query_stamp WHERE id = 1").fetchone()[0]
    finally:
        conn.close()


def _dump(path) -> list[str]:
    """Every statement that rebuilds the database and its header fields, sorted (two runs of the migrations
    may create indexes in another order), the query index's random token (a uuid4 per database) replaced by
    a placeholder."""
    token = _token(path)
    conn = sqlite3.connect(path)
    try:
        return sorted(line.replace(token, "<token>") for line in conn.iterdump()) + [
            f"user_version={conn.execute('PRAGMA user_version').fetchone()[0]}",
            f"application_id={conn.execute('PRAGMA application_id').fetchone()[0]}",
            f"journal_mode={conn.execute('PRAGMA journal_mode').fetchone()[0]}",
        ]
    finally:
        conn.close()


def _migrated_by_alembic(path) -> None:
    """``path`` created by the product's code with every Alembic migration (no template)."""
    sqlite_template.ENABLED["on"] = False
    try:
        _db.create_sqlite_database(path)
    finally:
        sqlite_template.ENABLED["on"] = True


def test_a_copied_database_is_the_migrated_one_line_for_line(tmp_path):
    _migrated_by_alembic(tmp_path / "alembic.sqlite")
    repo = Repository(tmp_path / "copied.sqlite")
    repo.close()
    copied = _dump(tmp_path / "copied.sqlite")
    assert len(copied) > 50  # tables, indexes, triggers, the alembic_version row
    assert copied == _dump(tmp_path / "alembic.sqlite")
    assert sum("<token>" in line for line in copied) == 1
    tokens = {_token(tmp_path / "copied.sqlite"), _token(tmp_path / "alembic.sqlite"), _token(sqlite_template.template_path())}
    assert len(tokens) == 3  # each database its own: the query cache tells them apart
    assert current_revision(f"sqlite:///{tmp_path / 'copied.sqlite'}") == head_revision()


def test_a_new_database_is_copied_not_migrated(tmp_path, monkeypatch):
    sqlite_template.template_path()  # built before the real migrations are taken away

    def no_alembic(*args, **kwargs):
        raise AssertionError("Alembic ran for a new database at head")

    monkeypatch.setattr(sqlite_template, "_real_upgrade", no_alembic)
    repo = Repository(tmp_path / "new.sqlite")
    try:
        with repo.read_engine.connect() as conn:
            assert conn.exec_driver_sql("PRAGMA journal_mode").scalar() == "wal"
            assert conn.exec_driver_sql("PRAGMA integrity_check").scalar() == "ok"
    finally:
        repo.close()


def test_other_revisions_and_existing_databases_run_the_migrations(tmp_path, monkeypatch):
    ran = []
    real = sqlite_template._real_upgrade
    monkeypatch.setattr(sqlite_template, "_real_upgrade", lambda engine, rev="head": (ran.append(rev), real(engine, rev)))
    from jointdb.store import downgrade, upgrade

    url = f"sqlite:///{tmp_path / 'old.sqlite'}"
    assert upgrade(url, "0001") == "0001"
    assert ran == ["0001"]
    assert upgrade(url) == head_revision()  # an old catalogue: migrated, not replaced by the copy
    assert ran == ["0001", "head"]
    assert downgrade(url, "0001") == "0001"


@pytest.mark.real_migrations
def test_a_real_migrations_test_runs_alembic(tmp_path, monkeypatch):
    assert sqlite_template.ENABLED["on"] is False
    Repository(tmp_path / "m.sqlite").close()
    assert _dump(tmp_path / "m.sqlite") == _dump(sqlite_template.template_path())
