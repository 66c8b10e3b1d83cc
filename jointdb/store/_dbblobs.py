"""FRF blobs kept in the database itself (table ``frf_blobs``), selected with
``blobs="database"`` (or ``JOINTDB_BLOBS=database``): several API hosts then need nothing
but the database.

Same guarantees as the file store (:class:`jointdb.store._blobs.BlobStore`), same bytes:
a row's ``data`` is exactly a blob file (user block with the whole-file SHA-256, then the
HDF5 layout with fletcher32 chunks), so every read checks the whole-file hash, the chunk
checksums and that the decoded FRF hashes to the row's key. ``put`` is idempotent
(``INSERT ... ON CONFLICT``: a new blob is inserted, an existing one touched), its bytes
decoded once and compared with the FRF before they are written, and committed before it
returns; :meth:`DatabaseBlobStore.put_pending` writes it in the transaction of the version
that references it instead. ``collect`` (gc) locks the row (``FOR UPDATE`` on PostgreSQL, the write lock on
SQLite), re-reads its age and asks the database whether a row references it, all in one
transaction; a concurrent ``put`` of the same blob waits for that transaction and then
writes it again, so a writer can never reference a collected blob.
"""

from __future__ import annotations

import functools
import threading
from collections.abc import Iterator
from concurrent import futures
from datetime import datetime, timezone

from sqlalchemy import Engine, bindparam, delete, select
from sqlalchemy.orm import Session

from jointdb.errors import IntegrityError, NotFoundError
from jointdb.frf import FRF
from jointdb.store._blobformat import blob_bytes, check_digest, decode_blob_bytes, frf_sha256, verify_blob_bytes
from jointdb.store._blobs import BlobInfo, VerifyingBlobs
from jointdb.store._chain import pipelined, queue
from jointdb.store._durable import executor
from jointdb.store._models import BlobRow

#: the value of ``blobs=`` / ``JOINTDB_BLOBS`` that selects this store
DATABASE = "database"


def _now() -> datetime:
    return datetime.now(timezone.utc)


@functools.cache
def _blob_insert(dialect: str, touch: bool):
    """``INSERT`` of a blob row (parameters ``sha256``, ``data``, ``size``, ``now``) that, when the row
    exists, does nothing and returns no row (``touch=False``: a returned row says it was inserted) or
    refreshes its ``touched_at`` (``ON CONFLICT``; PostgreSQL and SQLite); built once per dialect."""
    if dialect == "postgresql":
        from sqlalchemy.dialects.postgresql import insert
    else:
        from sqlalchemy.dialects.sqlite import insert
    now = bindparam("now", type_=BlobRow.__table__.c.created_at.type)
    stmt = insert(BlobRow).values(sha256=bindparam("sha256"), data=bindparam("data"), size=bindparam("size"),
                                  created_at=now, touched_at=now)
    if touch:
        return stmt.on_conflict_do_update(index_elements=["sha256"], set_={"touched_at": stmt.excluded.touched_at})
    return stmt.on_conflict_do_nothing(index_elements=["sha256"]).returning(BlobRow.sha256)


class SessionPut:
    """A database blob being encoded and verified on a worker thread, written in the transaction of
    its version (see :meth:`DatabaseBlobStore.put_pending`); the interface of
    :class:`~jointdb.store._durable.PendingPut`.

    The worker encodes the bytes, hands them over (:meth:`wait` can queue their INSERT) and then
    decodes them and compares them with the FRF; the transaction commits only after that
    verification passed (on a pipelined PostgreSQL connection it runs while the INSERT travels)."""

    def __init__(self, store: "DatabaseBlobStore", digest: str, frf: FRF):
        self.store, self.digest = store, digest
        self._data: bytes | None = None
        self._encoded = threading.Event()
        self._encoding = executor().submit(self._encode_and_verify, frf)

    def _encode_and_verify(self, frf: FRF) -> bytes:
        try:
            _, data = blob_bytes(frf, self.digest)
            self._data = data
        finally:
            self._encoded.set()  # (no data: the error is the future's)
        verify_blob_bytes(data, frf, self.digest)  # the one decode: these bytes give back this FRF
        return data

    def _bytes(self) -> bytes:
        """The encoded bytes, once the worker has them (not yet verified)."""
        self._encoded.wait()
        if self._data is None:
            self._encoding.result()  # raises what the encoder met
        return self._data

    def verified(self) -> bytes:
        """The bytes once they read back as the FRF.

        Raises
        ------
        IntegrityError
            They did not (the transaction that holds them must not commit).
        """
        return self._encoding.result()

    def wait(self, session: Session | None = None) -> str:
        """Write the blob in ``session`` (committed with it, after its verification), or in its own
        transaction; its digest.

        Raises
        ------
        IntegrityError
            The encoded bytes did not read back as the FRF (nothing is written).
        """
        if session is None:
            data = self.verified()
            with Session(self.store.engine) as own, own.begin():
                self.store._write(own, self.digest, data)
        else:
            self.store._write(session, self.digest, self._bytes(), self.verified)
        return self.digest

    def join(self) -> None:
        """Wait for the worker's encoding, without raising what it met."""
        futures.wait([self._encoding])

    def cancel(self) -> None:
        """Nothing was written; wait for the worker."""
        self.join()


class DatabaseBlobStore(VerifyingBlobs):
    """Content-addressed FRF blobs in the ``frf_blobs`` table of the repository's database."""

    #: a blob is written in the transaction of the version that references it (``put_pending``)
    writes_in_version_transaction = True

    def __init__(self, engine: Engine, where: str = "database"):
        self.engine = engine
        self.root = f"{where} (table frf_blobs)"  # shown by `jointdb db info`; not a directory

    def __repr__(self) -> str:
        return f"DatabaseBlobStore({self.root!r})"

    _key = staticmethod(check_digest)

    # ------------------------------------------------------------------ write
    def put(self, frf: FRF) -> str:
        """Store an FRF durably (committed in a transaction of its own); return its SHA-256.
        Idempotent; the encoded bytes are verified before they are written."""
        return self.put_pending(frf).wait()

    def put_pending(self, frf: FRF) -> "SessionPut":
        """The blob's content hash now; its bytes encoded and verified on a worker thread while the
        caller runs the transaction of the version that references it, and written by
        ``wait(session)`` in that transaction (one commit for blob and row; nothing written when
        the version is refused or the bytes do not verify). ``wait()`` without a session writes it
        in its own transaction."""
        return SessionPut(self, frf_sha256(frf), frf)

    def _write(self, session: Session, digest: str, data: bytes, verified=None) -> None:
        """Insert (or touch) a blob in ``session``; a damaged stored copy is replaced.

        A new blob is one ``INSERT ... ON CONFLICT DO NOTHING RETURNING``; only when the row exists is it
        read (and replaced when damaged) and its ``touched_at`` refreshed (in one upsert, which
        waits for a ``gc`` holding the row's lock and writes it again if ``gc`` deleted it). On a
        pipelined PostgreSQL connection the INSERT is sent at commit, in the round trip of the
        history chain's entries (:func:`jointdb.store._chain.queue`), and the rest follows there.
        ``verified()`` (when given) returns once the bytes are known to read back, or raises: it is
        waited for before the commit (before the INSERT when that is not sent at commit)."""
        now = _now()
        conn = session.connection()
        params = {"sha256": digest, "data": data, "size": len(data), "now": now}
        insert = _blob_insert(conn.dialect.name, False)
        if pipelined(conn):
            def then(cursor) -> None:
                if verified is not None:
                    verified()  # IntegrityError: the transaction does not commit
                if cursor.fetchone() is None:  # the row exists
                    self._existing(session, digest, data, params)

            queue(session, insert, params, then)
            return
        if verified is not None:
            verified()
        if conn.dialect.insert_returning:  # a row back: inserted (SQLite >= 3.35 and PostgreSQL)
            if conn.execute(insert, params).first() is not None:
                return
        self._existing(session, digest, data, params)

    def _existing(self, session: Session, digest: str, data: bytes, params: dict) -> None:
        """The blob's row exists (or existed): replace it when damaged, refresh ``touched_at``."""
        existing = session.get(BlobRow, digest)
        if existing is not None and bytes(existing.data) != data and self._check(digest, existing.data):
            existing.data, existing.size = data, len(data)
        session.execute(_blob_insert(session.connection().dialect.name, True), params)

    # ------------------------------------------------------------------- read
    @staticmethod
    def _decode(digest: str, data: bytes) -> FRF:
        # header, whole-file hash, HDF5 chunk checksums, content hash = the stored attribute = the key
        return decode_blob_bytes(data, f"blob {digest}", digest)

    def _check(self, digest: str, data: bytes) -> str | None:
        try:
            self._decode(digest, data)
        except IntegrityError as exc:
            return str(exc)
        return None

    def get(self, digest: str) -> FRF:
        """Read and verify a blob (NotFoundError when missing, IntegrityError when corrupt)."""
        key = self._key(digest)
        with Session(self.engine) as s:
            data = s.scalar(select(BlobRow.data).where(BlobRow.sha256 == key))
        if data is None:
            raise NotFoundError(f"blob {digest} is missing (table frf_blobs)")
        return self._decode(key, bytes(data))

    def exists(self, digest: str) -> bool:
        key = self._key(digest)
        with Session(self.engine) as s:
            return s.scalar(select(BlobRow.sha256).where(BlobRow.sha256 == key)) is not None

    # ------------------------------------------------------------------ walk / gc
    def walk(self) -> Iterator[BlobInfo]:
        """All blobs; ``path`` is the digest (what :meth:`age_seconds` takes)."""
        with Session(self.engine) as s:
            rows = list(s.execute(select(BlobRow.sha256, BlobRow.size, BlobRow.touched_at).order_by(BlobRow.sha256)))
        for digest, size, touched in rows:
            yield BlobInfo(digest, digest, size, touched.timestamp())

    def temporaries(self) -> list:
        """None: a database write leaves no temporary behind."""
        return []

    def restore_set_aside(self, is_referenced) -> list[str]:
        return []

    def age_seconds(self, path) -> float:
        """Seconds since the blob ``path`` (its digest, as :meth:`walk` gives it) was written or touched."""
        with Session(self.engine) as s:
            touched = s.scalar(select(BlobRow.touched_at).where(BlobRow.sha256 == str(path)))
        return 0.0 if touched is None else (_now() - touched).total_seconds()

    def remove(self, digest: str) -> None:
        """Delete one blob unconditionally (tests and repairs; ``gc`` uses :meth:`collect`)."""
        with Session(self.engine) as s, s.begin():
            s.execute(delete(BlobRow).where(BlobRow.sha256 == self._key(digest)))

    def collect(self, digest: str, min_age_s: float, still_referenced) -> bool:
        """Delete an unreferenced blob old enough, in one transaction holding its row lock."""
        key = self._key(digest)
        engine = self.engine
        if engine.dialect.name == "sqlite":
            engine = engine.execution_options(sqlite_begin="IMMEDIATE")
        with Session(engine) as s, s.begin():
            touched = s.scalar(select(BlobRow.touched_at).where(BlobRow.sha256 == key).with_for_update())
            if touched is None:
                return False
            if (_now() - touched).total_seconds() < min_age_s or still_referenced(key):
                return False
            s.execute(delete(BlobRow).where(BlobRow.sha256 == key))
        return True


def open_blob_store(url: str, blobs, engine: Engine):
    """The blob store of a repository: the ``frf_blobs`` table when ``blobs`` (or
    ``JOINTDB_BLOBS``) is ``"database"``, else the blob directory (:func:`jointdb.store._db.blob_dir`)."""
    import os

    from jointdb.store import _db
    from jointdb.store._blobs import BlobStore

    chosen = str(blobs) if blobs is not None else os.environ.get("JOINTDB_BLOBS", "")
    if chosen == DATABASE:
        return DatabaseBlobStore(engine, _db.safe_url(url))
    return BlobStore(_db.blob_dir(url, blobs))
