"""Database location, opening checks, engines, error translation and Alembic migrations.

Location, first match wins: the ``url`` argument (CLI ``--db``), the
``JOINTDB_URL`` environment variable, then the per-user default SQLite file
``$XDG_DATA_HOME/jointdb/jointdb.sqlite`` (``~/.local/share/jointdb/...``).
A plain path is taken as a SQLite file.

Blobs live in ``<sqlite file>.blobs/`` beside a SQLite database, or in the
directory given by ``blobs=`` / ``JOINTDB_BLOBS`` (required for PostgreSQL).

Opening a SQLite path (:func:`open_sqlite_target`): a directory, an empty
(0-byte) file, a file that is not SQLite, or a SQLite database that is not a
jointdb database is refused with one line; it is never re-created. A file that
does not exist is created only when the caller asks (``create=True``), and then
atomically: the schema is built in a temporary file beside it which is then
hard-linked into place, so another process sees either no file or a complete
database.

SQLite connections run with WAL, ``foreign_keys=ON``, ``synchronous=FULL`` and a
30 s busy timeout; write transactions start with ``BEGIN IMMEDIATE`` (the
``write`` engine), reads with a plain deferred ``BEGIN``.

Database errors that a user can cause or meet (no server, no driver, a damaged
file) are turned into jointdb errors by :func:`translate_error`.

Migrations are the Alembic scripts in the repository's top-level ``migrations/``
(shipped in the wheel as ``jointdb/migrations`` through a package-dir mapping in
setup.py); the Alembic configuration is built in code from that path, so no
``alembic.ini`` is needed at run time.
"""

from __future__ import annotations

import contextlib
import os
import re
import uuid
from pathlib import Path

from sqlalchemy import Engine, create_engine, event, inspect
from sqlalchemy.engine import make_url
from sqlalchemy.exc import ArgumentError

from jointdb.errors import InputError, NotFoundError
from jointdb.store._dberrors import db_errors, safe_url, translate_error, with_db_errors
from jointdb.store._sqlitefile import (  # noqa: F401 - part of this module's interface
    BUSY_TIMEOUT_S,
    SCHEMA_TABLES,
    SQLITE_MAGIC,
    HEAD_REVISION,
    check_jointdb_sqlite,
    check_sqlite_file,
    default_sqlite_path,
    schema_mismatch,
    sqlite_tables,
)

__all_errors__ = (db_errors, safe_url, translate_error, with_db_errors)  # re-exported: callers use _db.db_errors etc.

__all__ = [
    "resolve_url",
    "default_sqlite_path",
    "blob_dir",
    "make_engines",
    "alembic_config",
    "current_revision",
    "head_revision",
    "upgrade",
    "downgrade",
    "downgrade_plan",
    "open_sqlite_target",
    "translate_error",
    "BUSY_TIMEOUT_S",
]

PG_CONNECT_TIMEOUT_S = 10


def resolve_url(url: str | os.PathLike | None = None) -> str:
    """The database URL to use (see module docstring)."""
    text = str(url) if url is not None else os.environ.get("JOINTDB_URL") or ""
    if not text:
        text = str(default_sqlite_path())
    if "\0" in text:
        raise InputError("database path or URL contains a NUL character")
    if "://" not in text:
        if text == ":memory:":
            raise InputError("in-memory databases are not supported; give a file path or URL")
        try:
            text = "sqlite:///" + str(Path(text).expanduser().resolve())
        except (OSError, RuntimeError) as exc:
            raise InputError(f"cannot use database path {text!r}: {exc}") from None
    try:
        parsed = make_url(text)
    except (ArgumentError, ValueError):
        raise InputError(f"cannot read database URL {safe_url(text)!r}; expected e.g. "
                         "postgresql+psycopg://user@host/jointdb or a SQLite file path") from None
    if parsed.get_backend_name() not in ("sqlite", "postgresql"):
        raise InputError(f"unsupported database {parsed.get_backend_name()!r}: use sqlite or postgresql")
    if parsed.get_backend_name() == "sqlite" and parsed.database in (None, "", ":memory:"):
        raise InputError("in-memory SQLite databases are not supported; give a file path")
    return text


def is_sqlite(url: str) -> bool:
    return make_url(url).get_backend_name() == "sqlite"


def sqlite_path(url: str) -> Path:
    return Path(str(make_url(url).database))


def blob_dir(url: str, blobs: str | os.PathLike | None = None) -> Path:
    """Directory of the blob store for a database URL."""
    if blobs is not None:
        return Path(blobs).expanduser().resolve()
    env = os.environ.get("JOINTDB_BLOBS")
    if env:
        return Path(env).expanduser().resolve()
    u = make_url(url)
    if u.get_backend_name() == "sqlite":
        return Path(str(u.database) + ".blobs")
    raise InputError(
        "a PostgreSQL database needs a shared blob directory: set JOINTDB_BLOBS=/path/to/blobs "
        "(or pass blobs= to Repository)"
    )


# --------------------------------------------------------------------------- SQLite files
# check_sqlite_file, sqlite_tables, check_jointdb_sqlite: in _sqlitefile (no SQLAlchemy; `jointdb query` uses them)


def create_sqlite_database(path: Path, revision: str = "head") -> None:
    """Create a new SQLite jointdb database at ``path`` atomically (module docstring).

    If another process created ``path`` meanwhile, its database is kept and
    this one discarded.
    """
    from jointdb.io._atomic import fsync_dir

    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"cannot create directory {path.parent} for database {path.name}: "
                         f"{exc.strerror or exc}") from None
    tmp = path.parent / f".{path.name}.tmp-{uuid.uuid4().hex}"
    try:
        engine, write = _sqlite_engine("sqlite:///" + str(tmp))
        try:
            upgrade(write, revision)
        finally:
            engine.dispose()  # the last connection checkpoints the WAL into the file
        fd = os.open(tmp, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
        try:
            os.link(tmp, path)  # never replaces a database another process created first
        except FileExistsError:
            pass
        except OSError:  # no hard links on this file system
            if not path.exists():
                os.replace(tmp, path)
        fsync_dir(path.parent)
    except OSError as exc:
        raise InputError(f"cannot create database {path}: {exc.strerror or exc}") from None
    finally:
        for suffix in ("", "-wal", "-shm", "-journal"):
            with contextlib.suppress(OSError):
                Path(str(tmp) + suffix).unlink()


def open_sqlite_target(url: str, create: bool, revision: str = "head") -> bool:
    """Check (and with ``create``, create) the SQLite file of ``url``; True when it was created.

    An existing file must be a jointdb database (:func:`check_sqlite_file`,
    :func:`check_jointdb_sqlite`), checked without changing it.

    Raises
    ------
    NotFoundError
        The file does not exist and ``create`` is False (nothing is created).
    InputError, IntegrityError
        Not a usable jointdb SQLite database, or a damaged one.
    """
    path = sqlite_path(url)
    if check_sqlite_file(path):
        check_jointdb_sqlite(path)
        return False
    if not create:
        raise NotFoundError(f"database {path} does not exist (`jointdb catalogue`, `jointdb joints import` "
                            "or `jointdb db upgrade` creates it)")
    create_sqlite_database(path, revision)
    return True


def check_existing(url: str) -> None:
    """Refuse a target that is not an existing jointdb database, creating nothing (SQLite only;
    a PostgreSQL URL is checked when it is connected to).

    Raises
    ------
    NotFoundError, InputError, IntegrityError
    """
    if is_sqlite(url):
        open_sqlite_target(url, create=False)


# --------------------------------------------------------------------------- engines
def _sqlite_engine(url: str) -> tuple[Engine, Engine]:
    engine = create_engine(url, connect_args={"timeout": BUSY_TIMEOUT_S})

    @event.listens_for(engine, "connect")
    def _on_connect(dbapi_conn, record):  # pragma: no cover - trivial
        dbapi_conn.isolation_level = None  # we issue BEGIN ourselves
        cur = dbapi_conn.cursor()
        cur.execute(f"PRAGMA busy_timeout = {int(BUSY_TIMEOUT_S * 1000)}")
        cur.execute("PRAGMA foreign_keys = ON")
        cur.execute("PRAGMA journal_mode = WAL")
        cur.execute("PRAGMA synchronous = FULL")
        cur.close()

    @event.listens_for(engine, "begin")
    def _on_begin(conn):  # pragma: no cover - trivial
        mode = conn.get_execution_options().get("sqlite_begin", "DEFERRED")
        conn.exec_driver_sql(f"BEGIN {mode}")

    return engine, engine.execution_options(sqlite_begin="IMMEDIATE")


def _without_jit(options: "str | tuple[str, ...] | None") -> str:
    """The libpq ``options`` of a PostgreSQL URL plus ``-c jit=off``.

    The store's statements are short (a page of 50, one version, a count over the query
    index); PostgreSQL's JIT compiler, which starts above a planner cost these reach on a large
    catalogue, spends 0.5–0.9 s compiling a statement that runs in milliseconds
    (bench/bench_listing.py, docs/validation/performance.md).
    """
    given = " ".join(options) if isinstance(options, tuple) else (options or "")
    return f"{given} -c jit=off".strip()


def make_engines(url: str, pool_size: int | None = None) -> tuple[Engine, Engine]:
    """``(read_engine, write_engine)`` for a URL; identical for PostgreSQL.

    No connection is opened here (and no file created); for SQLite call
    :func:`open_sqlite_target` first. ``pool_size`` (PostgreSQL): connections kept
    open, plus up to half as many again under a burst (default: SQLAlchemy's 5 + 10);
    a server sizes it to the requests it lets in at once (``jointdb serve --concurrency``).

    Raises
    ------
    InputError
        The driver is not installed (e.g. psycopg: ``pip install "jointdb[postgres]"``).
    """
    with db_errors(url):
        if is_sqlite(url):
            return _sqlite_engine(url)
        query = make_url(url).query
        connect_args: dict = {"options": _without_jit(query.get("options"))}
        if "connect_timeout" not in query:
            connect_args["connect_timeout"] = PG_CONNECT_TIMEOUT_S
        kwargs: dict = {"connect_args": connect_args}
        if pool_size is not None:
            if not 1 <= int(pool_size) <= 1000:
                raise InputError(f"pool_size must be 1..1000, got {pool_size}")
            kwargs |= {"pool_size": int(pool_size), "max_overflow": max(2, int(pool_size) // 2)}
        engine = create_engine(url, **kwargs)
        _ping_when_idle(engine)
    return engine, engine


#: A pooled PostgreSQL connection unused for longer than this is pinged before it is handed out [s].
PING_AFTER_S = 2.0


def _ping_when_idle(engine: Engine) -> None:
    """Ping a pooled connection only when it sat idle for :data:`PING_AFTER_S` (a dead one is
    replaced before use, as with ``pool_pre_ping``), not on every checkout: under load a
    connection is handed out again within milliseconds, and a ping is one more round trip per
    statement. (A connection the database dropped within the last ``PING_AFTER_S`` of use still
    fails once; SQLAlchemy then discards the pool's connections.)"""
    import time

    from sqlalchemy.exc import DisconnectionError

    @event.listens_for(engine, "connect")
    def _fresh(dbapi_connection, record) -> None:
        record.info["jointdb_used"] = time.monotonic()

    @event.listens_for(engine, "checkin")
    def _used(dbapi_connection, record) -> None:
        record.info["jointdb_used"] = time.monotonic()

    @event.listens_for(engine, "checkout")
    def _ping(dbapi_connection, record, proxy) -> None:
        if time.monotonic() - record.info.get("jointdb_used", 0.0) < PING_AFTER_S:
            return
        try:
            with dbapi_connection.cursor() as cur:
                cur.execute("SELECT 1")
            dbapi_connection.rollback()
        except Exception as exc:  # noqa: BLE001 - any failure: this connection is gone, the pool makes a new one
            raise DisconnectionError(f"pooled connection is dead ({type(exc).__name__})") from exc


# --------------------------------------------------------------------------- alembic
def migrations_dir() -> Path:
    """The Alembic environment: ``jointdb/migrations`` in an installed package (the wheel maps
    the repository's top-level ``migrations/`` there, see setup.py), else the top-level
    ``migrations/`` of the source tree."""
    package = Path(__file__).resolve().parent.parent
    if (package / "migrations" / "env.py").is_file():
        return package / "migrations"
    return package.parent / "migrations"


def alembic_config(url: str | None = None):
    """An Alembic ``Config`` built in code (no alembic.ini needed)."""
    from alembic.config import Config

    cfg = Config()
    cfg.set_main_option("script_location", str(migrations_dir()))
    if url:
        cfg.set_main_option("sqlalchemy.url", url.replace("%", "%%"))
    return cfg


def _script():
    from alembic.script import ScriptDirectory

    return ScriptDirectory.from_config(alembic_config())


def head_revision() -> str:
    return _script().get_current_head()


def current_revision(engine: Engine) -> str | None:
    from alembic.runtime.migration import MigrationContext

    with engine.connect() as conn:
        return MigrationContext.configure(conn).get_current_revision()


def _run(write_engine: Engine, fn, revision: str) -> None:
    cfg = alembic_config()
    with write_engine.begin() as conn:
        cfg.attributes["connection"] = conn
        fn(cfg, revision)


def upgrade(write_engine: Engine, revision: str = "head") -> None:
    """Apply migrations up to ``revision`` in one write transaction."""
    from alembic import command

    _run(write_engine, command.upgrade, revision)


def downgrade(write_engine: Engine, revision: str = "-1") -> None:
    """Revert migrations down to ``revision`` (``-1``: one step; ``base``: drop everything)."""
    from alembic import command

    _run(write_engine, command.downgrade, revision)


#: What reverting each revision removes (every step of ours drops data or a guard).
DOWNGRADE_DROPS = {
    "0001": "every table and all data",
    "0002": "the triggers that refuse UPDATE and DELETE of history rows",
    "0003": "the guards against REPLACE/UPSERT, TRUNCATE and dropping the triggers",
    "0004": "the query index (derived from history; upgrading rebuilds it)",
    "0005": "the API tokens of the HTTP service (every token stops working) and the blobs kept in the database",
    "0006": "the history chain (tamper evidence; checkpoints signed before no longer verify)",
    "0007": "the stored answers to idempotency keys (a retry after the downgrade may make a second version)",
    "0008": "the web catalogue's sign-in sessions (everyone signs in again) and the teams of API tokens",
    "0009": "the parts tables (spindles, holders, tools; refused while any part is catalogued: its rows are in "
            "the history chain)",
    "0010": "the listing's head columns of the query index (derived; upgrading rebuilds them)",
    "0011": "the query index's change log (derived; the next query after the downgrade refetches everything)",
}


def downgrade_plan(current: str | None, target: str) -> tuple[str | None, list[str]]:
    """``(target_revision, revisions_reverted_newest_first)`` for a downgrade from ``current``.

    ``target``: ``base``, ``-N`` (N steps) or a revision id below ``current``.

    Raises
    ------
    InputError
        Unknown revision, a target above the current revision, or more steps than exist.
    """
    script = _script()
    chain: list[str] = []  # current, its parent, ... down to the first revision
    rev = current
    while rev is not None:
        chain.append(rev)
        try:
            rev = script.get_revision(rev).down_revision
        except Exception:  # noqa: BLE001 - alembic raises several types for unknown ids
            raise InputError(f"the database is at revision {rev!r}, which this jointdb does not know") from None
    text = str(target).strip()
    if text == "base":
        return None, chain
    if re.fullmatch(r"-\d+", text):
        n = int(text[1:])
        if n > len(chain):
            raise InputError(f"cannot go {n} steps down from revision {current or 'base'} "
                             f"(only {len(chain)} below it)")
        return (chain[n] if n < len(chain) else None), chain[:n]
    if text in chain:
        return text, chain[:chain.index(text)]
    known = [r.revision for r in script.walk_revisions()]
    if text in known:
        raise InputError(f"revision {text} is not below the current revision {current or 'base'}; "
                         "use `jointdb db upgrade --to` to go up")
    raise InputError(f"unknown revision {text!r}; use base, -N or one of {', '.join(sorted(known))}")


def ensure_schema(read_engine: Engine, write_engine: Engine, auto_create: bool) -> None:
    """Refuse a database without the current schema, with advice.

    The check is one SELECT of ``alembic_version`` compared with
    :data:`jointdb.store._sqlitefile.HEAD_REVISION` (a test keeps that equal to the
    newest migration script); Alembic is imported only when they differ.
    SQLite files are created (atomically, with their schema) before this is
    called, so here a SQLite database must already be a jointdb one. A
    PostgreSQL database without any schema is migrated when ``auto_create``
    (under the write transaction, so concurrent first users migrate once).
    """
    from sqlalchemy.exc import DBAPIError

    head = HEAD_REVISION
    with read_engine.connect() as conn:
        try:
            current = conn.exec_driver_sql("SELECT version_num FROM alembic_version").scalar()
        except DBAPIError:  # no alembic_version table: no jointdb schema
            conn.rollback()
            current = None
        if current == head:
            return
        tables = set(inspect(conn).get_table_names())
    from alembic.runtime.migration import MigrationContext

    if current is None:
        if not auto_create or read_engine.dialect.name == "sqlite":
            raise InputError(
                "this database has no jointdb schema yet; run `jointdb db upgrade --db URL` first"
            )
        if tables & {"joints", "joint_versions"}:
            raise InputError("database has jointdb tables but no migration record; refusing to touch it")
        from alembic import command

        cfg = alembic_config()
        with write_engine.begin() as conn:
            if MigrationContext.configure(conn).get_current_revision() is None:
                cfg.attributes["connection"] = conn
                command.upgrade(cfg, "head")
        return
    raise schema_mismatch(current, {r.revision for r in _script().walk_revisions()})
