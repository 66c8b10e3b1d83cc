"""Database location, engines and Alembic migrations.

Location, first match wins: the ``url`` argument (CLI ``--db``), the
``JOINTDB_URL`` environment variable, then the per-user default SQLite file
``$XDG_DATA_HOME/jointdb/jointdb.sqlite`` (``~/.local/share/jointdb/...``).
A plain path is taken as a SQLite file.

Blobs live in ``<sqlite file>.blobs/`` beside a SQLite database, or in the
directory given by ``blobs=`` / ``JOINTDB_BLOBS`` (required for PostgreSQL).

SQLite connections run with WAL, ``foreign_keys=ON``, ``synchronous=FULL`` and a
30 s busy timeout; write transactions start with ``BEGIN IMMEDIATE`` (the
``write`` engine), reads with a plain deferred ``BEGIN``.

Migrations are the Alembic scripts in ``jointdb/migrations`` (shipped in the
wheel); the Alembic configuration is built in code from the package path, so
no ``alembic.ini`` is needed at run time.
"""

from __future__ import annotations

import os
from pathlib import Path

from sqlalchemy import Engine, create_engine, event, inspect
from sqlalchemy.engine import make_url
from sqlalchemy.exc import ArgumentError

from jointdb.errors import InputError

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
    "BUSY_TIMEOUT_S",
]

BUSY_TIMEOUT_S = 30.0


def default_sqlite_path() -> Path:
    base = os.environ.get("XDG_DATA_HOME") or str(Path.home() / ".local" / "share")
    return Path(base) / "jointdb" / "jointdb.sqlite"


def resolve_url(url: str | os.PathLike | None = None) -> str:
    """The database URL to use (see module docstring)."""
    text = str(url) if url is not None else os.environ.get("JOINTDB_URL") or ""
    if not text:
        text = str(default_sqlite_path())
    if "://" not in text:
        if text == ":memory:":
            raise InputError("in-memory databases are not supported; give a file path or URL")
        text = "sqlite:///" + str(Path(text).expanduser().resolve())
    try:
        parsed = make_url(text)
    except ArgumentError:
        raise InputError(f"cannot read database URL {text!r}") from None
    if parsed.get_backend_name() not in ("sqlite", "postgresql"):
        raise InputError(f"unsupported database {parsed.get_backend_name()!r}: use sqlite or postgresql")
    if parsed.get_backend_name() == "sqlite" and parsed.database in (None, "", ":memory:"):
        raise InputError("in-memory SQLite databases are not supported; give a file path")
    return text


def is_sqlite(url: str) -> bool:
    return make_url(url).get_backend_name() == "sqlite"


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


def _sqlite_engine(url: str) -> tuple[Engine, Engine]:
    u = make_url(url)
    Path(str(u.database)).parent.mkdir(parents=True, exist_ok=True)
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


def make_engines(url: str) -> tuple[Engine, Engine]:
    """``(read_engine, write_engine)`` for a URL; identical for PostgreSQL."""
    if is_sqlite(url):
        return _sqlite_engine(url)
    engine = create_engine(url, pool_pre_ping=True)
    return engine, engine


# --------------------------------------------------------------------------- alembic
def migrations_dir() -> Path:
    return Path(__file__).resolve().parent.parent / "migrations"


def alembic_config(url: str | None = None):
    """An Alembic ``Config`` built in code (no alembic.ini needed)."""
    from alembic.config import Config

    cfg = Config()
    cfg.set_main_option("script_location", str(migrations_dir()))
    if url:
        cfg.set_main_option("sqlalchemy.url", url.replace("%", "%%"))
    return cfg


def head_revision() -> str:
    from alembic.script import ScriptDirectory

    return ScriptDirectory.from_config(alembic_config()).get_current_head()


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


def ensure_schema(read_engine: Engine, write_engine: Engine, auto_create: bool) -> None:
    """Create the schema of a new empty database; refuse an outdated one with advice.

    Runs under the write lock (SQLite ``BEGIN IMMEDIATE``) so that several
    processes opening a new database at once migrate it exactly once.
    """
    from alembic.runtime.migration import MigrationContext

    head = head_revision()
    with read_engine.connect() as conn:
        current = MigrationContext.configure(conn).get_current_revision()
    if current == head:
        return
    if current is None:
        if not auto_create:
            raise InputError(
                "this database has no jointdb schema yet; run `jointdb db upgrade --db URL` first"
            )
        from alembic import command

        cfg = alembic_config()
        with write_engine.begin() as conn:
            now = MigrationContext.configure(conn).get_current_revision()
            tables = set(inspect(conn).get_table_names()) if now is None else set()
            if now is None and tables & {"joints", "joint_versions"}:
                raise InputError("database has jointdb tables but no migration record; refusing to touch it")
            if now is None:
                cfg.attributes["connection"] = conn
                command.upgrade(cfg, "head")
        return
    raise InputError(
        f"database schema is at revision {current}, this jointdb needs {head}; run `jointdb db upgrade`"
    )
