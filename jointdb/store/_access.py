"""What the store's helpers need of a database, without the :class:`Repository` facade.

The query, bundle and maintenance helpers (:mod:`jointdb.store._query`,
:mod:`jointdb.store._bundle`, :mod:`jointdb.store._maintenance`) take narrow interfaces
(:mod:`jointdb.store._protocol`): one that reads (``ReadAccess``: the URL, the read engine,
the blob store; :func:`read_session` opens a session on it) and one that also writes
(``WriteAccess``: plus :meth:`Storage.retrying`, a retried write transaction). A
:class:`Storage` is both; :func:`joint_row` finds a joint's row in a session. The
repository builds one ``Storage`` and hands it to them, so the helpers never import it.
"""

from __future__ import annotations

import random
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, TypeVar

from sqlalchemy import Engine, select
from sqlalchemy.exc import IntegrityError as DBIntegrityError
from sqlalchemy.exc import OperationalError
from sqlalchemy.orm import Session

from jointdb.schemas._limits import control_character
from jointdb.errors import ConflictError, InputError, NotFoundError
from jointdb.store._models import JointRow
from jointdb.store._reports import _is_transient, _is_unique_violation

#: how often a write transaction is retried after a conflict before ConflictError
MAX_WRITE_ATTEMPTS = 60

T = TypeVar("T")


@dataclass(frozen=True)
class Storage:
    """A database (two engines, its URL) and its blob store, as the helpers use them.

    Parameters
    ----------
    url
        The resolved database URL (named in error messages only through :func:`jointdb.store._db.safe_url`).
    read_engine, write_engine
        The SQLAlchemy engines of :func:`jointdb.store._db.make_engines`.
    blobs
        The blob store (:class:`jointdb.store._protocol.BlobStoreProtocol`).
    """

    url: str
    read_engine: Engine
    write_engine: Engine
    blobs: Any

    def read(self) -> Session:
        """A session on the read engine (objects stay usable after it closes)."""
        return read_session(self)

    def write(self) -> Session:
        """A session on the write engine (begin a transaction on it)."""
        return Session(self.write_engine, expire_on_commit=False)

    def retrying(self, fn: Callable[[Session], T]) -> T:
        """Run ``fn(session)`` in a write transaction; retry after rollback on conflicts.

        Raises
        ------
        ConflictError
            The transaction still conflicted after :data:`MAX_WRITE_ATTEMPTS` attempts.
        """
        delay = 0.005
        for attempt in range(MAX_WRITE_ATTEMPTS):
            try:
                with self.write() as session, session.begin():
                    return fn(session)
            except (DBIntegrityError, OperationalError) as exc:
                if isinstance(exc, OperationalError) and not _is_transient(exc):
                    raise
                if isinstance(exc, DBIntegrityError) and not _is_unique_violation(exc):
                    raise
                if attempt == MAX_WRITE_ATTEMPTS - 1:
                    raise ConflictError(f"write kept conflicting with other writers: {exc.orig}") from None
                time.sleep(delay * (1 + random.random()))
                delay = min(delay * 2, 0.5)
        raise AssertionError("unreachable")  # pragma: no cover


def read_session(store: Any) -> Session:
    """A session on ``store.read_engine`` (objects stay usable after it closes): what a helper
    that only reads needs of a store (:class:`jointdb.store._protocol.ReadAccess`)."""
    return Session(store.read_engine, expire_on_commit=False)


def joint_row(session: Session, name: str) -> JointRow:
    """The row of the joint called ``name``.

    Raises
    ------
    InputError
        ``name`` is not text, is too long or holds a control character (PostgreSQL refuses NUL).
    NotFoundError
        No joint has that name.
    """
    if not isinstance(name, str) or len(name) > 1000 or control_character(name):
        raise InputError(f"joint name {str(name)[:60]!r} must be text without control characters")
    joint = session.scalar(select(JointRow).where(JointRow.name == name))
    if joint is None:
        raise NotFoundError(f"no joint named {name!r} (see `jointdb joints list`)")
    return joint
