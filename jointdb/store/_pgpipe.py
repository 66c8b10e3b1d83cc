"""Several SQLAlchemy Core statements sent to PostgreSQL in one round trip (libpq pipeline mode).

The PostgreSQL catalogue (:mod:`jointdb.store._catalogue`, :mod:`jointdb.store._chain`) needs
the results of only a few of its statements before it sends the next ones: a :class:`Batch`
queues statements and sends them together on the transaction's psycopg connection, which
waits once for all their results. The server runs them one after the other, in order, each
on its own snapshot (READ COMMITTED), exactly as if they had been sent one by one: a SELECT
queued after a ``FOR UPDATE`` runs after the lock is granted and sees what the lock's
previous holder committed.

A statement is compiled by SQLAlchemy once per dialect and its parameters go through the
column types' bind processors (JSON, UTC times), so the bytes sent are those
``Connection.execute`` would send. Errors come back as SQLAlchemy's (``IntegrityError``,
``OperationalError``, ...), as from ``Connection.execute``; the transaction is then aborted
and the caller rolls it back.

Only :func:`jointdb.store._chain.pipelined` connections (PostgreSQL through psycopg with a
libpq that has pipeline mode) use this; nothing else may run on the connection while a
batch is being sent.
"""

from __future__ import annotations

import functools
from typing import Any


@functools.lru_cache(maxsize=512)  # (per engine's dialect: bounded, for processes that open many)
def _compiled(stmt, dialect, keys: tuple[str, ...] | None):
    """``(compiled, sql, {bind name: processor})`` of a statement (``keys``: the columns an INSERT or
    UPDATE without explicit values is compiled for)."""
    compiled = stmt.compile(dialect=dialect, column_keys=list(keys) if keys is not None else None)
    processors = {}
    for name, bind in compiled.binds.items():
        processor = bind.type.dialect_impl(dialect).bind_processor(dialect)
        if processor is not None:
            processors[name] = processor
    return compiled, compiled.string, processors


class Batch:
    """Statements to send in one round trip on ``conn`` (a SQLAlchemy Connection in a transaction).

    :meth:`add` queues a statement and returns the index of its cursor; :meth:`run` sends them
    all, waits once, and returns the cursors (rows are named tuples: ``row.column``).
    """

    def __init__(self, conn):
        self.conn = conn
        self._items: list[tuple[str, Any, bool]] = []

    def __len__(self) -> int:
        return len(self._items)

    def add(self, stmt, params: dict | list[dict] | None = None) -> int:
        """Queue ``stmt`` with ``params`` (a dict, or a list of dicts: one execution per row).

        Parameters
        ----------
        stmt
            A SQLAlchemy Core statement (built once and reused: it is compiled once).
        params
            Its parameters by bind name, or a list of them (``executemany``).

        Returns
        -------
        int
            The position of its cursor in what :meth:`run` returns.
        """
        many = isinstance(params, list)
        rows = params if many else [params or {}]
        keys = tuple(sorted(rows[0])) if rows and rows[0] else None
        compiled, sql, processors = _compiled(stmt, self.conn.dialect, keys)
        converted = []
        for row in rows:
            values = compiled.construct_params(row)
            for name, processor in processors.items():
                if name in values:
                    values[name] = processor(values[name])
            converted.append(values)
        self._items.append((sql, converted if many else converted[0], many))
        return len(self._items) - 1

    def run(self) -> list:
        """Send every queued statement in one pipeline and wait for all their results.

        Returns
        -------
        list of psycopg.Cursor
            One per statement, in the order added, with its results (``fetchone``,
            ``rowcount``).

        Raises
        ------
        sqlalchemy.exc.DBAPIError
            A statement failed (the subclass that matches the driver's error).
        """
        import psycopg
        from psycopg.rows import namedtuple_row
        from sqlalchemy.exc import DBAPIError

        raw = self.conn.connection.driver_connection
        cursors = []
        try:
            with raw.pipeline():  # sent together; leaving the block syncs once and receives every result
                for sql, params, many in self._items:
                    cur = raw.cursor(row_factory=namedtuple_row)
                    if many:
                        cur.executemany(sql, params)
                    else:
                        cur.execute(sql, params)
                    cursors.append(cur)
        except psycopg.Error as exc:
            statements = "; ".join(sql for sql, _, _ in self._items)
            raise DBAPIError.instance(statements, None, exc, psycopg.Error, dialect=self.conn.dialect) from exc
        finally:
            self._items = []
        return cursors
