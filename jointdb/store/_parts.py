"""Parts of stacks as versioned records: spindles, holders and tools (tables of migration ``0009``).

A part has a name and a kind; its versions are immutable rows ``(part, version)`` like the
joints' (:mod:`jointdb.store._catalogue`), with the same guarantees:

- the payload is the part's object of a stack file (``jointdb-stack/1``): a tool
  (``material, segments, ...``), a holder (``material, segments, loss_factor``) or a spindle
  (``{"model": {beam model}, "point": name}``, or ``{"node": N}`` with the measured FRF set of
  the spindle nose as a content-addressed blob in the repository's blob store);
- attributes for finding it: ``machine`` (spindles, required), ``family``, ``taper``, ``bore_mm``
  (holders), ``description``;
- provenance (input files with their SHA-256, method, software version, parent version);
- every version's content is hashed into ``record_sha256``, recomputed on every read, and its
  blob is verified against its digest on every load (:class:`~jointdb.errors.IntegrityError`);
- the database refuses UPDATE and DELETE of ``parts`` / ``part_versions`` (triggers of
  ``0009``), every new row enters the history chain (:mod:`jointdb.store._chain`), every write
  is audited; labels (``part_labels``) are the only mutable pointers;
- adding content identical to the latest version writes nothing and returns that version.

:class:`PartsStore` is a mixin of :class:`jointdb.store.Repository` (it uses its ``storage``).
"""

from __future__ import annotations

import uuid as uuidlib
from collections.abc import Mapping
from typing import Any

from sqlalchemy import func, select
from sqlalchemy.orm import Session

from jointdb.schemas._limits import check_stored_json, check_text
from jointdb.errors import ConflictError, InputError, NotFoundError
from jointdb.frf import FRF
from jointdb.store import _db
from jointdb.store._models import AuditRow, PartLabelRow, PartRow, PartVersionRow, utcnow
from jointdb.store._part_records import (
    PartVersion,
    check_attributes,
    check_part_kind,
    check_part_name,
    check_payload,
    parse_part_ref,
    part_identity,
    part_record,
    part_row,
    verified_part,
)
from jointdb.store._records import current_actor, record_sha256, software_version
from jointdb.store._types import check_label


class PartsStore:
    """``add_part``, ``get_part``, ``list_parts``, ``part_history``, ``label_part``, ``load_part_frf``."""

    @_db.with_db_errors
    def add_part(self, name: str, kind: str, payload: Mapping[str, Any], *, frf: FRF | None = None,
                 attributes: Mapping[str, Any] | None = None, provenance: Mapping[str, Any] | None = None,
                 author: str | None = None, label: str | None = None) -> PartVersion:
        """Catalogue a part as a new part or a new version of one (nothing written when identical).

        Parameters
        ----------
        name, kind
            The part's name (``check_part_name``) and kind (spindle / holder / tool).
        payload
            The part's object of a stack file (module docstring); a measured spindle: ``{"node": N}``.
        frf
            A measured spindle's nose FRF set (receptance, ``(n_freq, n_out, n_in)``, DOFs
            ``Nx``, ``Nry`` and optionally ``Ny``, ``Nrx``), stored as a verified blob.
        attributes, provenance
            See the module docstring; provenance keys are free (``input_files``, ``method``, ...).
        author, label
            Who catalogues it (default: ``JOINTDB_AUTHOR`` or the login), a label to point at it.

        Returns
        -------
        PartVersion
            The new version, or the latest one when its content is identical.

        Raises
        ------
        InputError
            A bad name, kind, attribute, payload or FRF (naming the field).
        ConflictError
            ``name`` exists as a part of another kind.
        """
        name, kind = check_part_name(name), check_part_kind(kind)
        if frf is not None and not isinstance(frf, FRF):
            raise InputError(f"frf must be a jointdb.frf.FRF, got {type(frf).__name__}")
        attrs = check_attributes(kind, attributes)
        body = check_payload(kind, payload, frf)
        if kind == "spindle" and frf is None and "node" in body:
            raise InputError("frf: a measured spindle needs its FRF set")
        prov = {"software_version": software_version(), **dict(provenance or {})}
        check_stored_json(prov, "provenance")
        actor = current_actor(author)
        label = check_label(label) if label is not None else None
        pending = self.blobs.put_pending(frf) if frf is not None else None
        try:
            blob = pending.digest if pending is not None else None

            def write(s: Session) -> tuple[str, int, bool]:
                number, created = self._write_part(s, name, kind, attrs, body, blob, prov, actor, label)
                if pending is not None:
                    pending.wait()  # the blob is durable before the row that references it commits
                return name, number, created

            _, number, _ = self.storage.retrying(write)
        finally:
            if pending is not None:
                pending.join()
        return self.get_part(name, number)

    def _write_part(self, s: Session, name, kind, attrs, body, blob, prov, actor, label) -> tuple[int, bool]:
        now = utcnow()
        part = s.scalar(select(PartRow).where(PartRow.name == name).with_for_update())
        if part is None:
            part = PartRow(name=name, kind=kind, created_at=now, created_by=actor)
            s.add(part)
            s.flush()
            latest = None
        else:
            if part.kind != kind:
                raise ConflictError(f"part {name!r} is a {part.kind}, not a {kind}; use another name")
            latest = s.scalar(select(PartVersionRow).where(PartVersionRow.part_id == part.id)
                              .order_by(PartVersionRow.version.desc()).limit(1))
        if latest is not None and part_identity(latest) == (attrs, body, blob):
            number, created = latest.version, False
        else:
            number, created = (latest.version if latest is not None else 0) + 1, True
            row = PartVersionRow(part_id=part.id, version=number, uuid=str(uuidlib.uuid4()), created_at=now,
                                 author=actor, machine=attrs.get("machine"), family=attrs.get("family"),
                                 attributes=attrs, payload=body, blob_sha256=blob,
                                 provenance={**prov, "parent_version": latest.version if latest else None},
                                 parent_version=latest.version if latest else None)
            row.record_sha256 = record_sha256(part_record(name, kind, row))
            s.add(row)
            s.add(AuditRow(at=now, actor=actor, action="part-add", joint_name=None, version=number,
                           details={"part": name, "kind": kind, "blob_sha256": blob,
                                    "record_sha256": row.record_sha256}))
            s.flush()
        if label is not None:
            self._move_part_label(s, part, number, label, actor, now)
        return number, created

    @staticmethod
    def _move_part_label(s: Session, part: PartRow, version: int, label: str, actor: str, now) -> None:
        row = s.scalar(select(PartLabelRow).where(PartLabelRow.part_id == part.id, PartLabelRow.label == label)
                       .with_for_update())
        old = None
        if row is None:
            s.add(PartLabelRow(part_id=part.id, label=label, version=version, updated_at=now, updated_by=actor))
        else:
            old = row.version
            row.version, row.updated_at, row.updated_by = version, now, actor
        s.add(AuditRow(at=now, actor=actor, action="part-label", joint_name=None, version=version,
                       details={"part": part.name, "label": label, "previous_version": old}))

    @_db.with_db_errors
    def label_part(self, name: str, version: int, label: str, author: str | None = None) -> PartVersion:
        """Point ``label`` of a part at ``version`` (created or moved; audited).

        Parameters
        ----------
        name
            The part.
        version
            The version number (>= 1) the label is to point at.
        label
            The label: 1-100 letters, digits, ``.``, ``_`` or ``-`` (e.g. ``released``).
        author
            Who moves it (default: ``JOINTDB_AUTHOR`` or the login), recorded in the audit log.

        Returns
        -------
        PartVersion
            That version, its ``labels`` including ``label``.

        Raises
        ------
        InputError
            A bad label or version number.
        NotFoundError
            Unknown part or version.
        """
        label = check_label(label)
        actor = current_actor(author)
        if isinstance(version, bool) or not isinstance(version, int) or version < 1:
            raise InputError(f"version must be a version number >= 1, got {version!r}")
        self.get_part(name, version)  # NotFoundError for an unknown part or version

        def write(s: Session) -> None:
            self._move_part_label(s, part_row(s, name, lock=True), int(version), label, actor, utcnow())

        self.storage.retrying(write)
        return self.get_part(name, version)

    def _part_labels(self, s: Session, part_id: int) -> dict[int, list[str]]:
        out: dict[int, list[str]] = {}
        for lab in s.scalars(select(PartLabelRow).where(PartLabelRow.part_id == part_id)):
            out.setdefault(lab.version, []).append(lab.label)
        return out

    @_db.with_db_errors
    def get_part(self, name: str, version: int | None = None, label: str | None = None) -> PartVersion:
        """One version of a part, its record verified: pinned, by ``label``, or (default) the latest.

        Parameters
        ----------
        name
            The part.
        version
            A version number (None: see ``label``).
        label
            A label pointing at the version (None, with ``version`` None too: the latest version).

        Returns
        -------
        PartVersion
            With the labels that point at it.

        Raises
        ------
        InputError
            Both ``version`` and ``label``, or a version that is not a whole number.
        NotFoundError
            Unknown part, version or label.
        IntegrityError
            The stored record does not match its hash.
        """
        if version is not None and label is not None:
            raise InputError("give a version or a label, not both")
        with self.storage.read() as s:
            part = part_row(s, name)
            q = select(PartVersionRow).where(PartVersionRow.part_id == part.id)
            if label is not None:
                lab = s.scalar(select(PartLabelRow.version).where(PartLabelRow.part_id == part.id,
                                                                    PartLabelRow.label == check_label(label)))
                if lab is None:
                    raise NotFoundError(f"part {name!r} has no label {label!r}")
                q = q.where(PartVersionRow.version == lab)
            elif version is not None:
                if isinstance(version, bool) or not isinstance(version, int):
                    raise InputError(f"version must be a whole number, got {version!r}")
                q = q.where(PartVersionRow.version == version)
            row = s.scalar(q.order_by(PartVersionRow.version.desc()).limit(1))
            if row is None:
                raise NotFoundError(f"part {name!r} has no version {version}")
            return verified_part(part, row, self._part_labels(s, part.id).get(row.version, ()))

    def resolve_part(self, ref: str) -> PartVersion:
        """The version a ``name@version`` / ``name@label`` reference names (:func:`parse_part_ref`).

        Parameters
        ----------
        ref
            ``"name@3"`` (a version number) or ``"name@released"`` (a label).

        Returns
        -------
        PartVersion
            As :meth:`get_part` returns it (record verified).

        Raises
        ------
        InputError
            Not ``name@version`` or ``name@label``.
        NotFoundError
            Unknown part, version or label.
        """
        name, tail = parse_part_ref(ref)
        return self.get_part(name, version=tail) if isinstance(tail, int) else self.get_part(name, label=tail)

    @_db.with_db_errors
    def part_history(self, name: str) -> list[PartVersion]:
        """Every version of a part, oldest first, each verified.

        Parameters
        ----------
        name
            The part.

        Returns
        -------
        list of PartVersion
            Version 1 first, each with the labels pointing at it.

        Raises
        ------
        NotFoundError
            Unknown part.
        IntegrityError
            A version whose stored record does not match its hash.
        """
        with self.storage.read() as s:
            part = part_row(s, name)
            labels = self._part_labels(s, part.id)
            rows = s.scalars(select(PartVersionRow).where(PartVersionRow.part_id == part.id)
                             .order_by(PartVersionRow.version))
            return [verified_part(part, r, labels.get(r.version, ())) for r in rows]

    @_db.with_db_errors
    def list_parts(self, kind: str | None = None, *, family: str | None = None,
                   machine: str | None = None) -> list[PartVersion]:
        """The latest version of every part (by name), optionally of one kind, holder family or machine.

        Parameters
        ----------
        kind
            Only parts of this kind (spindle / holder / tool; None: all).
        family
            Only parts whose latest version has this ``family`` attribute (holders, e.g. ``ER32``).
        machine
            Only parts whose latest version has this ``machine`` attribute (spindles).

        Returns
        -------
        list of PartVersion
            One per part, sorted by name, each verified and with its labels.

        Raises
        ------
        InputError
            An unknown kind, or a filter that is not plain text of at most 200 characters.
        """
        newest = (select(PartVersionRow.part_id, func.max(PartVersionRow.version).label("v"))
                  .group_by(PartVersionRow.part_id).subquery())
        q = (select(PartRow, PartVersionRow).join(PartVersionRow, PartVersionRow.part_id == PartRow.id)
             .join(newest, (newest.c.part_id == PartVersionRow.part_id) & (newest.c.v == PartVersionRow.version))
             .order_by(PartRow.name))
        if kind is not None:
            q = q.where(PartRow.kind == check_part_kind(kind))
        if family is not None:
            q = q.where(PartVersionRow.family == check_text(family, "family", 200, strict=True))
        if machine is not None:
            q = q.where(PartVersionRow.machine == check_text(machine, "machine", 200, strict=True))
        with self.storage.read() as s:
            labels: dict[tuple[int, int], list[str]] = {}
            for lab in s.scalars(select(PartLabelRow)):
                labels.setdefault((lab.part_id, lab.version), []).append(lab.label)
            return [verified_part(p, r, labels.get((p.id, r.version), ())) for p, r in s.execute(q)]

    def load_part_frf(self, part: PartVersion) -> FRF:
        """A measured spindle's FRF set, read from its blob and verified against its digest.

        Parameters
        ----------
        part
            A version from :meth:`get_part` (or another part read) whose ``blob_sha256`` is set.

        Returns
        -------
        FRF
            The spindle-nose receptance set ``(n_freq, n_out, n_in)``, DOFs ``Nx``, ``Nry`` (and
            ``Ny``, ``Nrx`` when measured), as catalogued.

        Raises
        ------
        NotFoundError
            The part has no FRF, or its blob is missing.
        IntegrityError
            The blob is corrupt (never a server path in the message).
        """
        if part.blob_sha256 is None:
            raise NotFoundError(f"part {part.ref} has no FRF set (it is a {part.kind} model)")
        return self._blob(part, part.blob_sha256, "FRF blob")  # verified; never a server path in an error
