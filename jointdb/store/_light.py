"""The nearest query on a SQLite file without SQLAlchemy or Alembic (``jointdb query``).

A one-shot command pays for every import: SQLAlchemy and Alembic cost more than
the query itself. For a SQLite target this module opens the file with the
standard ``sqlite3`` module after the same checks :class:`Repository` makes
(a jointdb SQLite file; schema at :data:`HEAD_REVISION`, read with one SELECT)
and ranks with :func:`jointdb.store._nearest.nearest_now`, the code
:meth:`Repository.nearest` runs too. PostgreSQL URLs go through the Repository.
"""

from __future__ import annotations

import os
import sqlite3
from pathlib import Path

from jointdb.errors import NotFoundError
from jointdb.store._nearest import Reader, nearest_now
from jointdb.store._sqlitefile import (
    BUSY_TIMEOUT_S,
    HEAD_REVISION,
    check_jointdb_sqlite,
    check_sqlite_file,
    default_sqlite_path,
    schema_mismatch,
)


def sqlite_target(db: str | os.PathLike | None) -> Path | None:
    """The SQLite file ``--db`` / ``$JOINTDB_URL`` / the default names, or None for anything
    else (a server URL, a URL with options, an odd spelling): those take the Repository path,
    which also gives the errors for bad ones."""
    text = str(db) if db is not None else os.environ.get("JOINTDB_URL") or ""
    if not text:
        return default_sqlite_path()
    if "\0" in text or text == ":memory:" or "?" in text:
        return None
    if "://" not in text:
        try:
            return Path(text).expanduser().resolve()
        except (OSError, RuntimeError):
            return None
    if text.startswith("sqlite:///") and text[len("sqlite:///"):] not in ("", ":memory:"):
        return Path(text[len("sqlite:///"):])
    return None


def open_reader(path: Path) -> Reader:
    """A read connection to a jointdb SQLite file at the current schema.

    Raises
    ------
    NotFoundError
        No file there (nothing is created).
    InputError, IntegrityError
        Not a jointdb SQLite file, damaged, or at another schema revision.
    """
    if not check_sqlite_file(path):
        raise NotFoundError(f"database {path} does not exist (`jointdb catalogue`, `jointdb joints import` "
                            "or `jointdb db upgrade` creates it)")
    check_jointdb_sqlite(path)
    conn = sqlite3.connect(str(path), timeout=BUSY_TIMEOUT_S, isolation_level=None)
    try:
        conn.execute(f"PRAGMA busy_timeout = {int(BUSY_TIMEOUT_S * 1000)}")
        conn.execute("PRAGMA query_only = ON")
        current = [r[0] for r in conn.execute("SELECT version_num FROM alembic_version")]
        if current != [HEAD_REVISION]:
            from jointdb.store._db import _script

            raise schema_mismatch(current[0] if current else "none",
                                  {r.revision for r in _script().walk_revisions()})
    except BaseException:
        conn.close()
        raise
    return Reader(conn, "sqlite")


def nearest_in_file(path: Path, joint_type: str, conditions, k: int = 3, **selection):
    """:func:`nearest_now` on a SQLite file (see :meth:`Repository.nearest` for the arguments).

    Raises
    ------
    InputError, NotFoundError, IntegrityError
        As :func:`open_reader` and :func:`nearest_now`; database errors become jointdb errors.
    """
    reader = open_reader(path)
    try:
        return nearest_now(reader, f"sqlite:///{path}", joint_type, conditions, k, stacklevel=4, **selection)
    except sqlite3.Error as exc:
        from jointdb.store._dberrors import translate_error

        raise translate_error(exc, f"sqlite:///{path}") from None
    finally:
        reader.conn.close()
