"""Open a joint store from what a caller holds: an open store, a server address, or a database.

:func:`open_store` is what the application layer calls with its ``repo`` argument (a
:class:`~jointdb.store.Repository`, a :class:`~jointdb.client.RemoteRepository`, a server
address, a database URL or SQLite path, or None for the default database);
:func:`owned_store` does the same in a ``with`` block and closes only what it opened.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from pathlib import Path

from jointdb.errors import InputError
from jointdb.store._protocol import JointStore

#: address prefixes that name a ``jointdb serve`` server rather than a database
SERVER_SCHEMES = ("http://", "https://")


def open_store(target: JointStore | str | os.PathLike | None = None, *, token: str | None = None,
               blobs: str | os.PathLike | None = None, auto_create: bool | None = None) -> JointStore:
    """The joint store ``target`` names.

    Parameters
    ----------
    target
        An open store (returned as is: whoever opened it closes it); an ``http://`` or
        ``https://`` address of ``jointdb serve`` (a :class:`~jointdb.client.RemoteRepository`);
        a database URL or SQLite path, or None for ``$JOINTDB_URL`` / the per-user SQLite file
        (a :class:`~jointdb.store.Repository`).
    token
        Bearer token for a server (default ``$JOINTDB_TOKEN``); refused for a database.
    blobs, auto_create
        As :class:`~jointdb.store.Repository` (a database only).

    Returns
    -------
    JointStore
        The store; close it (``close()`` or ``with``) when it was opened here.

    Raises
    ------
    InputError
        A target of another type, a token for a database, or ``blobs`` / ``auto_create`` for a server.
    """
    if isinstance(target, JointStore) and not isinstance(target, (str, Path)):
        return target
    if target is not None and not isinstance(target, (str, os.PathLike)):
        raise InputError(f"a joint store is a Repository, a RemoteRepository, a server address or a database "
                         f"URL or path, not {type(target).__name__}")
    if isinstance(target, str) and target.startswith(SERVER_SCHEMES):
        if blobs is not None or auto_create is not None:
            raise InputError("blobs and auto_create are settings of a database, not of a server")
        from jointdb.store._remote import RemoteRepository

        return RemoteRepository(target, token if token is not None else (os.environ.get("JOINTDB_TOKEN") or None))
    if token is not None:
        raise InputError("a token is for a jointdb server (http:// or https://), not for a database")
    from jointdb.store._repository import Repository

    return Repository(target, blobs=blobs, auto_create=auto_create)


@contextlib.contextmanager
def owned_store(target: JointStore | str | os.PathLike | None = None, **options) -> Iterator[JointStore]:
    """:func:`open_store` in a ``with`` block: the store is closed at the end only if it was opened here.

    Parameters
    ----------
    target
        An open store (used as is, not closed), or what :func:`open_store` takes.
    **options
        Keyword arguments of :func:`open_store`.

    Yields
    ------
    JointStore
    """
    store = open_store(target, **options)
    try:
        yield store
    finally:
        if store is not target:
            store.close()
