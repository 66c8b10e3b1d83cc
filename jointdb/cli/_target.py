"""Where a CLI command's catalogue is: the ``--db`` / ``--blobs`` / ``--json`` options, the checks of an SQLite
target before anything is opened or created, and the repository (local, or a server's over ``--server``).

Used by every command that reads or writes the catalogue (:mod:`jointdb.cli._store`, ``_db``, ``_parts``,
``_campaign``, ``_predict``, ``_optimize``, ``_serve``, ``_worker``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Optional

import typer

from jointdb.errors import InputError, NotFoundError

DbOpt = Annotated[
    Optional[str],
    typer.Option("--db", help="Database URL or SQLite file (default: $JOINTDB_URL or the per-user database)."),
]
JsonOpt = Annotated[bool, typer.Option("--json", help="Write JSON to stdout instead of a table.")]
BlobsOpt = Annotated[
    Optional[Path], typer.Option("--blobs", help="Blob directory, or 'database' to keep blobs in the database (default: $JOINTDB_BLOBS or beside the SQLite file).")
]


def check_db_target(db: str | None, create: bool = False) -> None:
    """Refuse an unusable SQLite ``--db``/``$JOINTDB_URL`` before anything is opened or created.

    A directory, an empty (0-byte) or non-SQLite file is refused (InputError);
    a missing file is NotFoundError unless ``create`` (``catalogue``,
    ``joints import``, ``db upgrade``), and even then its directory must exist
    (the per-user default directory is created).

    Raises
    ------
    NotFoundError, InputError
    """
    import os

    from jointdb.store._db import check_sqlite_file, is_sqlite, resolve_url, sqlite_path

    given = db if db is not None else os.environ.get("JOINTDB_URL")
    url = resolve_url(given)
    if not is_sqlite(url):
        return
    path = sqlite_path(url)
    if check_sqlite_file(path):
        return
    if not create:
        raise NotFoundError(f"database {path} does not exist (`jointdb catalogue`, `jointdb joints import` "
                            "or `jointdb db upgrade` creates it)")
    if given and not path.parent.is_dir():
        raise InputError(f"database {path}: directory {path.parent} does not exist")


def open_repo(db: str | None, blobs: Path | None = None, *, create: bool = False):
    """The repository of ``--db``; only writing commands (``create``) may create a new SQLite file.

    Without ``--db``, a server named by ``jointdb --server URL`` / ``$JOINTDB_SERVER`` is used
    instead (token from ``$JOINTDB_TOKEN``): :class:`jointdb.client.RemoteRepository`.
    """
    import os

    if db is None and os.environ.get("JOINTDB_SERVER"):
        from jointdb.client import RemoteRepository

        return RemoteRepository(os.environ["JOINTDB_SERVER"], os.environ.get("JOINTDB_TOKEN") or None)
    from jointdb.store import Repository

    check_db_target(db, create)
    return Repository(db, blobs=blobs, auto_create=None if create else False)


def refuse_server(db: str | None, command: str) -> None:
    """A command that needs the database itself says so over ``--server`` (instead of using a local one)."""
    import os

    if db is None and os.environ.get("JOINTDB_SERVER"):
        raise InputError(f"`jointdb {command}` does not work over --server (the API has no such call); "
                         "give --db URL (run it where the database is)")


def open_local_repo(db: str | None, blobs: Path | None, command: str, *, create: bool = False):
    """:func:`open_repo` for a command that needs the database itself: refused over ``--server``."""
    refuse_server(db, command)
    return open_repo(db, blobs, create=create)
