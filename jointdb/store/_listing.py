"""Listing the catalogue in SQL: one SELECT per page, filtered on the query index, keyset-paginated.

Which version of a joint is listed
----------------------------------
By default each joint's *current* version, as :meth:`Repository.get` returns it: the newest
version that is not deprecated, or the newest one when all are — the query index's maintained
head, ``query_versions.listed`` (:mod:`jointdb.store._index`, migration ``0010``).
``include_deprecated=False`` lists only joints with a version that is not deprecated; ``state``
keeps only active or only deprecated listed versions; ``label`` lists instead the version that
carries that label.

Cost of a page
--------------
Pages are ordered by name. A page is one SELECT that reads one range of the index
``(listed, name)`` — ``(joint_type, listed, name)`` with a type — from the cursor on, and
stops after ``limit + 1`` rows: its cost is the page's, not the catalogue's. Filters on the
index's other typed columns (materials: all given must be present; torque and preload ranges:
a joint without the value is left out when a bound is given; part of the name,
case-insensitive; state) are tested on the rows of that range, so a selective filter reads
more of it. ``after`` (the ``next`` cursor of the previous page) continues after a name;
``offset`` skips rows (and costs them).

The total
---------
``JointPage.total`` is the number of matches when the listing started. Without a filter, or
with only a joint type, ``state`` or ``include_deprecated``, it is read from the maintained
counts (``query_counts``: one row per type and standing), not counted. With any other filter it
is counted — once, on the first page — and carried in the ``next`` cursor, so later pages
do not count again (a page asked for by ``offset`` counts again). The total is a subquery of
the page's statement: one statement per page in every case.

A row that cannot be used (damaged JSON, a record hash that does not match, a stored field
beyond today's limits) does not stop the list: it is reported in :attr:`JointPage.damaged`
with the joint's name and version.
"""

from __future__ import annotations

import base64
import binascii
import json
import math
import threading
from collections.abc import Iterable
from dataclasses import dataclass
from types import SimpleNamespace

from sqlalchemy import Text, exists, false, func, literal, select, true, type_coerce
from sqlalchemy.orm import aliased

from jointdb.schemas._limits import control_character
from jointdb.errors import InputError, IntegrityError
from jointdb.store._models import LabelRow, QueryCountRow, QueryStampRow, QueryVersionRow, VersionRow
from jointdb.store._records import DamagedVersion, to_version
from jointdb.store._types import JointVersion, check_joint_type, check_label, normalise_material

#: Largest page of a listing.
MAX_PAGE = 10_000
VERSION_COLUMNS = [c.name for c in VersionRow.__table__.columns]


@dataclass(frozen=True)
class JointPage:
    """One page of :meth:`jointdb.store.Repository.list_page`.

    Attributes
    ----------
    items
        The listed versions.
    damaged
        Rows of this page that could not be read (:class:`DamagedVersion`).
    total
        Matches of the filters over the whole catalogue when the listing started (module
        docstring: read from the maintained counts, or counted on the first page and carried
        in the cursor).
    next
        The cursor of the next page (None on the last one).
    """

    items: tuple[JointVersion, ...]
    damaged: tuple[DamagedVersion, ...]
    total: int
    next: str | None


def encode_cursor(name: str, total: int | None = None) -> str:
    """The opaque ``next`` cursor continuing after joint ``name`` (carrying the listing's
    ``total`` when given; a name has no control characters, so a newline separates them)."""
    text = name if total is None else f"{name}\n{int(total)}"
    return base64.urlsafe_b64encode(text.encode("utf-8")).decode("ascii").rstrip("=")


def read_cursor(cursor: str) -> tuple[str, int | None]:
    """``(name, total)`` of a cursor: the joint name it continues after and the total it carries
    (None: a cursor without one). InputError for text that is not a cursor."""
    try:
        text = str(cursor)
        name = base64.urlsafe_b64decode(text + "=" * (-len(text) % 4)).decode("utf-8")
        name, _, count = name.partition("\n")
        total = int(count) if count else None
    except (binascii.Error, UnicodeError, ValueError):
        name, total = "", None
    if not name or len(name) > 200 or control_character(name) or not 0 <= (total or 0) <= 10**12:
        raise InputError(f"cursor {str(cursor)[:60]!r} is not a cursor of this list (use the 'next' of a page)")
    return name, total


def decode_cursor(cursor: str) -> str:
    """The joint name a cursor continues after; InputError for text that is not a cursor."""
    return read_cursor(cursor)[0]


def _bounds(name: str, lo: float | None, hi: float | None) -> None:
    for x in (lo, hi):
        if x is not None and (isinstance(x, bool) or not math.isfinite(float(x))):
            raise InputError(f"{name} bounds must be finite numbers, got {x}")


def check_text_filter(text: str | None, what: str) -> str | None:
    """A free-text filter (part of a name): at most 200 characters, no control characters (a NUL
    would reach PostgreSQL, which refuses it)."""
    if text is None or text == "":
        return None
    if not isinstance(text, str) or len(text) > 200 or control_character(text):
        raise InputError(f"{what} must be at most 200 characters without control characters")
    return text


def _filters(qv, *, joint_type, materials, label, include_deprecated, state, torque, preload, name_contains):
    """The WHERE terms of a listing on the query index ``qv``."""
    terms = []
    if joint_type:
        terms.append(qv.joint_type == check_joint_type(joint_type))
    for m in sorted({normalise_material(m) for m in materials or () if str(m).strip()}):
        terms.append(qv.materials.contains(f'"{m}"', autoescape=True))  # JSON text of the sorted list
    for col, (lo, hi) in ((qv.torque_nm, torque), (qv.preload_n, preload)):
        if lo is not None:
            terms.append(col >= float(lo))
        if hi is not None:
            terms.append(col <= float(hi))
    if name_contains:
        terms.append(func.lower(qv.name).contains(name_contains.lower(), autoescape=True))
    if state not in (None, "active", "deprecated"):
        raise InputError(f"state must be 'active' or 'deprecated', got {str(state)[:40]!r}")
    if state is not None:
        terms.append(qv.deprecated == (state == "deprecated"))
    if label is not None:
        lab = aliased(LabelRow)
        terms.append(exists().where(lab.joint_id == qv.joint_id, lab.version == qv.version, lab.label == label))
    else:
        terms.append(qv.listed == true())  # the head: newest active, else newest
    if not include_deprecated:  # listed and not deprecated: the newest active version
        terms.append(qv.deprecated == false())
    return terms


def _stored_total(filters: dict):
    """The total read from ``query_counts`` (None when a filter needs the rows counted)."""
    if filters["label"] is not None or filters["materials"] or filters["name_contains"] or any(
            x is not None for x in (*filters["torque"], *filters["preload"])):
        return None
    c = QueryCountRow
    terms = [c.joint_type == check_joint_type(filters["joint_type"])] if filters["joint_type"] else []
    standings = {"active": [False], "deprecated": [True], None: [False, True]}[filters["state"]]
    standings = [d for d in standings if filters["include_deprecated"] or not d]
    return select(func.coalesce(func.sum(c.joints), 0)).where(c.deprecated.in_(standings) if standings else false(),
                                                              *terms)


def count_statement(**filters):
    """The number of versions a listing's filters match: read from the maintained counts when
    the filters allow (no filter, or only type / state / ``include_deprecated``), else counted
    on the query index alone."""
    stored = _stored_total(filters)
    if stored is not None:
        return stored
    qv = aliased(QueryVersionRow)
    return select(func.count()).select_from(qv).where(*_filters(qv, **filters))


def page_statement(dialect: str, *, after: str | None, offset: int, limit: int | None, with_total: bool = True,
                   **filters):
    """The one SELECT of a page: version columns, joint name and type, standing, labels and
    (``with_total``) the listing's total."""
    qv, v, lab = QueryVersionRow, VersionRow, aliased(LabelRow)
    terms = _filters(qv, **filters)
    agg = func.string_agg if dialect == "postgresql" else func.group_concat
    labels = (select(agg(lab.label, literal(","))).where(lab.joint_id == qv.joint_id, lab.version == qv.version)
              .scalar_subquery())
    total = count_statement(**filters).scalar_subquery() if with_total else literal(None)
    stmt = (select(qv.name, qv.joint_type, qv.deprecated, labels.label("labels"), total.label("total"),
                   *[getattr(v, c) for c in VERSION_COLUMNS])
            .select_from(qv).join(v, v.id == qv.version_id).where(*terms).order_by(qv.name))
    if after is not None:
        stmt = stmt.where(qv.name > after)
    if offset:
        stmt = stmt.offset(offset)
    if limit is not None:
        stmt = stmt.limit(limit + 1)  # one more: is there a next page?
    return stmt


def version_of(row) -> JointVersion:
    """The JointVersion of one listed row (IntegrityError naming joint and version when damaged)."""
    fields = row._asdict()  # one dict of the row (getattr per column on a Row costs ~30x more)
    values = SimpleNamespace(**fields)  # the version columns, plus the listing's own (ignored)
    joint = SimpleNamespace(id=fields["joint_id"], name=fields["name"], joint_type=fields["joint_type"])
    labels = [x for x in (fields["labels"] or "").split(",") if x]
    return to_version(joint, values, "deprecated" if fields["deprecated"] else "active", labels)


def read_rows(rows: Iterable) -> tuple[list[JointVersion], list[DamagedVersion]]:
    """Listed rows as versions; damaged ones are reported apart instead of stopping the list."""
    items, damaged = [], []
    for row in rows:
        try:
            items.append(version_of(row))
        except IntegrityError as exc:
            damaged.append(DamagedVersion(row.name, int(row.version), str(exc).split(": ", 1)[-1]))
    return items, damaged


def list_page(conn, *, joint_type=None, materials=(), label=None, include_deprecated=True, state=None,
              torque_min=None, torque_max=None, preload_min=None, preload_max=None, name_contains=None,
              after=None, offset=0, limit=50) -> JointPage:
    """One page of the catalogue listing (module docstring) in one statement on ``conn``.

    Raises
    ------
    InputError
        A bad filter, cursor, offset or limit.
    """
    _bounds("torque", torque_min, torque_max)
    _bounds("preload", preload_min, preload_max)
    if limit is not None and (isinstance(limit, bool) or not 1 <= int(limit) <= MAX_PAGE):
        raise InputError(f"limit must be 1..{MAX_PAGE}, got {limit!r}")
    if isinstance(offset, bool) or not 0 <= int(offset) <= 10**9:
        raise InputError(f"offset must be 0..1000000000, got {offset!r}")
    filters = dict(joint_type=joint_type, materials=materials,
                   label=check_label(label) if label is not None else None,
                   include_deprecated=bool(include_deprecated), state=state,
                   torque=(torque_min, torque_max), preload=(preload_min, preload_max),
                   name_contains=check_text_filter(name_contains, "name filter"))
    start, carried = read_cursor(after) if after else (None, None)
    rows = list(conn.execute(page_statement(conn.dialect.name, after=start, offset=int(offset),
                                            limit=None if limit is None else int(limit),
                                            with_total=carried is None, **filters)))
    more = limit is not None and len(rows) > int(limit)
    rows = rows[:int(limit)] if limit is not None else rows
    total = carried if carried is not None else int(rows[0].total) if rows else 0
    if not rows and carried is None and (start is not None or offset):  # past the end: the total is still asked for
        total = int(conn.execute(count_statement(**filters)).scalar_one())  # PostgreSQL's SUM(bigint) is numeric
    items, damaged = read_rows(rows)
    return JointPage(tuple(items), tuple(damaged), total, encode_cursor(rows[-1].name, total) if more else None)


_FACETS: dict[tuple, dict[str, list[str]]] = {}
_FACETS_LOCK = threading.Lock()


def listing_facets(conn, key: str = "") -> dict[str, list[str]]:
    """The values a catalogue page offers to filter on, over the listed versions: ``types``,
    ``materials``, ``combos`` (material sets as ``"a + b"``), ``labels`` and ``tapers``
    (``conditions.extra.taper``).

    Read in SQL from the query index (no record is decoded or verified) and kept per process
    for the query stamp ``(token, generation)`` they were read at: a page after no write costs
    one single-row SELECT; the first after a write reads the listed rows once.

    Parameters
    ----------
    conn
        A connection of the repository's read engine.
    key
        What tells databases apart in the per-process cache (e.g. the URL).

    Returns
    -------
    dict of str to list of str
        Each facet's values, sorted.
    """
    qv, v, lab = QueryVersionRow, VersionRow, LabelRow
    stamp = tuple(conn.execute(select(QueryStampRow.token, QueryStampRow.generation)
                               .where(QueryStampRow.id == 1)).one())
    with _FACETS_LOCK:
        found = _FACETS.get((key, *stamp))
    if found is not None:
        return found
    types = conn.execute(select(QueryCountRow.joint_type).where(QueryCountRow.joints > 0).distinct()).scalars()
    labels = conn.execute(select(lab.label).join(qv, (qv.joint_id == lab.joint_id) & (qv.version == lab.version))
                          .where(qv.listed == true()).distinct()).scalars()
    mats, combos, tapers = set(), set(), set()
    rows = select(type_coerce(v.materials, Text), type_coerce(v.extra, Text)).join(qv, qv.version_id == v.id)
    for materials, extra in conn.execute(rows.where(qv.listed == true())):
        try:  # raw JSON text (SQLite) or values (psycopg decodes json); a damaged row offers nothing
            materials, extra = (json.loads(x) if isinstance(x, str) else x for x in (materials, extra))
        except ValueError:
            continue
        if not isinstance(materials, list) or not all(isinstance(m, str) for m in materials):
            continue
        mats.update(materials)
        combos.add(" + ".join(materials))
        taper = extra.get("taper") if isinstance(extra, dict) else None
        if isinstance(taper, str):
            tapers.add(taper)
    facets = {"types": sorted(set(types)), "materials": sorted(mats), "tapers": sorted(tapers),
              "labels": sorted(set(labels)), "combos": sorted(c for c in combos if c)}
    with _FACETS_LOCK:
        if len(_FACETS) > 64:
            _FACETS.clear()
        _FACETS[(key, *stamp)] = facets
    return facets
