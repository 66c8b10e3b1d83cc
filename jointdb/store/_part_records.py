"""Part records: names, kinds and references of parts, the :class:`PartVersion` read back, the
checks of a part's attributes and payload, and the record hash verified on every read.

The versioned storage of parts (:class:`jointdb.store._parts.PartsStore`) builds on these.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from datetime import datetime
from typing import Any

from sqlalchemy import select
from sqlalchemy.orm import Session

from jointdb.schemas._limits import check_stored_json, check_text, control_character
from jointdb.errors import InputError, IntegrityError, NotFoundError
from jointdb.frf import FRF
from jointdb.store._models import PartRow, PartVersionRow
from jointdb.store._records import DamagedJSON, record_sha256
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
    """One immutable version of a part (see the module docstring); ``labels`` point at it now.

    Parameters
    ----------
    name, kind
        The part's name and kind (one of :data:`PART_KINDS`: ``spindle``, ``holder``, ``tool``).
    version, uuid
        Version number (1 for the first, +1 per change of content) and a random UUID (text).
    created_at, author
        When (timezone-aware, UTC) and by whom it was catalogued.
    attributes
        What it is found by: ``machine`` (spindles), ``family``, ``taper``, ``bore_mm`` [mm]
        (holders), ``description``.
    payload
        The part's object of a stack file (lengths in m): a tool's or holder's ``material`` and
        ``segments``; a spindle's ``{"model": {beam model}, "point": name}`` or, measured, ``{"node": N}``.
    blob_sha256
        Content hash of a measured spindle's FRF set in the blob store; None for a model.
    provenance, parent_version
        Input files with their SHA-256, method, software version; the version this one follows
        (None for version 1).
    record_sha256
        SHA-256 of the version's content, recomputed and compared on every read.
    labels
        The labels pointing at this version when it was read, sorted.
    """

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
        ``measured`` at a node).

        Returns
        -------
        dict
            A tool: ``diameter_mm`` (of the first segment), ``length_mm``, ``fluted_length_mm``,
            ``material``; a holder: ``length_mm``, ``bore_mm`` and ``mouth_diameter_mm`` (of the first
            segment), ``material``; a spindle: ``source`` (``"measured"`` with ``node``, or ``"model"``
            with ``point`` and ``model_name``); empty for a tool or holder without segments.
        """
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
        """The record as JSON-ready values (times as ISO 8601 UTC).

        Returns
        -------
        dict
            Every field under its name (``labels`` as a list), plus ``geometry`` (:meth:`geometry`).
        """
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


def check_attributes(kind: str, attributes: Mapping[str, Any] | None) -> dict[str, Any]:
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


def check_payload(kind: str, payload: Any, frf: FRF | None) -> dict[str, Any]:
    """Validate a part's stack-file object with the stack reader's own rules (no file paths)."""
    from jointdb.stack import _stackfile as sf

    if not isinstance(payload, Mapping):
        raise InputError(f"payload: must be the {kind}'s object of a stack file, got {type(payload).__name__}")
    payload = dict(payload)
    check_stored_json(payload, "payload")
    if kind == "tool":
        sf.substructure_from_dict("tool", payload, "payload")
    elif kind == "holder":
        sf.substructure_from_dict("holder", payload, "payload")
    elif frf is not None:  # a measured spindle: the FRF set is the blob, the payload names its node
        if set(payload) - {"node", "file"} or "node" not in payload:
            raise InputError("payload: a measured spindle's payload is {\"node\": N} (the FRF is stored as a blob)")
        spindle = sf.substructure_from_dict("spindle", {"file": str(payload.get("file", "frf")), "node": payload["node"]},
                                            "payload")
        labels = {str(d) for d in frf.outputs}
        if f"{spindle.node}x" not in labels or f"{spindle.node}ry" not in labels:
            raise InputError(f"frf: the spindle-nose FRF needs DOFs {spindle.node}x and {spindle.node}ry "
                             f"(node {spindle.node}); it has {', '.join(sorted(labels))[:200]}")
    else:
        if "file" in payload or not isinstance(payload.get("model"), Mapping):
            raise InputError("payload: a modelled spindle is {\"model\": {beam model}, \"point\": name}; a measured "
                             "one is stored with its FRF (no file paths are read)")
        from jointdb.fe import model_from_dict

        sp = sf.substructure_from_dict("spindle", payload, "payload")
        model = model_from_dict(dict(sp.model))
        if sp.point not in {p.name for p in model.points}:
            raise InputError(f"payload.point: the model has no point {sp.point!r}")
    if frf is not None and kind != "spindle":
        raise InputError(f"frf: only a measured spindle carries an FRF set, not a {kind}")
    return payload


def to_part(part: PartRow, row: PartVersionRow, labels=()) -> PartVersion:
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
    return to_part(part, row, labels)


def part_row(session: Session, name: str, lock: bool = False) -> PartRow:
    if not isinstance(name, str) or len(name) > 1000 or control_character(name):
        raise InputError(f"part name {str(name)[:60]!r} must be text without control characters")
    q = select(PartRow).where(PartRow.name == name)
    part = session.scalar(q.with_for_update() if lock else q)
    if part is None:
        raise NotFoundError(f"no part named {name!r} (see `jointdb parts list`)")
    return part


def part_identity(row: Any) -> tuple:
    return (row.attributes, row.payload, row.blob_sha256)
