"""The query index: derived rows that let the nearest query rank without touching history.

Tables (migration ``0004``; models in :mod:`jointdb.store._models`):

``query_versions``  per version: joint (id and name), type, number, torque, preload,
                    materials (JSON text of the sorted list) and four flags of its current
                    standing: ``deprecated`` (the latest state row that applies to it says
                    so), ``newest`` (highest number of its joint), ``newest_active``
                    (highest number among the joint's versions that are not deprecated),
                    ``listed`` (the version :meth:`Repository.get` returns: the newest
                    active one, else the newest; exactly one per joint — the listing's head).
``query_geometry``  per version and geometry key: the number.
``query_counts``    per joint type and ``deprecated``: how many joints have their listed
                    version in that standing (the total of an unfiltered listing, read
                    instead of counted; migration ``0010``).
``query_stamp``     one row ``(token, generation)``; ``generation`` goes up in every
                    transaction that changes versions, states or labels, so a reader
                    can tell with one SELECT whether arrays it holds are still current.
``query_changes``   per such transaction its new generation and each joint it touched
                    (migration ``0011``; :func:`bump`), so that a reader holding the arrays
                    of an older generation refetches only those joints' rows. Pruned to the
                    last :data:`KEEP_GENERATIONS` generations; a gap means "refetch all".

The rows are written inside the same write transaction as the history rows they
derive from (:func:`refresh_joints`, :func:`bump`; a new version:
:mod:`jointdb.store._catalogue`), so a reader never sees one
without the other. They are derived state, not history: the immutability guards
of migrations ``0002``/``0003`` do not apply to them; :func:`index_problems`
(``jointdb db check``) recomputes them from history and reports any difference.
"""

from __future__ import annotations

import functools
import json
import struct
import uuid
from collections.abc import Iterable, Sequence
from typing import Any

from sqlalchemy import Connection, bindparam, delete, insert, inspect, select, text, update
from sqlalchemy.orm import Session

from jointdb.store._models import (
    JointRow,
    QueryChangeRow,
    QueryCountRow,
    QueryGeometryRow,
    QueryStampRow,
    QueryVersionRow,
    StateRow,
    VersionRow,
)


def materials_key(materials: Iterable[str]) -> str:
    """Canonical text of a material multiset (the JSON of the sorted list)."""
    return json.dumps(sorted(str(m) for m in materials or ()))


def standing(versions: Sequence[tuple[int, int]], states: Iterable[tuple[Any, int, int | None, str]]
             ) -> dict[int, tuple[bool, bool, bool, bool]]:
    """``{version_id: (deprecated, newest, newest_active, listed)}`` of one joint's versions.

    ``versions``: ``(version_id, number)``; ``states``: ``(at, state_id, version or None,
    state)``. A version's state is that of the latest row, by ``(at, id)``, that names it
    or the whole joint (as :func:`jointdb.store._records.state_of`); default active.
    """
    joint_wide = None
    per_version: dict[int, tuple] = {}
    for at, sid, number, state in states:
        key = (at, sid, state)
        if number is None:
            if joint_wide is None or key[:2] > joint_wide[:2]:
                joint_wide = key
        elif number not in per_version or key[:2] > per_version[number][:2]:
            per_version[number] = key
    deprecated: dict[int, bool] = {}
    for vid, number in versions:
        rows = [r for r in (joint_wide, per_version.get(number)) if r is not None]
        deprecated[vid] = bool(rows) and max(rows, key=lambda r: r[:2])[2] == "deprecated"
    newest = max((n for _, n in versions), default=None)
    active = [n for vid, n in versions if not deprecated[vid]]
    newest_active = max(active, default=None)
    listed = newest if newest_active is None else newest_active
    return {vid: (deprecated[vid], n == newest, n == newest_active, n == listed) for vid, n in versions}


#: ``query_versions.packed``: the numbers a ranking needs as little-endian bytes (NULL as -1.0;
#: stored conditions are >= 0), so that SQLite can hand over all candidates in one string.
PACKED = struct.Struct("<qqqdd")


def pack_row(version_id: int, joint_id: int, number: int, torque, preload) -> bytes:
    return PACKED.pack(version_id, joint_id, number, -1.0 if torque is None else float(torque),
                       -1.0 if preload is None else float(preload))


def geometry_row(key: str, version_id: int, value: float) -> dict:
    return {"key": key, "version_id": version_id, "value": value, "bits": struct.pack("<d", value)}


FLAGS = ("deprecated", "newest", "newest_active", "listed")


def index_values(version_id: int, joint: tuple[int, str, str], number: int, materials, torque, preload,
                 geometry: dict, flags: tuple[bool, bool, bool, bool]) -> tuple[dict, list[dict]]:
    """The ``query_versions`` row and ``query_geometry`` rows of one version.

    Parameters
    ----------
    version_id
        The version's row id.
    joint
        ``(id, name, joint_type)`` of its joint.
    number
        The version number.
    materials, torque, preload, geometry
        Its conditions (torque [N·m], preload [N], geometry numbers in SI units).
    flags
        ``(deprecated, newest, newest_active, listed)`` (:func:`standing`).

    Returns
    -------
    row : dict
        The ``query_versions`` row.
    geometry_rows : list of dict
        The ``query_geometry`` rows.
    """
    joint_id, name, joint_type = joint
    row = {"version_id": version_id, "joint_id": joint_id, "name": name, "joint_type": joint_type,
           "version": number, **dict(zip(FLAGS, flags)),
           "torque_nm": torque, "preload_n": preload, "materials": materials_key(materials),
           "packed": pack_row(version_id, joint_id, number, torque, preload)}
    geo = [geometry_row(str(k), version_id, float(x)) for k, x in (geometry or {}).items()]
    return row, geo


@functools.cache
def count_upsert(dialect: str):
    """The statement that adds ``joints`` to the ``query_counts`` row ``(joint_type, deprecated)``
    (parameters of those names; inserted when missing: ``ON CONFLICT DO UPDATE``), per dialect."""
    t = QueryCountRow.__table__
    if dialect == "postgresql":
        from sqlalchemy.dialects.postgresql import insert as upsert
    else:
        from sqlalchemy.dialects.sqlite import insert as upsert
    stmt = upsert(t).values(joint_type=bindparam("joint_type"), deprecated=bindparam("deprecated"),
                            joints=bindparam("joints"))
    return stmt.on_conflict_do_update(index_elements=[t.c.joint_type, t.c.deprecated],
                                      set_={"joints": t.c.joints + stmt.excluded.joints})


def count_params(deltas: dict[tuple[str, bool], int]) -> list[dict]:
    """The parameters of :func:`count_upsert`, one dict per changed row, for ``{(joint_type, deprecated):
    change}`` (in a fixed order: two writers lock the rows in the same order)."""
    return [{"joint_type": joint_type, "deprecated": bool(deprecated), "joints": change}
            for (joint_type, deprecated), change in sorted(deltas.items()) if change]


def add_counts(session: Session | Connection, deltas: dict[tuple[str, bool], int]) -> None:
    """Add ``{(joint_type, deprecated): change}`` to ``query_counts`` (in the caller's write
    transaction). One upsert per changed row: two writers adding the first joints of a new type
    at once do not collide on the missing row (PostgreSQL and SQLite ``ON CONFLICT DO UPDATE``)."""
    conn = session.connection() if isinstance(session, Session) else session
    for params in count_params(deltas):
        conn.execute(count_upsert(conn.dialect.name), params)


def _count_changes(joint_type: str, before: Iterable[tuple], after: Iterable[tuple]) -> dict[tuple[str, bool], int]:
    """The ``query_counts`` changes between two sets of flags ``(deprecated, ..., listed)``."""
    deltas: dict[tuple[str, bool], int] = {}
    for sign, flags in ((-1, before), (1, after)):
        for f in flags:
            if f[3]:
                deltas[(joint_type, bool(f[0]))] = deltas.get((joint_type, bool(f[0])), 0) + sign
    return deltas


#: generations the change log keeps (older ones are pruned every :data:`PRUNE_EVERY` generations)
KEEP_GENERATIONS = 4096
PRUNE_EVERY = 256


def bump(session: Session | Connection, joint_ids: Iterable[int] | None = None) -> int:
    """Increase the query stamp's generation and log the joints changed (in the caller's write transaction).

    Every write that changes what a nearest query can return calls this once, where it bumps
    the stamp: a new version, a state, a label, an import.

    Parameters
    ----------
    session
        The write transaction.
    joint_ids
        The joints whose index rows or labels it changed; None (or none given): any joint may
        have changed, and readers refetch everything.

    Returns
    -------
    int
        The new generation.
    """
    t, c = QueryStampRow.__table__, QueryChangeRow.__table__
    conn = session.connection() if isinstance(session, Session) else session
    if conn.dialect.name == "postgresql":  # one round trip: the stamp and the log in one statement
        generation = int(conn.execute(bump_pg(), bump_params(joint_ids)).first()[0])
    else:
        generation = int(conn.execute(update(t).where(t.c.id == 1).values(generation=t.c.generation + 1)
                                      .returning(t.c.generation)).scalar_one())
        conn.execute(insert(c), [{"generation": generation, "joint_id": j} for j in bump_params(joint_ids)["ids"]])
    prune(conn, generation)
    return generation


@functools.cache
def bump_pg():
    """PostgreSQL: :func:`bump` in one statement (parameter ``ids``: :func:`bump_params`), which
    returns the new generation (then :func:`prune`)."""
    return text("WITH s AS (UPDATE query_stamp SET generation = generation + 1 WHERE id = 1 RETURNING generation) "
                "INSERT INTO query_changes (generation, joint_id) SELECT s.generation, j "
                "FROM s, unnest(CAST(:ids AS integer[])) AS j RETURNING generation")


def bump_params(joint_ids: Iterable[int] | None) -> dict:
    """The parameters of :func:`bump_pg` (no joints: one NULL entry, "refetch everything")."""
    ids = sorted({int(j) for j in joint_ids}) if joint_ids is not None else []
    return {"ids": ids or [None]}


def prune(conn: Connection, generation: int) -> None:
    """Every :data:`PRUNE_EVERY` generations, drop the change log older than :data:`KEEP_GENERATIONS`."""
    if generation % PRUNE_EVERY == 0:
        c = QueryChangeRow.__table__
        conn.execute(delete(c).where(c.c.generation <= generation - KEEP_GENERATIONS))


def refresh_joints(session: Session, joint_ids: Iterable[int]) -> None:
    """Bring the index rows of these joints up to date with their history, and :func:`bump`.

    Rows of versions not yet indexed are inserted; the standing flags of all the
    joints' versions are recomputed and the changed ones updated. Call after the
    history rows were added and flushed, in the same transaction.
    """
    joint_ids = sorted(set(joint_ids))
    for joint_id in joint_ids:
        name, joint_type = session.execute(select(JointRow.name, JointRow.joint_type)
                                           .where(JointRow.id == joint_id)).one()
        versions = [tuple(r) for r in session.execute(select(VersionRow.id, VersionRow.version)
                                                      .where(VersionRow.joint_id == joint_id))]
        states = [tuple(r) for r in session.execute(select(StateRow.at, StateRow.id, StateRow.version, StateRow.state)
                                                    .where(StateRow.joint_id == joint_id))]
        flags = standing(versions, states)
        have = {row[0]: tuple(bool(x) for x in row[1:]) for row in session.execute(
            select(QueryVersionRow.version_id, *[getattr(QueryVersionRow, f) for f in FLAGS])
            .where(QueryVersionRow.joint_id == joint_id))}
        missing = [vid for vid, _ in versions if vid not in have]
        if missing:
            new_rows, new_geo = [], []
            for vid, number, mats, torque, preload, geometry in session.execute(
                    select(VersionRow.id, VersionRow.version, VersionRow.materials, VersionRow.torque_nm,
                           VersionRow.preload_n, VersionRow.geometry).where(VersionRow.id.in_(missing))):
                row, geo = index_values(vid, (joint_id, name, joint_type), number, mats, torque, preload, geometry,
                                        flags[vid])
                new_rows.append(row)
                new_geo.extend(geo)
            session.execute(insert(QueryVersionRow), new_rows)
            if new_geo:
                session.execute(insert(QueryGeometryRow), new_geo)
        for vid, f in flags.items():
            if vid in have and have[vid] != f:
                session.execute(update(QueryVersionRow).where(QueryVersionRow.version_id == vid)
                                .values(**dict(zip(FLAGS, f))))
        add_counts(session, _count_changes(joint_type, have.values(), flags.values()))
    bump(session, joint_ids)


def _expected(conn: Connection) -> tuple[dict[int, dict], set[tuple[str, int, float]]]:
    """Every index row as recomputed from the history tables."""
    joints = {r[0]: (r[0], r[1], r[2]) for r in conn.execute(select(JointRow.id, JointRow.name, JointRow.joint_type))}
    per_joint: dict[int, list] = {}
    for vid, jid, number, mats, torque, preload, geometry in conn.execute(
            select(VersionRow.id, VersionRow.joint_id, VersionRow.version, VersionRow.materials,
                   VersionRow.torque_nm, VersionRow.preload_n, VersionRow.geometry)):
        per_joint.setdefault(jid, []).append((vid, number, mats, torque, preload, geometry))
    states: dict[int, list] = {}
    for at, sid, jid, number, state in conn.execute(
            select(StateRow.at, StateRow.id, StateRow.joint_id, StateRow.version, StateRow.state)):
        states.setdefault(jid, []).append((at, sid, number, state))
    rows: dict[int, dict] = {}
    geo: set[tuple[str, int, float]] = set()
    for jid, vs in per_joint.items():
        flags = standing([(v[0], v[1]) for v in vs], states.get(jid, ()))
        for vid, number, mats, torque, preload, geometry in vs:
            row, g = index_values(vid, joints[jid], number, mats, torque, preload, geometry, flags[vid])
            rows[vid] = row
            geo.update((x["key"], x["version_id"], x["value"]) for x in g)
    return rows, geo


def rebuild(conn: Connection) -> int:
    """Rewrite the whole index from history (migration ``0004``); returns the number of versions.

    Only the columns the table has at the caller's schema revision are written (migration
    ``0004`` runs before ``0010`` adds ``listed`` and ``name``, which ``0010`` then fills)."""
    rows, geo = _expected(conn)
    conn.execute(delete(QueryGeometryRow))
    conn.execute(delete(QueryVersionRow))
    present = {c["name"] for c in inspect(conn).get_columns(QueryVersionRow.__tablename__)}
    ordered = [{c: x for c, x in rows[vid].items() if c in present} for vid in sorted(rows)]
    for i in range(0, len(ordered), 5000):
        conn.execute(insert(QueryVersionRow), ordered[i:i + 5000])
    g = [geometry_row(k, v, x) for k, v, x in sorted(geo)]
    for i in range(0, len(g), 5000):
        conn.execute(insert(QueryGeometryRow), g[i:i + 5000])
    if inspect(conn).has_table(QueryCountRow.__tablename__):
        conn.execute(delete(QueryCountRow))
        add_counts(conn, _expected_counts(rows))
    if conn.execute(select(QueryStampRow.id)).first() is None:
        conn.execute(insert(QueryStampRow), [{"id": 1, "token": str(uuid.uuid4()), "generation": 0}])
    else:  # no change-log entry: a gap, so that readers refetch everything
        t = QueryStampRow.__table__
        conn.execute(update(t).where(t.c.id == 1).values(generation=t.c.generation + 1))
    return len(rows)


def _expected_counts(rows: dict[int, dict]) -> dict[tuple[str, bool], int]:
    counts: dict[tuple[str, bool], int] = {}
    for row in rows.values():
        if row["listed"]:
            key = (row["joint_type"], bool(row["deprecated"]))
            counts[key] = counts.get(key, 0) + 1
    return counts


def index_problems(conn: Connection) -> list[str]:
    """Differences between the query index and the history it derives from (``db check``)."""
    rows, geo = _expected(conn)
    cols = [c.name for c in QueryVersionRow.__table__.columns]
    have = {r.version_id: {c: getattr(r, c) for c in cols} for r in conn.execute(select(QueryVersionRow))}
    problems: list[str] = []
    if conn.execute(select(QueryStampRow.id).where(QueryStampRow.id == 1)).first() is None:
        problems.append("query index: the query_stamp row is missing")
    for vid in sorted(set(rows) | set(have)):
        want, got = rows.get(vid), have.get(vid)
        if got is not None:
            got = {k: (bool(v) if k in FLAGS else v) for k, v in got.items()}
        if want != got:
            problems.append(f"query index: row of version id {vid} differs from history "
                            f"(expected {want}, found {got})")
            if len(problems) >= 10:
                break
    have_geo = {tuple(r) for r in conn.execute(select(QueryGeometryRow.key, QueryGeometryRow.version_id,
                                                      QueryGeometryRow.value))}
    if have_geo != geo:
        problems.append(f"query index: {len(geo ^ have_geo)} geometry rows differ from history")
    counts = {(t, bool(d)): n for t, d, n in conn.execute(select(QueryCountRow.joint_type, QueryCountRow.deprecated,
                                                                 QueryCountRow.joints)) if n}
    if counts != _expected_counts(rows):
        problems.append(f"query index: the listing's counts {counts} differ from history "
                        f"({_expected_counts(rows)})")
    return problems
