"""Tamper-evident history: an append-only hash chain over every history row, and signed checkpoints.

Every row of the history tables (joints, versions, state changes, audit rows, parts and part
versions) gets one
entry of the table ``history_chain`` (migration ``0006``) in the transaction that writes it,
in commit order::

    entry_i = (seq, kind, row id, content hash of the row)
    head_i  = SHA-256(head_{i-1} || "seq|kind|row id|content hash"),  head_0 = 32 zero bytes

The content hash is recomputed from the row as stored (every column; JSON columns as their
stored text), so ``jointdb db check`` can recompute the whole chain from the rows alone.
That canonical form (:func:`content_hash`, :func:`next_head`) is part of the stored data:
changing it needs a migration that re-chains (and invalidates every checkpoint signed before).

Appending is serialised: PostgreSQL takes a transaction-level advisory lock (per schema)
before reading the chain's head, in the transaction of the rows it covers, and ``seq`` is
the primary key, so concurrent writers never fork the chain; SQLite writers are serialised
by ``BEGIN IMMEDIATE``. The write paths need no call of their own for ORM rows: a
``after_flush`` hook notes every new history row of a session and a ``before_commit`` hook
appends them; rows inserted with Core statements are noted with :func:`append_chain`.

Whoever owns the tables can rewrite a row *and* the chain after it. A signed checkpoint
(tree size, head, time; Ed25519, :mod:`jointdb.store._signing`) kept elsewhere detects that:
:func:`chain_problems` recomputes the chain from the rows and requires the history it sees
to extend the checkpoint (same head at that size).
"""

from __future__ import annotations

import base64
import functools
import hashlib
import json
from datetime import datetime, timezone
from typing import Any, Iterable

from sqlalchemy import JSON, BigInteger, Integer, String, UniqueConstraint, event, insert, select, text
from sqlalchemy.orm import Mapped, Session, mapped_column

from jointdb.errors import InputError, IntegrityError
from jointdb.store._models import AuditRow, Base, JointRow, PartRow, PartVersionRow, StateRow, VersionRow
from jointdb.store._pgpipe import Batch

ZERO = "0" * 64
CHECKPOINT_FORMAT = "jointdb-checkpoint/1"
SIGNED_PREFIX = b"jointdb-checkpoint-signature-v1\n"
#: kind -> mapped class, in the order the rows of one transaction are appended
KINDS = {"joint": JointRow, "version": VersionRow, "state": StateRow, "audit": AuditRow,
         "part": PartRow, "part_version": PartVersionRow}  # parts: migration 0009
_KIND_OF = {cls: kind for kind, cls in KINDS.items()}
_PENDING = "jointdb_chain_pending"
_HELD = "jointdb_chain_held"  # (seq, head) read under the lock by this transaction
_QUEUED = "jointdb_chain_queued"  # statements sent with the chain's entries at commit


class ChainRow(Base):
    """One entry of the history chain (migration ``0006``): append-only like the rows it covers."""

    __tablename__ = "history_chain"
    __table_args__ = (UniqueConstraint("kind", "row_id"),)

    seq: Mapped[int] = mapped_column(BigInteger, primary_key=True, autoincrement=False)
    kind: Mapped[str] = mapped_column(String(20))
    row_id: Mapped[int] = mapped_column(Integer)
    content_sha256: Mapped[str] = mapped_column(String(64))
    head_sha256: Mapped[str] = mapped_column(String(64))


# --------------------------------------------------------------------------- hashing
def _plain(value: Any) -> Any:
    if isinstance(value, datetime):
        if value.tzinfo is not None:
            value = value.astimezone(timezone.utc).replace(tzinfo=None)
        return value.isoformat(timespec="microseconds")
    if isinstance(value, (bytes, memoryview)):
        return bytes(value).hex()
    if isinstance(value, float):
        return repr(value)
    return value


def _columns(cls, dialect: str):
    """The columns of a history table, JSON ones read as their stored text (never decoded; on SQLite
    the times too), so that a damaged value is hashed as it is instead of failing to load."""
    from sqlalchemy import Text, cast, type_coerce

    from jointdb.store._models import UTCDateTime

    out = []
    for c in cls.__table__.columns:
        if isinstance(c.type, JSON):
            out.append(cast(c, Text).label(c.name))
        elif dialect == "sqlite" and isinstance(c.type, UTCDateTime):
            out.append(type_coerce(c, Text).label(c.name))
        else:
            out.append(c)
    return out


def stored_columns(kind: str, dialect: str) -> list:
    """The columns of a history row as :func:`content_hash` reads them (the stored text of JSON
    columns), for ``INSERT ... RETURNING``: the row as stored comes back with its insert, and
    :func:`append_chain` takes its content hash without reading it again.

    Parameters
    ----------
    kind
        One of :data:`KINDS`.
    dialect
        ``"postgresql"`` or ``"sqlite"``.

    Returns
    -------
    list
        SQLAlchemy column expressions, labelled with the column names.
    """
    return _columns(KINDS[kind], dialect)


def content_hash(kind: str, row: Any) -> str:
    """SHA-256 of a row's canonical content: every column, by name (``row`` is a result row, or a
    mapping of column name to value as a result row holds them)."""
    mapping = dict(row._mapping) if hasattr(row, "_mapping") else dict(row)
    content = {"kind": kind, **{k: _plain(v) for k, v in mapping.items()}}
    data = json.dumps(content, sort_keys=True, separators=(",", ":"), ensure_ascii=True, default=str)
    return hashlib.sha256(data.encode()).hexdigest()


def next_head(previous: str, seq: int, kind: str, row_id: int, content: str) -> str:
    """``head_i = SHA-256(head_{i-1} || entry_i)`` (hex digests)."""
    return hashlib.sha256(bytes.fromhex(previous) + f"{seq}|{kind}|{row_id}|{content}".encode()).hexdigest()


def _contents(conn, kind: str, ids: Iterable[int] | None = None) -> dict[int, str]:
    """``row id -> content hash`` of the rows of one kind (all, or the ``ids`` given)."""
    cls = KINDS[kind]
    q = select(*_columns(cls, conn.dialect.name))
    if ids is not None:
        q = q.where(cls.__table__.c.id.in_(sorted(set(ids))))
    return {r.id: content_hash(kind, r) for r in conn.execute(q)}


# --------------------------------------------------------------------------- appending
def _lock(conn) -> None:
    if conn.dialect.name == "postgresql":  # held to the end of the transaction: appends in commit order
        conn.execute(text("SELECT pg_advisory_xact_lock(hashtext('jointdb_history_chain'), "
                          "hashtext(current_schema()))"))


def _append(conn, rows: list[tuple[str, int, str | None]], held: tuple[int, str] | None = None,
            queued: list | None = None) -> None:
    # the rows' content first (this transaction's own rows: no lock needed; a content hash taken from
    # the row its INSERT returned is not read again), then, under the lock held to commit, only the
    # chain's head and the insert. ``held``: the head this transaction read under the lock already
    # (:func:`hold_head`); ``queued``: statements sent with the insert (:func:`queue`)
    known = {(k, i): c for k, i, c in rows if c is not None}
    todo = []
    for kind in KINDS:
        ids = sorted({i for k, i, _ in rows if k == kind})
        missing = [i for i in ids if (kind, i) not in known]
        contents = _contents(conn, kind, missing) if missing else {}
        for row_id in ids:
            content = known.get((kind, row_id)) or contents.get(row_id)
            if content is None:
                raise IntegrityError(f"history row {kind} {row_id} vanished before its chain entry was written")
            todo.append((kind, row_id, content))
    if held is None and todo:
        held = _locked_head(conn)
    seq, head = held or (0, ZERO)
    entries = []
    for kind, row_id, content in todo:
        seq += 1
        head = next_head(head, seq, kind, row_id, content)
        entries.append({"seq": seq, "kind": kind, "row_id": row_id, "content_sha256": content, "head_sha256": head})
    if not queued:
        # executemany: psycopg sends the rows in one pipeline (one round trip), and the statement is compiled
        # once (a multi-row VALUES statement would be compiled again for every call: 10x the CPU time)
        conn.execute(_chain_insert(), entries)
        return
    batch = Batch(conn)  # the entries and the queued statements in one round trip
    if entries:
        batch.add(_chain_insert(), entries)
    positions = [(batch.add(stmt, params), then) for stmt, params, then in queued]
    cursors = batch.run()
    for position, then in positions:
        if then is not None:
            then(cursors[position])


@functools.cache
def _chain_insert():
    return insert(ChainRow.__table__)


_HEAD = "SELECT seq, head_sha256 FROM history_chain ORDER BY seq DESC LIMIT 1"
_LOCK = "SELECT pg_advisory_xact_lock(hashtext('jointdb_history_chain'), hashtext(current_schema()))"


@functools.cache
def _pipelines() -> bool:
    """Whether psycopg's libpq has pipeline mode (libpq >= 14; a distribution's psycopg may link an
    older one): without it the lock and the SELECT are two round trips."""
    import psycopg

    return bool(psycopg.Pipeline.is_supported())


def pipelined(conn) -> bool:
    """Whether statements can be sent to ``conn``'s database several in one round trip
    (:class:`jointdb.store._pgpipe.Batch`: PostgreSQL through psycopg, libpq with pipeline mode).

    Parameters
    ----------
    conn
        A SQLAlchemy Connection.

    Returns
    -------
    bool
    """
    return conn.dialect.name == "postgresql" and conn.dialect.driver == "psycopg" and _pipelines()


@functools.cache
def lock_and_head() -> tuple:
    """The chain's advisory lock and its head's SELECT, for a :class:`~jointdb.store._pgpipe.Batch`
    (queued in this order: the SELECT runs after the lock is granted, on a snapshot of its own)."""
    return text(_LOCK), text(_HEAD)


def head_of(row) -> tuple[int, str]:
    """``(seq, head)`` from the row of the head's SELECT (None: the chain is empty)."""
    return (int(row[0]), row[1]) if row else (0, ZERO)


def _locked_head(conn) -> tuple[int, str]:
    """``(seq, head)`` of the chain's last entry (``(0, ZERO)`` when empty), read under the chain's lock.

    PostgreSQL (psycopg): the advisory lock and the head's SELECT are sent in one pipeline (one
    round trip; the SELECT runs after the lock is granted, on a snapshot of its own, as two
    statements would); errors come back as SQLAlchemy's, as from ``conn.execute``.
    """
    if not pipelined(conn):
        _lock(conn)
        return chain_head(conn)
    batch = Batch(conn)
    for stmt in lock_and_head():
        batch.add(stmt)
    return head_of(batch.run()[1].fetchone())


def hold_head(session: Session, seq: int, head: str) -> None:
    """Note that ``session``'s transaction holds the chain's lock and read its head ``(seq, head)``
    (:func:`lock_and_head`): its rows are appended at commit without reading the head again."""
    session.info[_HELD] = (seq, head)


def queue(session: Session, stmt, params: dict, then=None) -> None:
    """Send ``stmt`` (with ``params``) at commit, in the round trip that inserts the chain's entries
    (only on a :func:`pipelined` connection); ``then(cursor)`` gets its result there."""
    session.info.setdefault(_QUEUED, []).append((stmt, params, then))


def append_chain(session: Session, rows: Iterable[tuple]) -> None:
    """Note history rows inserted with Core statements (``(kind, id)``, or ``(kind, id, content
    hash)`` when the caller has the row as stored: see :func:`stored_columns`; kind in
    :data:`KINDS`); they are appended to the chain when ``session`` commits, with the ORM rows of
    the transaction."""
    pending = session.info.setdefault(_PENDING, [])
    for kind, row_id, *content in rows:
        if row_id is not None:
            pending.append((kind, int(row_id), content[0] if content else None))


@event.listens_for(Session, "after_flush")
def _note_new_rows(session: Session, flush_context) -> None:
    for obj in session.new:
        kind = _KIND_OF.get(type(obj))
        if kind is not None:
            session.info.setdefault(_PENDING, []).append((kind, obj.id, None))


@event.listens_for(Session, "before_commit")
def _append_pending(session: Session) -> None:
    session.flush()
    rows = session.info.pop(_PENDING, None)
    held, queued = session.info.pop(_HELD, None), session.info.pop(_QUEUED, None)
    if rows or queued:
        _append(session.connection(), rows or [], held, queued)


@event.listens_for(Session, "after_soft_rollback")
def _forget_pending(session: Session, previous_transaction) -> None:
    for key in (_PENDING, _HELD, _QUEUED):
        session.info.pop(key, None)


def build_chain(conn) -> int:
    """Append every history row not yet in the chain, kind by kind in id order (migration ``0006``
    for existing databases). Returns the number of entries appended."""
    from sqlalchemy import inspect

    chain = ChainRow.__table__
    have = {(k, i) for k, i in conn.execute(select(chain.c.kind, chain.c.row_id))}
    tables = set(inspect(conn).get_table_names())  # migration 0006 runs before the tables of later kinds exist
    rows = [(kind, i, None) for kind, cls in KINDS.items() if cls.__tablename__ in tables
            for (i,) in conn.execute(select(cls.__table__.c.id).order_by(cls.__table__.c.id)) if (kind, i) not in have]
    if rows:
        _append(conn, rows)
    return len(rows)


# --------------------------------------------------------------------------- verifying
def chain_head(conn) -> tuple[int, str]:
    """``(tree size, head)`` as stored."""
    chain = ChainRow.__table__
    last = conn.execute(select(chain.c.seq, chain.c.head_sha256).order_by(chain.c.seq.desc()).limit(1)).first()
    return (int(last[0]), last[1]) if last else (0, ZERO)


def recompute(conn) -> tuple[list[str], list[str]]:
    """``(heads, problems)``: the heads recomputed from the rows themselves (``heads[i]`` is the head
    after entry ``i + 1``) and what differs from the stored chain (the first differing entry first)."""
    chain = ChainRow.__table__
    contents = {kind: _contents(conn, kind) for kind in KINDS}
    problems: list[str] = []
    heads: list[str] = []
    head = stored = ZERO
    seen: set[tuple[str, int]] = set()
    for entry in conn.execute(select(chain).order_by(chain.c.seq)):
        seq = len(heads) + 1
        where = f"chain entry {entry.seq} ({entry.kind} row {entry.row_id})"
        if entry.seq != seq:
            problems.append(f"chain entry {seq} is missing (the next one is {entry.seq})")
        row_content = contents.get(entry.kind, {}).get(entry.row_id)
        if row_content is None:
            problems.append(f"{where}: the row is missing (deleted)")
            row_content = "missing"
        elif row_content != entry.content_sha256:
            problems.append(f"{where}: the row's content differs from when it was written (rewritten)")
        head = next_head(head, seq, entry.kind, entry.row_id, row_content)
        stored = next_head(stored, seq, entry.kind, entry.row_id, entry.content_sha256)
        if stored != entry.head_sha256:
            problems.append(f"{where}: the stored chain head does not follow from the entries before it "
                            "(chain rewritten)")
            stored = entry.head_sha256
        heads.append(head)
        seen.add((entry.kind, entry.row_id))
    for kind, rows in contents.items():
        for row_id in sorted(set(rows) - {i for k, i in seen if k == kind}):
            problems.append(f"{kind} row {row_id} is not in the history chain (written around jointdb)")
    return heads, problems


def chain_problems(conn, checkpoint: dict | None = None) -> list[str]:
    """What differs between the rows, the stored chain and (optionally) a verified checkpoint."""
    heads, problems = recompute(conn)
    if checkpoint is not None:
        size, head = int(checkpoint["tree_size"]), checkpoint["head_sha256"]
        if size > len(heads):
            problems.insert(0, f"the history has {len(heads)} chain entries, fewer than the checkpoint's {size} "
                               "(entries were removed)")
        elif size and heads[size - 1] != head:
            problems.insert(0, f"the history does not extend the checkpoint: the head recomputed from the rows "
                               f"at entry {size} differs from the signed one (history up to entry {size} was "
                               "rewritten)")
    return problems


# --------------------------------------------------------------------------- checkpoints
def _signed_bytes(cp: dict) -> bytes:
    return SIGNED_PREFIX + f"{cp['format']}|{int(cp['tree_size'])}|{cp['head_sha256']}|{cp['time']}".encode()


def make_checkpoint(size: int, head: str, private_key) -> dict[str, Any]:
    """A checkpoint of ``(size, head)`` now, signed with an Ed25519 private key."""
    from jointdb.store._signing import fingerprint, public_raw

    cp: dict[str, Any] = {"format": CHECKPOINT_FORMAT, "tree_size": int(size), "head_sha256": head,
                          "time": datetime.now(timezone.utc).isoformat(timespec="seconds")}
    raw = public_raw(private_key.public_key())
    cp["public_key"] = base64.b64encode(raw).decode()
    cp["key_fingerprint"] = fingerprint(raw)
    cp["signature"] = base64.b64encode(private_key.sign(_signed_bytes(cp))).decode()
    return cp


def parse_checkpoint(data: Any, trusted=()) -> tuple[dict[str, Any], str]:
    """``(checkpoint, fingerprint)`` of a checkpoint whose signature verifies.

    ``trusted``: public keys (``load_public_key``); when given, the signer must be one of them,
    else the key named in the checkpoint is used (it proves integrity, not who signed).

    Raises
    ------
    IntegrityError
        Malformed, or the signature does not verify (with a trusted key).
    """
    from cryptography.exceptions import InvalidSignature
    from cryptography.hazmat.primitives.asymmetric import ed25519

    from jointdb.store._signing import fingerprint, public_raw

    try:
        if data.get("format") != CHECKPOINT_FORMAT:
            raise ValueError("unknown format")
        size = int(data["tree_size"])
        head = str(data["head_sha256"])
        if size < 0 or len(head) != 64 or any(c not in "0123456789abcdef" for c in head):
            raise ValueError("bad size or head")
        signature = base64.b64decode(str(data["signature"]), validate=True)
        keys = list(trusted) or [ed25519.Ed25519PublicKey.from_public_bytes(
            base64.b64decode(str(data["public_key"]), validate=True))]
        cp = {"format": data["format"], "tree_size": size, "head_sha256": head, "time": str(data["time"])}
    except (AttributeError, KeyError, TypeError, ValueError):
        raise IntegrityError("the checkpoint is malformed (expected a JSON object from `jointdb db checkpoint`)") from None
    for key in keys:
        try:
            key.verify(signature, _signed_bytes(cp))
            return cp, fingerprint(public_raw(key))
        except InvalidSignature:
            continue
    who = "any trusted key" if trusted else "the key it names"
    raise IntegrityError(f"the checkpoint's signature does not verify with {who} (checkpoint forged or altered)")


def read_checkpoint_file(path) -> Any:
    """The JSON of a checkpoint file (one line errors)."""
    from pathlib import Path

    from jointdb.store._signing import read_small_file

    p = Path(path)
    raw = read_small_file(p, f"checkpoint {p.name}", "is too large ({n} bytes) to be a checkpoint")
    try:
        return json.loads(raw)
    except (UnicodeDecodeError, ValueError):
        raise IntegrityError(f"checkpoint {p.name} is not JSON") from None


def signed_checkpoint(conn, private_key, since: dict | None = None) -> dict[str, Any]:
    """Recompute the chain from the rows (in ``conn``'s snapshot) and sign its head.

    ``since``: an earlier checkpoint the history must extend.

    Raises
    ------
    IntegrityError
        The rows, the stored chain or ``since`` disagree: nothing is signed (signing would
        bless a rewritten history).
    """
    problems = chain_problems(conn, since)
    if problems:
        raise IntegrityError(f"history chain is broken, nothing signed: {problems[0]} (run `jointdb db check`)")
    size, head = chain_head(conn)
    return make_checkpoint(size, head, private_key)


def check_serve_options(db, allow_owner: bool, key_path, interval_s: float) -> dict[str, str]:
    """``jointdb serve``'s role and checkpoint options, checked before the server starts; returns
    the environment the workers read them from.

    Raises
    ------
    InputError
        Connected as the tables' owner or a superuser without ``allow_owner``; an unusable key
        or interval.
    """
    from pathlib import Path

    from jointdb.store._db import resolve_url
    from jointdb.store._roles import refuse_owner
    from jointdb.store._signing import load_private_key

    if not allow_owner:
        refuse_owner(resolve_url(db))
    env: dict[str, str] = {}
    if key_path is not None:
        load_private_key(key_path)  # refuse a bad key now, not at the first request
        if not interval_s >= 1:
            raise InputError(f"--checkpoint-interval must be >= 1 second, got {interval_s:g}")
        env = {"JOINTDB_CHECKPOINT_KEY": str(Path(key_path).resolve()), "JOINTDB_CHECKPOINT_INTERVAL_S": str(interval_s)}
    return env
