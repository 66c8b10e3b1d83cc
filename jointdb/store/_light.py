"""The nearest query without SQLAlchemy or Alembic (``jointdb query``).

A one-shot command pays for every import: SQLAlchemy and Alembic cost more than
the query itself. For a SQLite target this module opens the file with the
standard ``sqlite3`` module after the same checks :class:`Repository` makes
(a jointdb SQLite file; schema at :data:`HEAD_REVISION`, read with one SELECT);
for a ``postgresql://`` or ``postgresql+psycopg://`` URL it connects with psycopg
directly, with the connection options the Repository's engine uses (JIT off, a
connect timeout) and the same schema check. Both rank with
:func:`jointdb.store._nearest.nearest_now`, the code :meth:`Repository.nearest`
runs too. SQLAlchemy is imported only to word an error.
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


#: URL prefixes the PostgreSQL fast path takes (other drivers go through the Repository)
PG_PREFIXES = ("postgresql://", "postgresql+psycopg://")
#: as :data:`jointdb.store._db.PG_CONNECT_TIMEOUT_S` (a test keeps them equal)
PG_CONNECT_TIMEOUT_S = 10


def _check_head(current: list[str]) -> None:
    """Refuse a schema revision other than :data:`HEAD_REVISION` (Alembic is imported only then)."""
    if current != [HEAD_REVISION]:
        from jointdb.store._db import _script

        raise schema_mismatch(current[0] if current else "none", {r.revision for r in _script().walk_revisions()})


def postgres_target(db: str | os.PathLike | None) -> str | None:
    """The PostgreSQL URL ``--db`` / ``$JOINTDB_URL`` names (psycopg driver), else None."""
    text = str(db) if db is not None else os.environ.get("JOINTDB_URL") or ""
    return text if text.startswith(PG_PREFIXES) and "\0" not in text else None


def _libpq(url: str) -> tuple[str, dict]:
    """``("", connect keyword arguments)`` of a SQLAlchemy-style PostgreSQL URL, with the engine's
    options (:func:`jointdb.store._db.make_engines`): ``-c jit=off`` added to ``options``, a connect
    timeout unless given. The URL is taken apart here (user, password, host, port and database
    percent-decoded as SQLAlchemy does) and handed to libpq as keywords, never as a URI: libpq's URI
    parser repeats a token it cannot read in its error, which could show the password.

    Raises
    ------
    InputError
        The port is not a number (the message does not repeat the URL).
    """
    from urllib.parse import parse_qsl, unquote, urlsplit

    from jointdb.errors import InputError

    parts = urlsplit(url)
    query = parse_qsl(parts.query, keep_blank_values=True)
    options = " ".join(v for k, v in query if k == "options")
    kwargs: dict = {k: v for k, v in query if k != "options"}
    kwargs.setdefault("connect_timeout", str(PG_CONNECT_TIMEOUT_S))
    try:
        port = parts.port
    except ValueError:
        raise InputError("the database URL's port is not a number") from None
    given = {"user": parts.username, "password": parts.password, "host": parts.hostname,
             "port": None if port is None else str(port), "dbname": parts.path.lstrip("/") or None}
    kwargs.update({k: unquote(v) for k, v in given.items() if v})
    kwargs["options"] = f"{options} -c jit=off".strip()
    return "", kwargs


def open_postgres_reader(url: str) -> Reader:
    """A read connection (psycopg) to a jointdb PostgreSQL database at the current schema.

    Raises
    ------
    InputError
        No server, no jointdb schema, or another schema revision (as the Repository says it).
    """
    import psycopg
    from psycopg.types.json import set_json_loads

    from jointdb.errors import InputError
    from jointdb.store._records import load_stored_json

    conninfo, kwargs = _libpq(url)
    conn = psycopg.connect(conninfo, **kwargs)
    try:
        set_json_loads(load_stored_json, conn)  # a damaged JSON value reads as DamagedJSON, as in the Repository
        try:
            current = [r[0] for r in conn.execute("SELECT version_num FROM alembic_version")]
        except psycopg.errors.UndefinedTable:
            raise InputError("this database has no jointdb schema yet; run `jointdb db upgrade --db URL` first") \
                from None
        finally:
            conn.rollback()
        _check_head(current)
    except BaseException:
        conn.close()
        raise
    return Reader(conn, "postgresql")


def nearest_on_postgres(url: str, joint_type: str, conditions, k: int = 3, **selection):
    """:func:`nearest_now` on a PostgreSQL database through psycopg (see :meth:`Repository.nearest`
    for the arguments); the query cache is shared with a Repository of the same URL.

    Raises
    ------
    InputError, NotFoundError, IntegrityError
        As :func:`open_postgres_reader` and :func:`nearest_now`; database errors become jointdb errors.
    """
    try:
        import psycopg
    except ImportError as exc:
        from jointdb.store._dberrors import translate_error

        raise translate_error(exc, url) from None
    try:
        reader = open_postgres_reader(url)
    except psycopg.Error as exc:
        from jointdb.store._dberrors import translate_error

        raise translate_error(exc, url) from None
    try:
        return nearest_now(reader, url, joint_type, conditions, k, stacklevel=4, **selection)
    except psycopg.Error as exc:
        from jointdb.store._dberrors import translate_error

        raise translate_error(exc, url) from None
    finally:
        reader.conn.close()


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
        _check_head(current)
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
