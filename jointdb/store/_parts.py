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

import re
import uuid as uuidlib
from collections.abc import Mapping
from dataclasses import dataclass, field
from datetime import datetime
from typing import Any

from sqlalchemy import func, select
from sqlalchemy.orm import Session

from jointdb._limits import check_stored_json, check_text, control_character
from jointdb.errors import ConflictError, InputError, IntegrityError, NotFoundError
from jointdb.frf import FRF
from jointdb.store import _db
from jointdb.store._models import AuditRow, PartLabelRow, PartRow, PartVersionRow, utcnow
from jointdb.store._records import DamagedJSON, current_actor, record_sha256, software_version
from jointdb.store._types import check_label

PART_KINDS = ("spindle", "holder", "tool")
#: attribute -> kinds that may carry it
ATTRIBUTES = {"machine": ("spindle",), "family": ("holder",), "taper": ("holder", "spindle"),
              "bore_mm": ("holder",), "description": PART_KINDS}
_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.+-]{0,199}")
_REF = re.compile(r"^\s*([^@\s]+)\s*@\s*([^@\s]+)\s*$")


def check_part_name(name: Any) -> str:
    """A part name: 1-200 letters, digits, ``. _ + -``, starting with a letter or digit (no ``@``, ``/``)."""
    if not isinstance(name, str) or not _NAME.fullmatch(name):
        raise InputError(f"part name {str(name)[:60]!r} must be 1-200 letters, digits, '.', '_', '+' or '-' "
                         "(starting with a letter or digit)")
    return name


def check_part_kind(kind: Any) -> str:
    if kind not in PART_KINDS:
        raise InputError(f"part kind {str(kind)[:40]!r} must be one of {', '.join(PART_KINDS)}")
    return kind


def parse_part_ref(ref: Any) -> tuple[str, int | str]:
    """``"name@3"`` -> ``("name", 3)``; ``"name@released"`` -> ``("name", "released")``.

    Raises
    ------
    InputError
        Not ``name@version`` or ``name@label``.
    """
    m = _REF.match(ref) if isinstance(ref, str) else None
    if not m:
        raise InputError(f"part reference {str(ref)[:80]!r} must be 'name@version' or 'name@label'")
    name, tail = check_part_name(m.group(1)), m.group(2)
    if tail.isdigit():
        return name, int(tail)
    return name, check_label(tail)


@dataclass(frozen=True)
class PartVersion:
    """One immutable version of a part (see the module docstring); ``labels`` point at it now."""

    name: str
    kind: str
    version: int
    uuid: str
    created_at: datetime
    author: str
    attributes: Mapping[str, Any]
    payload: Mapping[str, Any]
    blob_sha256: str | None
    provenance: Mapping[str, Any]
    parent_version: int | None
    record_sha256: str
    labels: tuple[str, ...] = field(default=())

    @property
    def ref(self) -> str:
        """``name@version``."""
        return f"{self.name}@{self.version}"

    def geometry(self) -> dict[str, Any]:
        """What a page or table shows of the payload, in mm: a tool's diameter, length and fluted length;
        a holder's length, bore and mouth diameter; a spindle's source (``model`` at a point, or
        ``measured`` at a node)."""
        p = self.payload
        segs = p.get("segments") if isinstance(p.get("segments"), list) else []
        mm = [s for s in segs if isinstance(s, Mapping)]
        if self.kind == "tool" and mm:
            return {"diameter_mm": 1e3 * float(mm[0].get("diameter", 0.0)),
                    "length_mm": 1e3 * sum(float(s.get("length", 0.0)) for s in mm),
                    "fluted_length_mm": 1e3 * sum(float(s.get("length", 0.0)) for s in mm if s.get("fluted")),
                    "material": p.get("material", "carbide")}
        if self.kind == "holder" and mm:
            return {"length_mm": 1e3 * sum(float(s.get("length", 0.0)) for s in mm),
                    "bore_mm": 1e3 * float(mm[0].get("inner_diameter", 0.0)),
                    "mouth_diameter_mm": 1e3 * float(mm[0].get("outer_diameter", 0.0)),
                    "material": p.get("material", "steel")}
        if self.kind == "spindle":
            if self.blob_sha256 is not None:
                return {"source": "measured", "node": p.get("node")}
            model = p.get("model") if isinstance(p.get("model"), Mapping) else {}
            return {"source": "model", "point": p.get("point"), "model_name": model.get("name", "")}
        return {}

    def to_dict(self) -> dict[str, Any]:
        """The record as JSON-ready values (times as ISO 8601 UTC)."""
        return {"name": self.name, "kind": self.kind, "version": self.version, "uuid": self.uuid,
                "created_at": self.created_at.isoformat(), "author": self.author,
                "attributes": dict(self.attributes), "payload": dict(self.payload),
                "blob_sha256": self.blob_sha256, "provenance": dict(self.provenance),
                "parent_version": self.parent_version, "record_sha256": self.record_sha256,
                "labels": list(self.labels), "geometry": self.geometry()}


def part_record(name: str, kind: str, row: Any) -> dict[str, Any]:
    """Everything that identifies a part version's content (hashed into ``record_sha256``)."""
    return {"name": name, "kind": kind, "version": row.version, "uuid": row.uuid,
            "created_at": row.created_at.isoformat(timespec="microseconds"), "author": row.author,
            "machine": row.machine, "family": row.family, "attributes": dict(row.attributes),
            "payload": dict(row.payload), "blob_sha256": row.blob_sha256, "provenance": dict(row.provenance),
            "parent_version": row.parent_version}


def _check_attributes(kind: str, attributes: Mapping[str, Any] | None) -> dict[str, Any]:
    attrs = dict(attributes or {})
    for key, value in attrs.items():
        if key not in ATTRIBUTES:
            raise InputError(f"attributes.{str(key)[:40]}: unknown attribute; expected one of {', '.join(ATTRIBUTES)}")
        if kind not in ATTRIBUTES[key]:
            raise InputError(f"attributes.{key}: a {kind} has no {key} (it is for {' / '.join(ATTRIBUTES[key])})")
        if key == "bore_mm":
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0.001 <= value <= 10_000:
                raise InputError(f"attributes.bore_mm: must be a number of millimetres in 0.001-10000, got {value!r}")
            attrs[key] = float(value)
        else:
            text = check_text(value if isinstance(value, str) else None, f"attributes.{key}", 200, strict=True)
            if not text.strip():
                raise InputError(f"attributes.{key}: must be a non-empty text")
            attrs[key] = text.strip()
    if kind == "spindle" and "machine" not in attrs:
        raise InputError("attributes.machine: a spindle is catalogued per machine; give the machine's name")
    return dict(sorted(attrs.items()))


def _check_payload(kind: str, payload: Any, frf: FRF | None) -> dict[str, Any]:
    """Validate a part's stack-file object with the stack reader's own rules (no file paths)."""
    from jointdb.stack import _stackfile as sf

    if not isinstance(payload, Mapping):
        raise InputError(f"payload: must be the {kind}'s object of a stack file, got {type(payload).__name__}")
    payload = dict(payload)
    check_stored_json(payload, "payload")
    if kind == "tool":
        sf._tool(payload, "payload")
    elif kind == "holder":
        sf._holder(payload, "payload")
    elif frf is not None:  # a measured spindle: the FRF set is the blob, the payload names its node
        if set(payload) - {"node", "file"} or "node" not in payload:
            raise InputError("payload: a measured spindle's payload is {\"node\": N} (the FRF is stored as a blob)")
        spindle = sf._spindle({"file": str(payload.get("file", "frf")), "node": payload["node"]}, "payload")
        labels = {str(d) for d in frf.outputs}
        if f"{spindle.node}x" not in labels or f"{spindle.node}ry" not in labels:
            raise InputError(f"frf: the spindle-nose FRF needs DOFs {spindle.node}x and {spindle.node}ry "
                             f"(node {spindle.node}); it has {', '.join(sorted(labels))[:200]}")
    else:
        if "file" in payload or not isinstance(payload.get("model"), Mapping):
            raise InputError("payload: a modelled spindle is {\"model\": {beam model}, \"point\": name}; a measured "
                             "one is stored with its FRF (no file paths are read)")
        from jointdb.fe import model_from_dict

        sp = sf._spindle(payload, "payload")
        model = model_from_dict(dict(sp.model))
        if sp.point not in {p.name for p in model.points}:
            raise InputError(f"payload.point: the model has no point {sp.point!r}")
    if frf is not None and kind != "spindle":
        raise InputError(f"frf: only a measured spindle carries an FRF set, not a {kind}")
    return payload


def _to_part(part: PartRow, row: PartVersionRow, labels=()) -> PartVersion:
    return PartVersion(part.name, part.kind, row.version, row.uuid, row.created_at, row.author, dict(row.attributes),
                       dict(row.payload), row.blob_sha256, dict(row.provenance), row.parent_version,
                       row.record_sha256, tuple(sorted(labels)))


def verified_part(part: PartRow, row: PartVersionRow, labels=()) -> PartVersion:
    """The version of a row whose content still hashes to its ``record_sha256``.

    Raises
    ------
    IntegrityError
        A damaged column or a content that differs from what was written (the row was rewritten).
    """
    damaged = [c for c in ("attributes", "payload", "provenance") if isinstance(getattr(row, c), DamagedJSON)
               or not isinstance(getattr(row, c), dict)]
    if damaged or record_sha256(part_record(part.name, part.kind, row)) != row.record_sha256:
        raise IntegrityError(f"part {part.name} v{row.version}: its stored record does not match its hash "
                             "(damaged or rewritten); refusing to use it - run `jointdb db check`")
    return _to_part(part, row, labels)


def _part_row(session: Session, name: str, lock: bool = False) -> PartRow:
    if not isinstance(name, str) or len(name) > 1000 or control_character(name):
        raise InputError(f"part name {str(name)[:60]!r} must be text without control characters")
    q = select(PartRow).where(PartRow.name == name)
    part = session.scalar(q.with_for_update() if lock else q)
    if part is None:
        raise NotFoundError(f"no part named {name!r} (see `jointdb parts list`)")
    return part


def _identity(row: Any) -> tuple:
    return (row.attributes, row.payload, row.blob_sha256)


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
        attrs = _check_attributes(kind, attributes)
        body = _check_payload(kind, payload, frf)
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
        if latest is not None and _identity(latest) == (attrs, body, blob):
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
        """Point ``label`` of a part at ``version`` (created or moved; audited)."""
        label = check_label(label)
        actor = current_actor(author)
        if isinstance(version, bool) or not isinstance(version, int) or version < 1:
            raise InputError(f"version must be a version number >= 1, got {version!r}")
        self.get_part(name, version)  # NotFoundError for an unknown part or version

        def write(s: Session) -> None:
            self._move_part_label(s, _part_row(s, name, lock=True), int(version), label, actor, utcnow())

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

        Raises
        ------
        NotFoundError
            Unknown part, version or label.
        IntegrityError
            The stored record does not match its hash.
        """
        if version is not None and label is not None:
            raise InputError("give a version or a label, not both")
        with self.storage.read() as s:
            part = _part_row(s, name)
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
        """The version a ``name@version`` / ``name@label`` reference names (:func:`parse_part_ref`)."""
        name, tail = parse_part_ref(ref)
        return self.get_part(name, version=tail) if isinstance(tail, int) else self.get_part(name, label=tail)

    @_db.with_db_errors
    def part_history(self, name: str) -> list[PartVersion]:
        """Every version of a part, oldest first, each verified."""
        with self.storage.read() as s:
            part = _part_row(s, name)
            labels = self._part_labels(s, part.id)
            rows = s.scalars(select(PartVersionRow).where(PartVersionRow.part_id == part.id)
                             .order_by(PartVersionRow.version))
            return [verified_part(part, r, labels.get(r.version, ())) for r in rows]

    @_db.with_db_errors
    def list_parts(self, kind: str | None = None, *, family: str | None = None,
                   machine: str | None = None) -> list[PartVersion]:
        """The latest version of every part (by name), optionally of one kind, holder family or machine."""
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
