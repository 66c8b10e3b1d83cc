"""Reading versions: one by name, label or time; a joint's history; the catalogue listing; FRF
blobs; the difference of two versions.

A mixin of :class:`jointdb.store.Repository`: it uses the repository's ``_read`` sessions and
``blobs`` store.
"""

from __future__ import annotations

import re
import warnings
from collections.abc import Iterable
from datetime import datetime

from sqlalchemy import bindparam, func, literal, or_, select
from sqlalchemy.orm import Session, aliased

from jointdb.errors import InputError, IntegrityError, NotFoundError
from jointdb.frf import FRF
from jointdb.store import _db
from jointdb.store._access import joint_row
from jointdb.store._reports import VersionDiff
from jointdb.store._models import JointRow, LabelRow, StateRow, VersionRow
from jointdb.schemas._limits import control_character
from jointdb.store._listing import VERSION_COLUMNS, JointPage, list_page, version_of
from jointdb.store._records import DamagedRecordWarning, DamagedVersion, as_utc, state_of, to_version
from jointdb.store._types import JointVersion, check_label

_HEX64 = re.compile(r"[0-9a-f]{64}")


def pinned_statement(dialect: str):
    """One version of a joint by name and number with its current state and labels, in one SELECT
    (the columns :func:`jointdb.store._listing.version_of` reads): the state is the joint's newest
    state row for the whole joint or this version (by time, then id, as :func:`state_of`), the
    labels those pointing at this version."""
    j, v, st, lab = JointRow, VersionRow, aliased(StateRow), aliased(LabelRow)
    state = (select(st.state).where(st.joint_id == j.id, or_(st.version.is_(None), st.version == v.version))
             .order_by(st.at.desc(), st.id.desc()).limit(1).scalar_subquery())
    agg = func.string_agg if dialect == "postgresql" else func.group_concat
    labels = select(agg(lab.label, literal(","))).where(lab.joint_id == j.id, lab.version == v.version).scalar_subquery()
    return (select(j.name, j.joint_type, (func.coalesce(state, literal("active")) == literal("deprecated"))
                   .label("deprecated"), labels.label("labels"), *[getattr(v, c) for c in VERSION_COLUMNS])
            .select_from(j).join(v, v.joint_id == j.id)
            .where(j.name == bindparam("name"), v.version == bindparam("version")))


class _PinnedByDialect(dict):
    """:func:`pinned_statement` per dialect name, built on first use (SQLAlchemy caches its compilation)."""

    def __missing__(self, dialect: str):
        self[dialect] = pinned_statement(dialect)
        return self[dialect]


_PINNED = _PinnedByDialect()


def _report_damaged(found: list[DamagedVersion], into: list | None) -> None:
    """Damaged versions a list skipped: into the caller's list, or as one warning naming them."""
    if into is not None:
        into.extend(found)
    elif found:
        warnings.warn("skipped damaged versions (run `jointdb db check`): "
                      + "; ".join(d.describe() for d in found[:10]), DamagedRecordWarning, stacklevel=3)


class VersionReads:
    """``get``, ``history``, ``list_page``, ``list_joints``, ``load_frf``, ``load_raw``, ``diff``
    (see :class:`jointdb.store.Repository`)."""

    @staticmethod
    def _joint(session: Session, name: str) -> JointRow:
        return joint_row(session, name)

    def _states(self, session: Session, joint_id: int, at: datetime | None) -> list[StateRow]:
        q = select(StateRow).where(StateRow.joint_id == joint_id)
        if at is not None:
            q = q.where(StateRow.at <= at)
        return list(session.scalars(q))

    def _labels(self, session: Session, joint_id: int) -> dict[int, list[str]]:
        out: dict[int, list[str]] = {}
        for lab in session.scalars(select(LabelRow).where(LabelRow.joint_id == joint_id)):
            out.setdefault(lab.version, []).append(lab.label)
        return out

    @_db.with_db_errors
    def get(
        self,
        name: str,
        version: int | None = None,
        at: datetime | str | None = None,
        label: str | None = None,
    ) -> JointVersion:
        """One version of a joint: pinned (``version``), by ``label``, current at
        time ``at``, or (default) the latest version that is not deprecated
        (the latest one if all are).

        Parameters
        ----------
        name
            The joint's name.
        version
            A version number.
        at
            A past instant (datetime or ISO 8601 text).
        label
            A label of the joint.

        Returns
        -------
        JointVersion

        Raises
        ------
        NotFoundError
            Unknown joint, version or label, or no version existed at ``at``
            (also when the pinned ``version`` was catalogued after ``at``).
        InputError
            ``label`` combined with ``version`` or ``at`` (labels are current pointers).
        """
        at = as_utc(at)
        if version is not None and at is None and label is None:
            found = self._pinned(name, version)
            if found is not None:
                return found
        if label is not None and (version is not None or at is not None):
            raise InputError("a label names one version now; do not combine it with --version or --at")
        with self._read() as s:
            joint = self._joint(s, name)
            labels = self._labels(s, joint.id)
            if label is not None:
                label = check_label(label)  # a NUL would reach PostgreSQL, which refuses it
                lab = s.scalar(select(LabelRow).where(LabelRow.joint_id == joint.id, LabelRow.label == label))
                if lab is None:
                    have = sorted({x for v in labels.values() for x in v})
                    raise NotFoundError(f"joint {name!r} has no label {label!r} (labels: {', '.join(have) or 'none'})")
                version = lab.version
            q = select(VersionRow).where(VersionRow.joint_id == joint.id)
            if version is not None:
                # beyond the database's integers (PostgreSQL would refuse the query) no version exists
                row = s.scalar(q.where(VersionRow.version == int(version))) if 0 < int(version) < 2**31 else None
                if row is None:
                    n = s.scalar(select(func.max(VersionRow.version)).where(VersionRow.joint_id == joint.id))
                    raise NotFoundError(f"joint {name!r} has no version {version} (versions 1..{n or 0})")
                if at is not None and row.created_at > at:
                    raise NotFoundError(f"joint {name!r} version {version} did not exist yet at {at.isoformat()} "
                                        f"(catalogued {row.created_at.isoformat(timespec='seconds')})")
                states = self._states(s, joint.id, at)
                return to_version(joint, row, state_of(row.version, states), labels.get(row.version, ()))
            if at is not None:
                q = q.where(VersionRow.created_at <= at)
            rows = list(s.scalars(q.order_by(VersionRow.version.desc())))
            if not rows:
                raise NotFoundError(f"joint {name!r} had no version at {at.isoformat() if at else 'all'}")
            states = self._states(s, joint.id, at)
            for row in rows:
                if state_of(row.version, states) == "active":
                    return to_version(joint, row, "active", labels.get(row.version, ()))
            row = rows[0]
            return to_version(joint, row, "deprecated", labels.get(row.version, ()))

    def _pinned(self, name: str, version: int) -> JointVersion | None:
        """A pinned version in one statement (:func:`pinned_statement`), or None when it is not
        there (or the arguments are not plain): :meth:`get`'s general path then answers (its errors
        name what is missing). Same value as the general path: the state and labels are read
        fresh with the row, and the record hash is verified as on every read."""
        if (not isinstance(name, str) or len(name) > 1000 or control_character(name)
                or isinstance(version, bool) or not isinstance(version, int) or not 0 < version < 2**31):
            return None
        with self.read_engine.connect() as conn:
            row = conn.execute(_PINNED[conn.dialect.name], {"name": name, "version": version}).first()
        return None if row is None else version_of(row)

    @_db.with_db_errors
    def history(self, name: str, *, damaged: list | None = None) -> list[JointVersion]:
        """All versions of a joint, oldest first, with their current state and labels.

        A version whose stored row is damaged is left out and reported: appended to ``damaged``
        (a list, as :class:`DamagedVersion`) when given, else in a :class:`DamagedRecordWarning`.

        Parameters
        ----------
        name
            The joint's name.
        damaged
            A list to append the damaged versions to, or None (warn instead).

        Returns
        -------
        list of JointVersion

        Raises
        ------
        NotFoundError
            No joint of that name.
        """
        with self._read() as s:
            joint = self._joint(s, name)
            labels = self._labels(s, joint.id)
            states = self._states(s, joint.id, None)
            rows = s.scalars(select(VersionRow).where(VersionRow.joint_id == joint.id).order_by(VersionRow.version))
            out, bad = [], []
            for r in rows:
                try:
                    out.append(to_version(joint, r, state_of(r.version, states), labels.get(r.version, ())))
                except IntegrityError as exc:
                    bad.append(DamagedVersion(joint.name, r.version, str(exc).split(": ", 1)[-1]))
        _report_damaged(bad, damaged)
        return out

    @_db.with_db_errors
    def list_page(self, joint_type: str | None = None, *, materials: Iterable[str] = (), label: str | None = None,
                  include_deprecated: bool = True, state: str | None = None, torque_min: float | None = None,
                  torque_max: float | None = None, preload_min: float | None = None,
                  preload_max: float | None = None, name_contains: str | None = None, after: str | None = None,
                  offset: int = 0, limit: int | None = 50) -> JointPage:
        """One page of the catalogue: the current version of each joint that passes the filters,
        by name, in one SQL statement that reads one range of the listing's head index (O(page)
        rows whatever the catalogue's size; see :mod:`jointdb.store._listing`).

        Damaged rows do not stop the list: they are in ``JointPage.damaged``.

        Parameters
        ----------
        joint_type
            Only joints of this type.
        materials
            Only joints whose conditions name all these materials.
        label
            Only versions carrying this label.
        include_deprecated
            List joints whose every version is deprecated too.
        state
            Only versions in this state (``"active"``, ``"deprecated"``).
        torque_min, torque_max
            Bounds on the torque [N·m].
        preload_min, preload_max
            Bounds on the preload [N].
        name_contains
            Part of the joint's name.
        after
            The ``next`` cursor of the previous page (keyset pagination).
        offset
            Rows to skip (without a cursor).
        limit
            Page size; None lists all.

        Returns
        -------
        JointPage
            ``items``, ``next`` cursor, ``damaged`` and ``total`` (the matches when the listing
            started: read from maintained counts, or counted on the first page and carried in
            the cursor).

        Raises
        ------
        InputError
            A bad filter (type, material, label, bounds, name part), cursor, offset or limit.
        """
        with self.read_engine.connect() as conn:
            return list_page(conn, joint_type=joint_type, materials=materials, label=label,
                             include_deprecated=include_deprecated, state=state, torque_min=torque_min,
                             torque_max=torque_max, preload_min=preload_min, preload_max=preload_max,
                             name_contains=name_contains, after=after, offset=offset, limit=limit)

    @_db.with_db_errors
    def list_joints(self, joint_type: str | None = None, include_deprecated: bool = True, *,
                    damaged: list | None = None) -> list[JointVersion]:
        """The current version (as :meth:`get`) of every joint, by name (one SQL statement).

        Damaged rows are left out and reported as in :meth:`history`.

        Parameters
        ----------
        joint_type
            Only joints of this type (None: all).
        include_deprecated
            Include joints whose every version is deprecated.
        damaged
            A list to append the damaged versions to, or None (warn instead).

        Returns
        -------
        list of JointVersion
        """
        page = self.list_page(joint_type, include_deprecated=include_deprecated, limit=None)
        _report_damaged(list(page.damaged), damaged)
        return list(page.items)

    @_db.with_db_errors
    def load_frf(self, version: JointVersion | str, number: int | None = None) -> FRF:
        """The joint FRF of a version, read from its blob and verified against its hash.

        ``load_frf(jv)`` or ``load_frf("name", 3)``.

        Parameters
        ----------
        version
            A :class:`JointVersion`, or a joint's name.
        number
            With a name: the version number (None: the current version).

        Returns
        -------
        FRF
            The joint's identified FRF, verified against its content hash.

        Raises
        ------
        IntegrityError
            The blob is corrupt; NotFoundError when it is missing.
        """
        jv = version if isinstance(version, JointVersion) else self.get(version, number)
        return self._blob(jv, jv.blob_sha256, "FRF blob")

    def _blob(self, jv: JointVersion, digest: str, what: str) -> FRF:
        """A blob of ``jv``; a corrupt or missing one is named by its version, never by a server path."""
        if not isinstance(digest, str) or not _HEX64.fullmatch(digest):  # never echoed, never used in a path
            raise IntegrityError(f"{jv.name} v{jv.version}: the digest of its {what} is not a SHA-256 hex digest; "
                                 "refusing to use it - run `jointdb db check`")
        try:
            return self.blobs.get(digest)
        except IntegrityError:
            raise IntegrityError(f"{jv.name} v{jv.version}: its {what} {digest} is corrupt or unreadable; refusing "
                                 "to use it - run `jointdb db check`") from None
        except NotFoundError:
            raise NotFoundError(f"{jv.name} v{jv.version}: its {what} {digest} is missing from the blob store - "
                                "run `jointdb db check`") from None

    @_db.with_db_errors
    def load_raw(self, version: JointVersion, key: str) -> FRF:
        """One raw measurement FRF stored with a version.

        Parameters
        ----------
        version
            The :class:`JointVersion`.
        key
            A key of ``version.raw_blobs``.

        Returns
        -------
        FRF
            The measurement as it was uploaded, verified against its content hash.

        Raises
        ------
        NotFoundError
            No raw measurement of that key, or its blob is missing.
        """
        if key not in version.raw_blobs:
            raise NotFoundError(f"{version.name} v{version.version} has no raw measurement {key!r}")
        return self._blob(version, version.raw_blobs[key], f"raw measurement {key!r}")

    # -------------------------------------------------------------- diff, etc.
    @_db.with_db_errors
    def diff(self, name: str, version_a: int, version_b: int | None = None, other: str | None = None) -> VersionDiff:
        """Compare two versions (of one joint, or of ``name`` and ``other``).

        Parameters
        ----------
        name
            The joint's name.
        version_a
            The first version number.
        version_b
            The second version number (default: the current version).
        other
            Another joint's name for ``version_b``.

        Returns
        -------
        VersionDiff
        """
        from jointdb.store._maintenance import diff_versions

        a = self.get(name, version_a)
        b = self.get(other or name, version_b) if (version_b is not None or other) else self.get(name)
        return diff_versions(self.load_frf, a, b)

