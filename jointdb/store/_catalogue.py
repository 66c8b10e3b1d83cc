"""The write transaction of :meth:`jointdb.store.Repository.catalogue`, in a few Core statements.

One new version is, inside the caller's write transaction:

1. the joint row, locked (``FOR UPDATE`` on PostgreSQL; SQLite writers are already
   serialised by ``BEGIN IMMEDIATE``), then its latest version row and the state that
   applies to the next one (the latest state row naming the joint or that number), in
   one SELECT; or a new joint row. On PostgreSQL the lock is its own statement and the
   read comes after it: a read inside the locking statement would use that statement's
   snapshot, taken before a writer that held the lock (a new version, a deprecation)
   committed, and could write the index from stale state;
2. the version row with its record hash, and its audit row: on PostgreSQL one statement
   (an ``INSERT ... RETURNING`` in a CTE for each) that returns the rows as stored, whose
   history-chain entries (:mod:`jointdb.store._chain`) are hashed from that, not read again;
3. the query index (:mod:`jointdb.store._index`): the joint's other versions lose the
   ``newest`` (and, unless the new one is deprecated, ``newest_active``) flags, the new
   version's index and geometry rows, and the stamp's generation is increased.

Before step 2, under the joint row's lock (so two concurrent writers cannot both pass):
the new version must be the same joint as the latest one (:mod:`jointdb.store._identity`:
a contradiction is refused unless forced), and content identical to the latest version
writes nothing (the latest version is the answer). A request made with an idempotency key
(``(owner, key, request_sha256)``) is answered from its ``idempotency_keys`` row when one
exists; otherwise that row is written in this same transaction.

The statements are built once per process and executed on the transaction's
connection (no ORM unit of work: the rows are only inserted, never changed, so
the immutability hook of the ORM has nothing to check). The rows are the ones
the ORM path wrote before; ``jointdb db check`` recomputes the index from history.

On PostgreSQL through psycopg (:func:`jointdb.store._chain.pipelined`) the statements
go in batches, each one round trip (:class:`jointdb.store._pgpipe.Batch`; the server
runs them in order, each on its own snapshot): after the BEGIN, (1) the joint's lock,
then its head and ``nextval`` of the version ids; (2) the version and audit rows, the
query index, the stamp, then the history chain's advisory lock and its head; (3) at
commit, the chain's entries and the blob's row (:func:`jointdb.store._chain.queue`);
then the COMMIT: five round trips (a new joint: one more, its row).
"""

from __future__ import annotations

import functools
import uuid as uuidlib
from types import SimpleNamespace

from sqlalchemy import and_, bindparam, false, func, insert, or_, select, text, true, update

from jointdb.errors import ConflictError, InputError
from jointdb.store._chain import (
    append_chain,
    content_hash,
    head_of,
    hold_head,
    lock_and_head,
    pipelined,
    stored_columns,
)
from jointdb.store._identity import contradiction, identity_changes, same_content
from jointdb.store._index import bump, bump_params, bump_pg, count_params, count_upsert, index_values, prune
from jointdb.store._pgpipe import Batch
from jointdb.store._models import (
    AuditRow,
    IdempotencyRow,
    JointRow,
    QueryGeometryRow,
    QueryVersionRow,
    StateRow,
    VersionRow,
    utcnow,
)
from jointdb.store._records import record_dict, record_sha256, software_version, to_version
from jointdb.store._vocabulary import dof_strings


@functools.cache
def _statements() -> SimpleNamespace:
    j, v, s = JointRow.__table__, VersionRow.__table__, StateRow.__table__
    q = QueryVersionRow.__table__
    others = v.alias("others")
    latest_of_name = select(func.max(others.c.version)).where(others.c.joint_id == j.c.id).correlate(j).scalar_subquery()
    idem = IdempotencyRow.__table__
    # the joint, its latest version row (outer join: a joint without one has NULLs) and the state that
    # applies to the version after it
    state = (select(s.c.state)
             .where(s.c.joint_id == j.c.id, or_(s.c.version.is_(None), s.c.version == func.coalesce(v.c.version, 0) + 1))
             .order_by(s.c.at.desc(), s.c.id.desc()).limit(1).correlate(j, v).scalar_subquery())
    # the joint's listed version is a deprecated one (it has no active version): a new version takes its place
    moved = (select(q.c.version_id).where(q.c.joint_id == j.c.id, q.c.listed, q.c.newest_active == false())
             .correlate(j).exists())
    head = (select(j.c.id, j.c.joint_type, state.label("state"), moved.label("moved"), *[v.c[c] for c in _PREV])
            .select_from(j.outerjoin(v, and_(v.c.joint_id == j.c.id, v.c.version == latest_of_name)))
            .where(j.c.name == bindparam("name")))
    return SimpleNamespace(
        latest_of_joint=select(j.c.id).where(j.c.name == bindparam("name")),
        latest_row=(select(*[v.c[c] for c in _PREV]).where(v.c.joint_id == bindparam("jid"))
                    .order_by(v.c.version.desc()).limit(1)),
        idempotency=select(idem.c.request_sha256, idem.c.joint_name, idem.c.version, idem.c.status)
        .where(idem.c.owner == bindparam("owner"), idem.c.key == bindparam("key")),
        insert_idempotency=insert(idem),
        joint=select(j.c.id).where(j.c.name == bindparam("name")).with_for_update(),
        head=head,
        precheck=select(j.c.joint_type, latest_of_name).where(j.c.name == bindparam("name")),
        # the joint's other versions are no longer the newest (nor the newest active or listed one,
        # unless the new version is deprecated: then the newest active version stays what it was, and
        # stays listed; a listed version that is deprecated itself hands the head to the new one)
        clear_newest=update(q).where(q.c.joint_id == bindparam("jid"), q.c.newest).values(newest=False),
        clear_listed_deprecated=(update(q).where(q.c.joint_id == bindparam("jid"), q.c.listed,
                                                 q.c.newest_active == false()).values(listed=False)),
        clear_all=(update(q).where(q.c.joint_id == bindparam("jid"), or_(q.c.newest, q.c.newest_active, q.c.listed))
                   .values(newest=False, newest_active=False, listed=False)),
        insert_index=insert(q),
        # PostgreSQL: the new version's row id, taken before its INSERT (its index rows are sent with it)
        next_version_id=text("SELECT nextval(pg_get_serial_sequence('joint_versions', 'id'))"),
        insert_geometry=insert(QueryGeometryRow.__table__),
    )


#: the latest version's columns the identity check reads
_PREV = ("version", "materials", "preload_n", "torque_nm", "geometry", "extra", "model_kind", "dofs", "blob_sha256")
_TABLES = {"joint": JointRow, "version": VersionRow, "audit": AuditRow}


@functools.cache
def _insert(kind: str) -> object:
    return insert(_TABLES[kind].__table__)


@functools.cache
def _insert_returning(shape: tuple[tuple[str, tuple[str, ...]], ...]) -> object:
    """PostgreSQL: one statement inserting one row of each ``(kind, columns)`` of ``shape``, each in a
    data-modifying CTE ``rN`` that returns the row as stored (:func:`jointdb.store._chain.stored_columns`);
    the SELECT returns them side by side, as ``rN_<column>``. Parameters: ``rN_<column>``."""
    ctes = []
    for n, (kind, columns) in enumerate(shape):
        table = _TABLES[kind].__table__
        values = {c: bindparam(f"r{n}_{c}", type_=table.c[c].type) for c in columns}
        ctes.append(insert(table).values(values).returning(*stored_columns(kind, "postgresql")).cte(f"r{n}"))
    joined = ctes[0]
    for cte in ctes[1:]:
        joined = joined.join(cte, true())
    return select(*[c.label(f"r{n}_{c.name}") for n, cte in enumerate(ctes) for c in cte.c]).select_from(joined)


def _insert_history(conn, rows: list[tuple[str, dict]]) -> list[tuple]:
    """Insert history rows ``(kind, values)``; ``(kind, id, content hash)`` of each, for :func:`append_chain`.

    PostgreSQL: all in one statement (:func:`_insert_returning`), each row's hash taken from the row
    as stored that it returned. SQLite: one INSERT each and no hash (the chain reads the rows: SQLite
    returns a REAL column's integral value as an integer, before its affinity is applied, so a hash
    of the returned row would differ from the stored row's).
    """
    if conn.dialect.name != "postgresql":
        return [(kind, conn.execute(_insert(kind), values).inserted_primary_key[0], None) for kind, values in rows]
    shape, params = _history_params(rows)
    return _hashed(shape, conn.execute(_insert_returning(shape), params).one()._mapping)


def _history_params(rows: list[tuple[str, dict]]) -> tuple[tuple, dict]:
    """The shape and the parameters of :func:`_insert_returning` for history rows ``(kind, values)``."""
    shape = tuple((kind, tuple(sorted(values))) for kind, values in rows)
    return shape, {f"r{n}_{c}": v for n, (_, values) in enumerate(rows) for c, v in values.items()}


def _hashed(shape: tuple, stored) -> list[tuple]:
    """``(kind, id, content hash)`` of each row :func:`_insert_returning` returned (``stored``: a mapping)."""
    out = []
    for n, (kind, _) in enumerate(shape):
        prefix = f"r{n}_"
        row = {k[len(prefix):]: v for k, v in stored.items() if k.startswith(prefix)}
        out.append((kind, row["id"], content_hash(kind, row)))
    return out


def precheck(conn, name: str, joint_type: str, parent: int | None, new: dict | None = None,
             force: bool = False) -> None:
    """The conflicts :func:`write_version` would raise, checked before any blob is written
    (the write transaction checks them again: another writer may have come between).

    ``new``: the defining conditions of the version about to be written (see
    :func:`identity_of`); checked against the latest version unless ``force``.

    Raises
    ------
    ConflictError
        ``name`` exists with another joint type, ``parent`` is not one of its versions, or
        ``new`` contradicts the latest version.
    """
    st = _statements()
    row = conn.execute(st.precheck, {"name": name}).first()
    latest = None
    if row is not None:
        if row[0] != joint_type:
            raise ConflictError(f"joint {name!r} is a {row[0]} joint, not {joint_type}; use another name")
        latest = row[1]
    if parent is not None and (latest is None or parent > latest):
        raise ConflictError(f"parent version {parent} of joint {name!r} does not exist (latest is {latest or 'none'})")
    if latest is not None and new is not None and not force:
        jid = conn.execute(st.latest_of_joint, {"name": name}).scalar()
        prev = conn.execute(st.latest_row, {"jid": jid}).first()
        if prev is not None:
            changes, _ = identity_changes(prev, new)
            if changes:
                raise contradiction(name, prev.version, changes)


def identity_of(frf, cond, kind: str, blob: str) -> dict:
    """What :mod:`jointdb.store._identity` compares: the defining conditions and the content."""
    return {"materials": list(cond.materials), "preload_n": cond.preload_n, "torque_nm": cond.torque_nm,
            "geometry": dict(cond.geometry), "extra": dict(cond.extra), "model_kind": kind,
            "dofs": list(dof_strings(frf.outputs)), "blob_sha256": blob}


def idempotent_answer(conn, idempotency: tuple[str, str, str] | None) -> tuple[str, int, int] | None:
    """The stored answer ``(joint name, version, HTTP status)`` to an idempotency key, or None.

    Raises
    ------
    InputError
        The key was used by the same owner for another request.
    """
    if idempotency is None:
        return None
    owner, key, digest = idempotency
    row = conn.execute(_statements().idempotency, {"owner": owner, "key": key}).first()
    if row is None:
        return None
    if row[0] != digest:
        raise InputError(f"Idempotency-Key {key[:60]!r} was already used for another request (joint {row[1]!r} "
                         f"v{row[2]}); send a new key with a new request")
    return row[1], int(row[2]), int(row[3])


def write_version(session, *, name, joint_type, frf, cond, kind, prov, qual, parent, actor, label, blob, raw_blobs,
                  move_label, force=False, allow_identical=False, idempotency=None) -> SimpleNamespace:
    """Insert one new version (module docstring) in ``session``'s write transaction.

    ``move_label(session, joint, name, number, label, actor, now)`` points ``label`` at it
    (when given). The caller commits after the blob the row names is durable.

    Returns
    -------
    SimpleNamespace
        ``version`` (the new :class:`JointVersion`, or None when nothing was written),
        ``number`` and ``created`` (False: identical to the latest version, or an
        idempotency key's stored answer that was not a new version).

    Raises
    ------
    ConflictError
        ``name`` exists with another joint type, ``parent`` is not one of its versions, or the
        version contradicts the latest one (not ``force``).
    InputError
        ``idempotency``'s key was used for another request.
    """
    conn = session.connection()
    answer = idempotent_answer(conn, idempotency)
    if answer is not None:
        return SimpleNamespace(version=None, name=answer[0], number=answer[1], created=answer[2] == 201)
    now = utcnow()
    fast = pipelined(conn)  # PostgreSQL: the statements in batches, one round trip each (module docstring)
    head, next_id = _locked_head(conn, name, fast)
    history = []
    if head is None:
        history += _insert_history(conn, [("joint", {"name": name, "joint_type": joint_type, "created_at": now,
                                                     "created_by": actor})])
        jid, latest, state, moved = history[0][1], None, None, False
    else:
        jid, latest, state, moved = head.id, head.version, head.state, bool(head.moved)
        if head.joint_type != joint_type:
            raise ConflictError(f"joint {name!r} is a {head.joint_type} joint, not {joint_type}; use another name")
    if parent is not None and (latest is None or parent > latest):
        raise ConflictError(f"parent version {parent} of joint {name!r} does not exist (latest is {latest or 'none'})")
    details = {"blob_sha256": blob, "method": prov.method}
    if latest is not None:
        same = _same_joint(name, head, identity_of(frf, cond, kind, blob), force, allow_identical, details)
        if same is not None:
            _remember(conn, idempotency, name, same, 200, now)
            return SimpleNamespace(version=None, name=name, number=same, created=False)
    number = (latest or 0) + 1
    row = _version_row(name, joint_type, jid, number, now, actor, frf, cond, kind, prov, qual, blob, raw_blobs,
                       parent if parent is not None else latest)
    audit = {"at": now, "actor": actor, "action": "catalogue", "joint_name": name, "version": number,
             "details": details}
    deprecated = state == "deprecated"
    standing = (head is not None, moved, deprecated)
    if fast:
        row.id = next_id
        history += _write_rows_pipelined(session, conn, row, audit, (jid, name, joint_type), standing)
    else:
        history += _insert_history(conn, [("version", dict(vars(row))), ("audit", audit)])
        row.id = history[-2][1]
        for stmt, params in _index_plan(conn, row, (jid, name, joint_type), standing):
            conn.execute(stmt, params)
        bump(conn, [jid])  # the stamp and the query index's change log
    append_chain(session, history)
    _remember(conn, idempotency, name, number, 201, now)
    joint = SimpleNamespace(id=jid, name=name, joint_type=joint_type)
    labels: tuple[str, ...] = ()
    if label is not None:
        move_label(session, joint, name, number, label, actor, now)
        labels = (label,)
    # the record hash was just computed from this row: not computed again
    version = to_version(joint, row, labels=labels, verify=False)
    return SimpleNamespace(version=version, name=name, number=number, created=True)


def _version_row(name, joint_type, jid, number, now, actor, frf, cond, kind, prov, qual, blob, raw_blobs,
                 parent) -> SimpleNamespace:
    """The ``joint_versions`` row of a new version, its record hash included."""
    row = SimpleNamespace(
        joint_id=jid, version=number, uuid=str(uuidlib.uuid4()), created_at=now, author=actor,
        materials=list(cond.materials), preload_n=cond.preload_n, torque_nm=cond.torque_nm,
        geometry=dict(cond.geometry), extra=dict(cond.extra), model_kind=kind, dofs=list(dof_strings(frf.outputs)),
        quantity=frf.quantity.value, n_freq=frf.n_freq, freq_min_hz=float(frf.freq[0]),
        freq_max_hz=float(frf.freq[-1]), blob_sha256=blob, raw_blobs=raw_blobs, input_files=dict(prov.input_files),
        method=prov.method, method_params=dict(prov.parameters),
        software_version=prov.software_version or software_version(), parent_version=parent, quality=qual)
    row.record_sha256 = record_sha256(record_dict(name, joint_type, row))
    return row


def _index_plan(conn, row, joint: tuple[int, str, str], standing: tuple[bool, bool, bool]) -> list[tuple]:
    """The query index's statements ``(statement, parameters)`` for the new version ``row`` (its id set)
    of ``joint`` ``(id, name, type)``; ``standing``: ``(the joint existed, its listed version is
    deprecated, the new version is deprecated)``, as read under the joint row's lock."""
    st = _statements()
    jid, _, joint_type = joint
    found, moved, deprecated = standing
    plan = []
    if moved and deprecated:  # the deprecated listed version hands the head to the new (deprecated) one
        plan.append((st.clear_listed_deprecated, {"jid": jid}))
    if found:  # (clear_all also clears the listed flag of a deprecated listed version)
        plan.append((st.clear_newest if deprecated else st.clear_all, {"jid": jid}))
    counts = {}
    if not found:
        counts = {(joint_type, deprecated): 1}
    elif moved and not deprecated:
        counts = {(joint_type, True): -1, (joint_type, False): 1}
    plan += [(count_upsert(conn.dialect.name), params) for params in count_params(counts)]
    listed = not found or moved or not deprecated
    values, geometry = index_values(row.id, joint, row.version, row.materials, row.torque_nm, row.preload_n,
                                    row.geometry, (deprecated, True, not deprecated, listed))
    plan.append((st.insert_index, values))
    if geometry:
        plan.append((st.insert_geometry, geometry))
    return plan


def _write_rows_pipelined(session, conn, row, audit: dict, joint: tuple[int, str, str],
                          standing: tuple[bool, bool, bool]) -> list[tuple]:
    """PostgreSQL: the version and audit rows, the query index, the stamp, and the history chain's
    lock and head, in one round trip (:class:`~jointdb.store._pgpipe.Batch`); returns the history
    rows ``(kind, id, content hash)`` (hashed from the rows as stored) and notes the chain's head
    as held (:func:`~jointdb.store._chain.hold_head`): their entries go out with the commit."""
    batch = Batch(conn)
    shape, params = _history_params([("version", dict(vars(row))), ("audit", audit)])
    inserted = batch.add(_insert_returning(shape), params)
    for stmt, values in _index_plan(conn, row, joint, standing):
        batch.add(stmt, values)
    bumped = batch.add(bump_pg(), bump_params([joint[0]]))
    for stmt in lock_and_head():
        chain = batch.add(stmt)
    cursors = batch.run()
    prune(conn, int(cursors[bumped].fetchone()[0]))
    hold_head(session, *head_of(cursors[chain].fetchone()))
    return _hashed(shape, cursors[inserted].fetchone()._asdict())


def _locked_head(conn, name: str, fast: bool) -> tuple:
    """``(head, next version id)``: the joint's row (locked), its latest version's columns, whether
    its listed version is deprecated and the next version's state, or None for a new joint
    (module docstring, step 1); with ``fast`` (PostgreSQL, pipelined), the new version's row id
    too, all in one round trip, else None."""
    st = _statements()
    if fast:  # the lock, then the head in a statement of its own (its snapshot after the lock's grant)
        batch = Batch(conn)
        for stmt in (st.joint, st.head):
            batch.add(stmt, {"name": name})
        batch.add(st.next_version_id)
        locked, head, next_id = batch.run()
        found = locked.fetchone() is not None
        return (head.fetchone() if found else None), int(next_id.fetchone()[0])
    if conn.dialect.name == "postgresql" and conn.execute(st.joint, {"name": name}).first() is None:
        return None, None  # a new joint (a concurrent creator of the same name fails on the unique name)
    # after the lock: this statement's snapshot includes what the lock's previous holder committed
    return conn.execute(st.head, {"name": name}).first(), None


def _same_joint(name: str, prev, new: dict, force: bool, allow_identical: bool, details: dict) -> int | None:
    """Check the new version against the joint's latest one ``prev`` (read under the joint row's lock).

    Returns the latest version's number when the content is identical (nothing to write),
    else None; adds ``forced`` / ``filled_in`` to the audit ``details``.

    Raises
    ------
    ConflictError
        A defining condition contradicts the latest version and ``force`` is not given.
    """
    if not allow_identical and same_content(prev, new):
        return int(prev.version)
    changes, filled = identity_changes(prev, new)
    if changes and not force:
        raise contradiction(name, prev.version, changes)
    if changes:
        details["forced"] = [{**c, "of_version": int(prev.version)} for c in changes]
    if filled:
        details["filled_in"] = filled
    return None


def _remember(conn, idempotency, name: str, number: int, status: int, now) -> None:
    """Store the answer to an idempotency key (in the transaction of the version it names)."""
    if idempotency is not None:
        owner, key, digest = idempotency
        conn.execute(_statements().insert_idempotency, {"owner": owner, "key": key, "request_sha256": digest,
                                                        "joint_name": name, "version": number, "status": status,
                                                        "created_at": now})
