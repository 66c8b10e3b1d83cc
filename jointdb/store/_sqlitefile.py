"""Checks of a SQLite file before jointdb opens it (no SQLAlchemy: the query command uses them).

See :mod:`jointdb.store._db` for what is refused and why.
"""

from __future__ import annotations

import os
from pathlib import Path

from jointdb.errors import InputError

#: The newest schema revision this jointdb knows: the schema check compares ``alembic_version``
#: with it (one SELECT, no Alembic import); a test keeps it equal to the newest migration script.
HEAD_REVISION = "0011"
BUSY_TIMEOUT_S = 30.0
SQLITE_MAGIC = b"SQLite format 3\x00"
#: Tables of the jointdb schema (besides ``alembic_version``).
#: Tables of jointdb kept outside the Alembic history: the job queue of the in-process worker
#: (:mod:`jointdb.jobs._table`, created on first use by ``jointdb serve``).
OUTSIDE_ALEMBIC = frozenset({"jointdb_jobs"})
SCHEMA_TABLES = frozenset({"joints", "joint_versions", "joint_states", "labels", "audit_log",
                           "query_versions", "query_geometry", "query_stamp", "query_counts", "query_changes", "api_tokens", "frf_blobs",
                           "history_chain", "web_sessions", "idempotency_keys",
                           "parts", "part_versions", "part_labels"})


def check_sqlite_file(path: Path) -> bool:
    """Whether a SQLite database file exists at ``path`` (False: nothing there).

    Raises
    ------
    InputError
        ``path`` is a directory or not a regular file, is empty (0 bytes) or is
        not a SQLite file.
    """
    try:
        if path.is_dir():
            raise InputError(f"database {path} is a directory; give a database file such as {path / 'jointdb.sqlite'}")
        if not path.exists():
            return False
        if not path.is_file():
            raise InputError(f"database {path} is not a regular file")
        size = path.stat().st_size
        if size == 0:
            wal = Path(str(path) + "-wal")
            if wal.is_file() and wal.stat().st_size > 0:
                return True  # a database whose pages are still in its write-ahead log
            raise InputError(f"database {path} is an empty file (0 bytes), not a jointdb database; refusing to "
                             "use it (restore it from a backup, or remove it to start a new database)")
        with open(path, "rb") as fh:
            head = fh.read(len(SQLITE_MAGIC))
    except OSError as exc:
        raise InputError(f"cannot read database {path}: {exc.strerror or exc}") from None
    if head != SQLITE_MAGIC:
        raise InputError(f"{path} is not a SQLite database (it does not start with the SQLite header); "
                         "give a jointdb database file")
    return True


def sqlite_tables(path: Path) -> set[str]:
    """Table names of an existing SQLite file, read through a read-only connection
    (no pragma is run, so a foreign file is not changed by looking at it).

    Raises
    ------
    IntegrityError
        The file has the SQLite header but cannot be read (damaged).
    """
    import sqlite3

    try:
        conn = sqlite3.connect(f"{path.as_uri()}?mode=ro", uri=True, timeout=BUSY_TIMEOUT_S)
    except sqlite3.Error as exc:
        raise InputError(f"cannot open database {path}: {exc}") from None
    try:
        return {r[0] for r in conn.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
    except sqlite3.DatabaseError as exc:
        from jointdb.store._dberrors import translate_error

        raise translate_error(exc, f"sqlite:///{path}") from None
    finally:
        conn.close()


def check_jointdb_sqlite(path: Path) -> None:
    """Refuse a SQLite database that is not a jointdb database (no ``alembic_version``, other tables)."""
    tables = sqlite_tables(path)
    if "alembic_version" not in tables:
        what = f"tables: {', '.join(sorted(tables)[:5])}" if tables else "no tables"
        raise InputError(f"{path} is a SQLite database but not a jointdb database ({what}); refusing to touch it")
    # sqlite_stat1..4: SQLite's own planner statistics, written by ANALYZE (or PRAGMA optimize)
    foreign = {t for t in tables - SCHEMA_TABLES - {"alembic_version"} - OUTSIDE_ALEMBIC
               if not t.startswith("sqlite_stat")}
    if foreign:
        raise InputError(f"{path} has tables jointdb does not know ({', '.join(sorted(foreign)[:5])}); "
                         "refusing to touch it")


def default_sqlite_path() -> Path:
    base = os.environ.get("XDG_DATA_HOME") or str(Path.home() / ".local" / "share")
    return Path(base) / "jointdb" / "jointdb.sqlite"


def schema_mismatch(current: str, known: set[str] | None = None) -> InputError:
    """The error for a database at another schema revision than :data:`HEAD_REVISION`."""
    if known is not None and current not in known:
        return InputError(f"database schema is at revision {current}, which this jointdb ({HEAD_REVISION}) does "
                          "not know; use a newer jointdb")
    return InputError(f"database schema is at revision {current}, this jointdb needs {HEAD_REVISION}; "
                      "run `jointdb db upgrade`")
