"""Labels (mutable pointers), deprecation states and the audit log of a repository.

A mixin of :class:`jointdb.store.Repository`: it uses the repository's ``get``,
``history`` and ``storage`` (:class:`jointdb.store._access.Storage`: read sessions and
retried write transactions).
"""

from __future__ import annotations

from typing import Any

from sqlalchemy import select
from sqlalchemy.orm import Session

from jointdb.schemas._limits import check_text
from jointdb.store import _db
from jointdb.store._access import joint_row
from jointdb.store._index import bump, refresh_joints
from jointdb.store._models import AuditRow, JointRow, LabelRow, StateRow, utcnow
from jointdb.store._records import current_actor
from jointdb.store._types import JointVersion, check_label


class LabelsAndStates:
    """``label``, ``deprecate`` and ``audit`` (see :class:`jointdb.store.Repository`)."""

    @_db.with_db_errors
    def label(self, name: str, version: int, label: str, author: str | None = None) -> JointVersion:
        """Point ``label`` of a joint at ``version`` (created or moved).

        The label row is locked (``SELECT ... FOR UPDATE`` on PostgreSQL; SQLite
        writers are serialised by ``BEGIN IMMEDIATE``) so that the audit row's
        ``previous_version`` is the version the label really pointed at.

        Parameters
        ----------
        name
            The joint's name.
        version
            The version number the label points at afterwards.
        label
            The label (letters, digits, ``._-``).
        author
            Recorded in the audit log (default ``JOINTDB_AUTHOR``, else the login name).

        Returns
        -------
        JointVersion
            The labelled version.
        """
        label = check_label(label)
        actor = current_actor(author)
        self.get(name, version)  # NotFoundError for an unknown joint or version

        def write(s: Session) -> None:
            joint = joint_row(s, name)
            self._move_label(s, joint, name, int(version), label, actor, utcnow())
            bump(s, [joint.id])  # labels are read live by the query; only its stamp changes

        self.storage.retrying(write)
        return self.get(name, version)

    @staticmethod
    def _move_label(s: Session, joint: JointRow, name: str, version: int, label: str, actor: str, now) -> None:
        row = s.scalar(
            select(LabelRow).where(LabelRow.joint_id == joint.id, LabelRow.label == label).with_for_update()
        )
        old = None
        if row is None:  # two creators at once: the unique constraint refuses one, which is retried
            s.add(LabelRow(joint_id=joint.id, label=label, version=version, updated_at=now, updated_by=actor))
        else:
            old = row.version
            row.version, row.updated_at, row.updated_by = version, now, actor
        s.add(AuditRow(at=now, actor=actor, action="label", joint_name=name, version=version,
                       details={"label": label, "previous_version": old}))

    @_db.with_db_errors
    def unlabel(self, name: str, label: str, author: str | None = None) -> int:
        """Remove ``label`` from a joint (the undo of a new label); the audit log keeps the
        version it pointed at.

        Parameters
        ----------
        name
            The joint.
        label
            The label to remove.
        author
            Who removes it (default: the current actor).

        Returns
        -------
        int
            The version the label pointed at.

        Raises
        ------
        NotFoundError
            The joint has no such label.
        """
        from jointdb.errors import NotFoundError

        label = check_label(label)
        actor = current_actor(author)
        removed: list[int] = []

        def write(s: Session) -> None:
            joint = joint_row(s, name)
            row = s.scalar(select(LabelRow).where(LabelRow.joint_id == joint.id, LabelRow.label == label)
                           .with_for_update())
            if row is None:
                raise NotFoundError(f"joint {name!r} has no label {label!r}")
            removed[:] = [row.version]
            s.delete(row)
            s.add(AuditRow(at=utcnow(), actor=actor, action="unlabel", joint_name=name, version=row.version,
                           details={"label": label, "previous_version": row.version}))
            bump(s, [joint.id])

        self.storage.retrying(write)
        return removed[0]

    @_db.with_db_errors
    def deprecate(
        self, name: str, version: int | None = None, reason: str = "", author: str | None = None, undo: bool = False
    ) -> list[JointVersion]:
        """Mark a version (or, with ``version=None``, the whole joint) deprecated.

        Nothing is deleted: a new state row is appended (``undo=True`` appends
        ``active`` again); the latest applicable row wins. A joint deprecated as
        a whole stays deprecated, including versions catalogued later, until it
        is undone.

        Parameters
        ----------
        name
            The joint's name.
        version
            The version (None: the whole joint).
        reason
            Why, recorded in the state row and the audit log.
        author
            Recorded in the audit log (default ``JOINTDB_AUTHOR``, else the login name).
        undo
            Make it active again.

        Returns
        -------
        list of JointVersion
            The joint's history afterwards.
        """
        actor = current_actor(author)
        reason = check_text(str(reason), "reason")  # no NUL or control characters, at most 10000 characters
        if version is not None:
            self.get(name, version)
        state = "active" if undo else "deprecated"

        def write(s: Session) -> None:
            joint = joint_row(s, name)
            now = utcnow()
            s.add(StateRow(joint_id=joint.id, version=version, state=state, reason=str(reason), author=actor, at=now))
            s.add(AuditRow(at=now, actor=actor, action="undeprecate" if undo else "deprecate", joint_name=name,
                           version=version, details={"reason": str(reason)}))
            s.flush()
            refresh_joints(s, [joint.id])  # the query index, in the same transaction

        self.storage.retrying(write)
        return self.history(name)

    @_db.with_db_errors
    def audit(self, name: str | None = None, limit: int = 100) -> list[dict[str, Any]]:
        """The newest audit-log entries, newest first.

        Parameters
        ----------
        name
            Only entries of this joint (None: all).
        limit
            At most this many.

        Returns
        -------
        list of dict
            ``at`` (ISO 8601), ``actor``, ``action``, ``joint``, ``version``, ``details``.
        """
        with self.storage.read() as s:
            q = select(AuditRow).order_by(AuditRow.id.desc()).limit(limit)
            if name:
                q = q.where(AuditRow.joint_name == name)
            return [
                {"at": r.at.isoformat(timespec="seconds"), "actor": r.actor, "action": r.action,
                 "joint": r.joint_name, "version": r.version, "details": r.details}
                for r in s.scalars(q)
            ]

