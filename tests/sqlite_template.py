"""A new SQLite catalogue made in a test process starts as a copy of one migrated by Alembic.

Running every migration for each new SQLite file costs 0.06 s of CPU and up to 0.3 s of wall time
(the migration's commit is synced to disk) per database, over hundreds of databases in a run. In
this test process, :func:`jointdb.store._db.upgrade` of an *empty* SQLite database to the head
revision instead copies the pages of a template (SQLite's online backup) that the real
:func:`jointdb.store._db.create_sqlite_database` built — with every Alembic migration — the first
time one was needed. Everything around it stays the product's path: the temporary file, the
engine and its PRAGMAs, the sync, the hard link that never replaces another process's database.

Not copied (the real migration runs): another revision, a database that already has tables (an
upgrade of an old catalogue), PostgreSQL, subprocesses (``python -m jointdb`` never sees this),
and every test marked ``real_migrations`` (``tests/store/test_store_migrations.py``: the tests
about creating and migrating a database). ``tests/test_sqlite_template.py`` checks that a copy
is the same database as a freshly migrated one, ``iterdump()`` line for line but for the one value a
migration draws at random (the query index's token, drawn anew for each copy).
"""

from __future__ import annotations

import sqlite3
import tempfile
import threading
import uuid
from pathlib import Path

#: True while the running test lets new SQLite databases start from the template
ENABLED = {"on": True}
_lock = threading.Lock()
_template: dict[str, Path] = {}
_real_upgrade = None


def template_path() -> Path:
    """The migrated template of this process (built once, by the real migrations)."""
    from jointdb.store import _db

    with _lock:
        if "path" not in _template:
            root = Path(tempfile.mkdtemp(prefix="jointdb-test-sqlite-template-"))
            path = root / "template.sqlite"
            saved, _db.upgrade = _db.upgrade, _real_upgrade
            try:
                _db.create_sqlite_database(path)
            finally:
                _db.upgrade = saved
            _template["path"] = path
        return _template["path"]


def _is_empty_sqlite(dbapi_conn) -> bool:
    return dbapi_conn.execute("SELECT count(*) FROM sqlite_master").fetchone()[0] == 0


def upgrade(write_engine, revision: str = "head") -> None:
    """:func:`jointdb.store._db.upgrade`, with an empty SQLite database at head copied from the template."""
    from jointdb.store._sqlitefile import HEAD_REVISION

    if not ENABLED["on"] or write_engine.dialect.name != "sqlite" or revision not in ("head", HEAD_REVISION):
        return _real_upgrade(write_engine, revision)
    source = template_path()
    with write_engine.connect() as conn:
        target = conn.connection.driver_connection
        if not _is_empty_sqlite(target):
            conn.rollback()
            return _real_upgrade(write_engine, revision)
        src = sqlite3.connect(source)
        try:
            src.backup(target)
        finally:
            src.close()
        # the one value a migration draws at random: the token naming this database to the query cache
        target.execute("UPDATE query_stamp SET token = ? WHERE id = 1", (str(uuid.uuid4()),))


def install() -> None:
    """Route :func:`jointdb.store._db.upgrade` through :func:`upgrade` in this process."""
    global _real_upgrade
    from jointdb.store import _db

    if _real_upgrade is None:
        _real_upgrade = _db.upgrade
        _db.upgrade = upgrade
