"""Nearest-joint ranking over the query index, on a plain DB-API connection.

No SQLAlchemy here: ``jointdb query`` on a SQLite file runs this on a
``sqlite3`` connection (fast start), :meth:`Repository.nearest` on a raw
connection of its engine (SQLite or PostgreSQL). The distance is defined in
:mod:`jointdb.store._query`.

Which versions rank (:class:`Selection`): the versions of the joint type,
without the deprecated ones unless ``include_deprecated``, only those carrying
``label`` if given; then, unless ``all_versions``, of each joint only the
newest of those left. The default is therefore each joint's newest version that
is not deprecated. Each such set is one SELECT on ``query_versions`` (see
:mod:`jointdb.store._index`) with the requested geometry keys joined in, fetched
whole into numpy arrays (on SQLite as one row of concatenated packed columns,
so that no Python object is made per candidate).

Cache: the arrays of a selection are kept per process (not per Repository)
and in a per-user cache file (:mod:`jointdb.store._qcache`), keyed by database
and selection, and reused while the index's stamp
``(token, generation)`` — one single-row SELECT — is unchanged. Stamp, arrays,
geometry and the winners' records are read in one read transaction (SQLite:
one snapshot; PostgreSQL: ``REPEATABLE READ``).
"""

from __future__ import annotations

import contextlib
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from datetime import datetime, timezone
from types import SimpleNamespace
from typing import Any

import numpy as np

from jointdb.errors import InputError, IntegrityError, NotFoundError
from jointdb.store._candidates import _NULL, Candidates, canonical_materials
from jointdb.store._rank import rank
from jointdb.store._records import DamagedRecordWarning, load_stored_json, to_version
from jointdb.store._types import Conditions, Match, as_conditions, check_joint_type, check_label

_CACHE_MAX = 32


class OutsideCatalogueWarning(UserWarning):
    """A nearest-joint request lies outside the catalogued range of some condition."""


class UnvariedConditionWarning(UserWarning):
    """A note: the request names a condition the catalogue never varied for that joint type (one value only),
    and it describes the machine the joint was identified on rather than the joint (:data:`MACHINE_CONDITIONS`);
    the joints are used at the requested value, since no data show a dependence on it."""


#: Conditions of a joint type that record the machine its campaign ran on, not the joint itself: a tool–holder
#: joint identified on a spindle at one drawbar force (``preload_n``) is used at another with a note, not an
#: extrapolation warning, while the catalogue holds that joint type at a single value of it.
MACHINE_CONDITIONS = {"tool-holder": ("preload_n",)}


@dataclass(frozen=True)
class Selection:
    """Which versions of ``joint_type`` rank (module docstring)."""

    joint_type: str
    label: str | None = None
    all_versions: bool = False
    include_deprecated: bool = False

    def where(self) -> tuple[str, str, list[Any]]:
        """``(join, where, params)`` on ``query_versions q`` (``?`` placeholders)."""
        join, conds, params = "", ["q.joint_type = ?"], [self.joint_type]
        if self.label is not None:
            join = " JOIN labels l ON l.joint_id = q.joint_id AND l.version = q.version AND l.label = ?"
            params.insert(0, self.label)
            if not self.include_deprecated:
                conds.append("NOT q.deprecated")
        elif self.all_versions:
            if not self.include_deprecated:
                conds.append("NOT q.deprecated")
        else:
            conds.append("q.newest" if self.include_deprecated else "q.newest_active")
        return join, " AND ".join(conds), params

    def describe(self) -> str:
        what = "versions" if self.all_versions else "newest versions"
        parts = [f"{what} of {self.joint_type} joints"]
        if self.label is not None:
            parts.append(f"labelled {self.label!r}")
        parts.append("including deprecated ones" if self.include_deprecated else "not deprecated")
        return ", ".join(parts)


# ----------------------------------------------------------------------------- connection
class Reader:
    """A DB-API connection (``sqlite3`` or psycopg) with ``?`` placeholders and a read transaction."""

    def __init__(self, dbapi_conn, dialect: str):
        self.conn = dbapi_conn
        self.dialect = dialect

    def rows(self, sql: str, params=()) -> list[tuple]:
        if self.dialect != "sqlite":
            sql = sql.replace("?", "%s")
        cur = self.conn.cursor()
        try:
            cur.execute(sql, tuple(params))
            return cur.fetchall() if cur.description is not None else []
        finally:
            cur.close()

    @contextlib.contextmanager
    def snapshot(self):
        """One read transaction (SQLite: deferred BEGIN; PostgreSQL: REPEATABLE READ, read only)."""
        if self.dialect == "sqlite":
            self.rows("BEGIN")
        else:
            self.conn.rollback()  # a fresh transaction: SET TRANSACTION must come first in it
            self.rows("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ READ ONLY")
        try:
            yield self
        finally:
            if self.dialect == "sqlite":
                self.rows("COMMIT")
            else:
                self.conn.rollback()


_cache: dict[tuple, tuple[tuple, Candidates]] = {}

#: PostgreSQL ``work_mem`` of the query's read transaction (``SET LOCAL``): the join of a million-version
#: index with a geometry key hashes ~500k rows, which spills to disk at the default 4 MB
WORK_MEM = "64MB"
#: the incremental update reads at most this many generations / changed joints; beyond, it refetches all
MAX_STEPS = 2000
MAX_CHANGED_JOINTS = 5000


#: ``query_versions.packed`` (see :data:`jointdb.store._index.PACKED`) and -1.0 as float64 bytes
_PACKED = np.dtype([("version_id", "<i8"), ("joint_id", "<i8"), ("number", "<i8"), ("torque", "<f8"),
                    ("preload", "<f8")])
_NULL_BITS = "000000000000F0BF"


def _restrict(sel: Selection, joint_ids, dialect: str) -> tuple[str, str, list, list]:
    """``(join, where, join_params, where_params)`` of ``sel``, limited to ``joint_ids`` unless None."""
    join, where, params = sel.where()
    head, tail = params[:-1], params[-1:]
    if joint_ids is not None:
        if dialect == "sqlite":
            where += f" AND q.joint_id IN ({', '.join('?' for _ in joint_ids)})"
            tail += [int(j) for j in joint_ids]
        else:
            where += " AND q.joint_id = ANY(?)"
            tail.append([int(j) for j in joint_ids])
    return join, where, head, tail


def _packed_row(reader: Reader, sel: Selection, geometry_keys: list[str], raw: bool,
                joint_ids=None) -> tuple[int, list[bytes], str]:
    """``(count, [packed bytes, geometry bytes per key], materials text)`` of ``sel`` in one SELECT.

    ``raw``: the binary columns concatenated as they are (SQLite: ``group_concat`` treats a
    BLOB as text of the same bytes in a UTF-8 database, embedded NULs included, and the CAST
    hands the result over as bytes; PostgreSQL: ``string_agg`` of ``bytea``); otherwise as hex
    text (SQLite, any database encoding). All aggregates of one SELECT visit the rows in the
    same order.
    """
    join, where, head, tail = _restrict(sel, joint_ids, reader.dialect)
    n_geo = range(len(geometry_keys))
    if reader.dialect != "sqlite":
        packed = "string_agg(q.packed, ''::bytea)"
        geo = [f"string_agg(coalesce(g{i}.bits, '\\x{_NULL_BITS}'::bytea), ''::bytea)" for i in n_geo]
        mats = "string_agg(q.materials, chr(30))"
    elif raw:
        col = "CAST(group_concat({}, '') AS BLOB)"
        packed, geo = col.format("q.packed"), [col.format(f"coalesce(g{i}.bits, x'{_NULL_BITS}')") for i in n_geo]
        mats = "group_concat(q.materials, char(30))"
    else:
        packed = "group_concat(hex(q.packed), '')"
        geo = [f"group_concat(CASE WHEN g{i}.bits IS NULL THEN '{_NULL_BITS}' ELSE hex(g{i}.bits) END, '')"
               for i in n_geo]
        mats = "group_concat(q.materials, char(30))"
    geo_join = "".join(f" LEFT JOIN query_geometry g{i} ON g{i}.key = ? AND g{i}.version_id = q.version_id"
                       for i in n_geo)
    row = reader.rows(f"SELECT count(*), {packed}, {mats}{''.join(', ' + g for g in geo)} "
                      f"FROM query_versions q{join}{geo_join} WHERE {where}", [*head, *geometry_keys, *tail])[0]
    binary = [bytes(b) if raw else bytes.fromhex(b) for b in (row[1], *row[3:])] if row[0] else []
    return int(row[0]), binary, row[2]


def _fetch(reader: Reader, sel: Selection, geometry_keys: list[str], joint_ids=None) -> Candidates:
    """The candidates of ``sel`` (only of ``joint_ids`` unless None) with the given geometry keys,
    as one row of concatenated binary columns (no Python object per candidate)."""
    if reader.dialect != "sqlite":
        reader.rows(f"SET LOCAL work_mem = '{WORK_MEM}'")  # this read transaction only
    raw = True
    n, binary, materials = _packed_row(reader, sel, geometry_keys, raw, joint_ids)
    if n and any(len(b) != size * n for b, size in zip(binary, [_PACKED.itemsize] + [8] * len(geometry_keys))):
        if reader.dialect == "sqlite":  # e.g. a UTF-16 database
            n, binary, materials = _packed_row(reader, sel, geometry_keys, False, joint_ids)
    if n == 0:
        return Candidates.from_rows([], geometry_keys)
    rec = np.frombuffer(binary[0], dtype=_PACKED) if len(binary[0]) == _PACKED.itemsize * n else None
    mats = materials.split("\x1e")  # JSON text escapes control characters: no material contains one
    if rec is None or len(mats) != n or any(len(b) != 8 * n for b in binary[1:]):
        raise IntegrityError("query index: packed candidate columns do not line up; run `jointdb db check`")
    order = np.argsort(rec["version_id"], kind="stable")
    keys: dict[str, int] = {}
    idx = np.array([keys.setdefault(m, len(keys)) for m in mats], dtype=np.intp)
    texts, idx = canonical_materials(list(keys), idx[order])

    def nums(a):
        a = np.array(a[order], dtype=float)
        a[a < 0] = np.nan
        return a
    geometry = {g: nums(np.frombuffer(b, dtype="<f8")) for g, b in zip(geometry_keys, binary[1:])}
    return Candidates(rec["version_id"][order].copy(), rec["joint_id"][order].copy(), rec["number"][order].copy(),
                      nums(rec["torque"]), nums(rec["preload"]), texts, idx, geometry)


def _fetch_geometry(reader: Reader, sel: Selection, key: str, cand: Candidates) -> np.ndarray:
    join, where, params = sel.where()
    pairs = reader.rows(f"SELECT g.version_id, g.value FROM query_geometry g JOIN query_versions q "
                        f"ON q.version_id = g.version_id{join} WHERE g.key = ? AND {where}",
                        [*params[:-1], key, params[-1]] if join else [key, *params])
    return cand.align(pairs)


def _changed_joints(reader: Reader, since: int, now: int) -> list[int] | None:
    """The joints changed after generation ``since`` up to ``now`` (the change log, migration
    ``0011``), or None when the log cannot say: too many steps or joints, a generation missing
    (pruned, or written without a log entry such as a rebuild) or one that changed any joint."""
    if not 0 <= since < now or now - since > MAX_STEPS:
        return None
    rows = reader.rows("SELECT generation, joint_id FROM query_changes WHERE generation > ? AND generation <= ?",
                       [since, now])
    if {int(g) for g, _ in rows} != set(range(since + 1, now + 1)) or any(j is None for _, j in rows):
        return None
    joints = sorted({int(j) for _, j in rows})
    return joints if len(joints) <= MAX_CHANGED_JOINTS else None


def _updated(reader: Reader, sel: Selection, base: tuple[tuple, Candidates] | None, stamp: tuple
             ) -> Candidates | None:
    """``base`` (arrays of an older generation of the same token) brought up to ``stamp`` by
    refetching only the rows of the joints changed since, or None (then fetch everything)."""
    if base is None or base[0][0] != stamp[0]:
        return None
    joints = _changed_joints(reader, int(base[0][1]), int(stamp[1]))
    if joints is None:
        return None
    keys = list(base[1].geometry)
    return base[1].replace_joints(joints, _fetch(reader, sel, keys, joints) if joints else None)


def current_candidates(reader: Reader, db_key: str, sel: Selection, geometry_keys) -> Candidates:
    """The candidates of ``sel`` now (call in a snapshot).

    In order: this process's cache, or the on-disk cache (:mod:`jointdb.store._qcache`), when
    its stamp is the current one; else the newest older arrays of either, updated with the rows
    of the joints changed since (the change log); else everything from the index. A
    selection's rows of a joint depend only on that joint's versions, states and labels, so
    replacing the changed joints' rows gives exactly the arrays a full fetch gives.
    """
    from jointdb.store import _qcache

    stamp = tuple(reader.rows("SELECT token, generation FROM query_stamp WHERE id = 1")[0])
    key = (db_key, sel)
    hit = _cache.get(key)
    keys = list(geometry_keys)
    if hit is None or hit[0] != stamp:
        if len(_cache) >= _CACHE_MAX:
            _cache.clear()
        cand = _qcache.load(db_key, stamp, sel)
        if cand is None:
            older = hit if hit is not None and hit[0][0] == stamp[0] and hit[0][1] < stamp[1] else None
            cand = _updated(reader, sel, older or _qcache.load_older(db_key, stamp, sel), stamp)
            if cand is None:
                cand = _fetch(reader, sel, keys)
            _qcache.save(db_key, stamp, sel, cand)
        hit = (stamp, cand)
        _cache[key] = hit
    cand = hit[1]
    missing = [g for g in keys if g not in cand.geometry]
    for g in missing:
        cand.geometry[g] = _fetch_geometry(reader, sel, g, cand)
    if missing:
        _qcache.save(db_key, stamp, sel, cand)
    return cand


# ----------------------------------------------------------------------------- records
_JSON_COLUMNS = ("materials", "geometry", "extra", "dofs", "raw_blobs", "input_files", "method_params", "quality")
_VERSION_COLUMNS = ("id", "joint_id", "version", "uuid", "created_at", "author", "materials", "preload_n",
                    "torque_nm", "geometry", "extra", "model_kind", "dofs", "quantity", "n_freq", "freq_min_hz",
                    "freq_max_hz", "blob_sha256", "raw_blobs", "input_files", "method", "method_params",
                    "software_version", "parent_version", "quality", "record_sha256")


def _utc(value) -> datetime:
    if isinstance(value, str):  # SQLite: naive UTC text
        value = datetime.fromisoformat(value)
    return value.replace(tzinfo=timezone.utc) if value.tzinfo is None else value.astimezone(timezone.utc)


def fetch_versions(reader: Reader, version_ids: list[int], states: Mapping[int, str] | None = None) -> dict:
    """``{version_id: JointVersion}`` (record hash verified), with labels and the current state
    from the index unless ``states`` gives them."""
    if not version_ids:
        return {}
    marks = ", ".join("?" for _ in version_ids)
    cols = ", ".join(f"v.{c}" for c in _VERSION_COLUMNS)
    agg = "group_concat(l.label, ',')" if reader.dialect == "sqlite" else "string_agg(l.label, ',')"
    rows = reader.rows(f"SELECT j.name, j.joint_type, q.deprecated, (SELECT {agg} FROM labels l WHERE l.joint_id = "
                       f"v.joint_id AND l.version = v.version), {cols} FROM joint_versions v "
                       f"JOIN joints j ON j.id = v.joint_id LEFT JOIN query_versions q ON q.version_id = v.id "
                       f"WHERE v.id IN ({marks})", version_ids)
    labels = {(r[5], r[6]): r[3].split(",") for r in rows if r[3]}  # labels are [A-Za-z0-9._-]: no comma
    rows = [(*r[:3], *r[4:]) for r in rows]
    out, damaged = {}, []
    for name, joint_type, deprecated, *values in rows:
        row = SimpleNamespace(**dict(zip(_VERSION_COLUMNS, values)))
        for c in _JSON_COLUMNS:
            if isinstance(getattr(row, c), (str, bytes)):
                setattr(row, c, load_stored_json(getattr(row, c)))
        joint = SimpleNamespace(name=name, joint_type=joint_type, id=row.joint_id)
        state = states[row.id] if states is not None else ("deprecated" if deprecated else "active")
        try:
            row.created_at = _utc(row.created_at)
            out[row.id] = to_version(joint, row, state, labels.get((row.joint_id, row.version), ()))
        except (IntegrityError, TypeError, ValueError) as exc:  # a damaged row: skipped and named, not fatal
            damaged.append(f"{name} v{row.version}: {str(exc).split(': ', 1)[-1]}")
    if damaged:
        warnings.warn("skipped damaged versions (run `jointdb db check`): " + "; ".join(damaged[:10]),
                      DamagedRecordWarning, stacklevel=3)
    return out


def unvaried_machine_conditions(joint_type: str, cand: Candidates, outside: list[str]) -> list[tuple[str, float]]:
    """``(name, the one catalogued value)`` of the conditions in ``outside`` that describe the machine
    (:data:`MACHINE_CONDITIONS`) and that the candidates hold at a single value: a note, not an extrapolation."""
    out = []
    for name in [n for n in outside if n in MACHINE_CONDITIONS.get(joint_type, ())]:
        column = {"preload_n": cand.preload, "torque_nm": cand.torque}[name]
        values = np.unique(column[np.isfinite(column)])
        if values.size == 1:
            out.append((name, float(values[0])))
    return out


def matches(reader: Reader, cand: Candidates, req: Conditions, k: int, sel: Selection,
            states: Mapping[int, str] | None = None, stacklevel: int = 3) -> list[Match]:
    """Rank ``cand`` and build the :class:`Match` list (warns when extrapolating)."""
    order, total, terms, outside = rank(cand, req, k)
    for name, value in unvaried_machine_conditions(sel.joint_type, cand, outside):
        outside.remove(name)
        warnings.warn(f"{sel.joint_type} joints are catalogued at one {name} only ({value:g}); they are "
                      f"used at the requested {getattr(req, name):g} (no data show a dependence on it)",
                      UnvariedConditionWarning, stacklevel=stacklevel)
    if outside:
        warnings.warn(
            f"request lies outside the catalogued range of {sel.joint_type} joints for: {', '.join(outside)}; "
            "the nearest catalogued joints (the edge) are used, nothing is extrapolated",
            OutsideCatalogueWarning,
            stacklevel=stacklevel,
        )
    found = fetch_versions(reader, [int(cand.version_id[i]) for i in order], states)
    return [Match(version=found[int(cand.version_id[i])], distance=float(total[i]),
                  per_condition={name: float(t[i]) for name, t in terms.items()},
                  extrapolating=bool(outside), outside_range=tuple(outside)) for i in order
            if int(cand.version_id[i]) in found]  # damaged versions are skipped (and warned about)


def check_request(joint_type: str, conditions, k: int, label: str | None) -> tuple[str, Conditions, int, str | None]:
    """Validated ``(joint_type, conditions, k, label)``.

    Raises
    ------
    InputError
        ``k < 1``, bad conditions, type or label.
    """
    joint_type = check_joint_type(joint_type)
    req = as_conditions(conditions)
    if isinstance(k, bool) or int(k) < 1:
        raise InputError(f"k must be >= 1, got {k!r}")
    return joint_type, req, int(k), (check_label(label) if label is not None else None)


def not_found(reader: Reader, sel: Selection) -> NotFoundError:
    types = sorted({r[0] for r in reader.rows("SELECT DISTINCT joint_type FROM joints")})
    among = "" if sel == Selection(sel.joint_type) else f" among the {sel.describe()}"
    return NotFoundError(f"no current catalogued joint of type {sel.joint_type!r}{among}; types in the catalogue: "
                         f"{', '.join(types) or 'none'} (joint types are never mixed)")


def nearest_now(reader: Reader, db_key: str, joint_type: str, conditions, k: int = 3, *, label: str | None = None,
                all_versions: bool = False, include_deprecated: bool = False, stacklevel: int = 3) -> list[Match]:
    """The ``k`` versions of the selection closest to ``conditions``, as the catalogue is now.

    Raises
    ------
    InputError
        Bad request (:func:`check_request`).
    NotFoundError
        Nothing in the selection.
    """
    joint_type, req, k, label = check_request(joint_type, conditions, k, label)
    sel = Selection(joint_type, label, bool(all_versions), bool(include_deprecated))
    with reader.snapshot():
        cand = current_candidates(reader, db_key, sel, list(req.geometry))
        if cand.version_id.size == 0:
            raise not_found(reader, sel)
        return matches(reader, cand, req, k, sel, stacklevel=stacklevel + 1)


