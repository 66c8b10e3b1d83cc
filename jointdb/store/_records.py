"""Conversions between database rows and the public value types, record hashes."""

from __future__ import annotations

import getpass
import hashlib
import itertools
import json
import os
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from datetime import datetime, timezone
from typing import TYPE_CHECKING, Any

from jointdb.schemas._limits import (
    MAX_FIELD_BYTES,
    MAX_FIELD_ENTRIES,
    MAX_JSON_NUMBER,
    check_stored_json,
    check_text,
)
from jointdb.errors import InputError, IntegrityError
from jointdb.store._types import Conditions, JointVersion, Provenance

if TYPE_CHECKING:  # pragma: no cover - the models import SQLAlchemy, which the query path avoids
    from jointdb.store._models import JointRow, StateRow, VersionRow


#: Largest encoded stored JSON column read back (a write allows MAX_FIELD_BYTES per free-form field).
MAX_RECORD_BYTES = 4 * MAX_FIELD_BYTES


def current_actor(author: str | None = None) -> str:
    """Who is acting: the given author, ``JOINTDB_AUTHOR``, or the login name."""
    if author:
        return check_text(str(author)[:200], "author", 200, strict=True)
    env = os.environ.get("JOINTDB_AUTHOR")
    if env:
        return check_text(env[:200], "JOINTDB_AUTHOR", 200, strict=True)
    try:
        return getpass.getuser()[:200]
    except (KeyError, OSError):  # no passwd entry in some containers
        return "unknown"


def software_version() -> str:
    from jointdb import __version__

    return __version__


def as_utc(at: datetime | str | None) -> datetime | None:
    if at is None:
        return None
    if isinstance(at, str):
        try:
            at = datetime.fromisoformat(at)
        except ValueError:
            raise InputError(f"cannot read time {at!r}; use ISO 8601, e.g. 2026-01-31T12:00:00Z") from None
    if at.tzinfo is None:
        at = at.replace(tzinfo=timezone.utc)
    return at.astimezone(timezone.utc)


def record_dict(joint_name: str, joint_type: str, row: "VersionRow") -> dict[str, Any]:
    """Everything that identifies a version's content (hashed into ``record_sha256``)."""
    return {
        "name": joint_name,
        "joint_type": joint_type,
        "version": row.version,
        "uuid": row.uuid,
        "created_at": row.created_at.isoformat(timespec="microseconds"),
        "author": row.author,
        "conditions": {
            "materials": list(row.materials),
            "preload_n": row.preload_n,
            "torque_nm": row.torque_nm,
            "geometry": dict(row.geometry),
            "extra": dict(row.extra),
        },
        "model_kind": row.model_kind,
        "dofs": list(row.dofs),
        "quantity": row.quantity,
        "n_freq": row.n_freq,
        "freq_min_hz": row.freq_min_hz,
        "freq_max_hz": row.freq_max_hz,
        "blob_sha256": row.blob_sha256,
        "raw_blobs": dict(row.raw_blobs),
        "provenance": {
            "input_files": dict(row.input_files),
            "method": row.method,
            "parameters": dict(row.method_params),
            "software_version": row.software_version,
        },
        "parent_version": row.parent_version,
        "quality": dict(row.quality),
    }


def record_sha256(record: Mapping[str, Any]) -> str:
    text = json.dumps(record, sort_keys=True, separators=(",", ":"), allow_nan=False, ensure_ascii=True)
    return hashlib.sha256(text.encode()).hexdigest()


class DamagedJSON(dict):
    """What a JSON column that cannot be decoded reads as (empty, so generic code goes on; every
    record check then refuses the row, see :func:`stored_problem`)."""


class DamagedRecordWarning(UserWarning):
    """A list skipped versions whose stored rows are damaged (named in the message)."""


@dataclass(frozen=True)
class DamagedVersion:
    """A version a listing skipped because its stored row cannot be used.

    Attributes
    ----------
    name, version
        The joint and version number.
    reason
        Why its row cannot be used.
    """

    name: str
    version: int
    reason: str

    def describe(self) -> str:
        """One line: the version and why it was skipped.

        Returns
        -------
        str
        """
        return f"{self.name} v{self.version}: {self.reason}"


def load_stored_json(text: str | bytes) -> Any:
    """Decode a JSON column; a :class:`DamagedJSON` instead of an exception for text that is not
    JSON (a damaged file), too deep to decode, or not text at all (the engines' ``json_deserializer``)."""
    try:
        if isinstance(text, bytes):
            text = text.decode("utf-8")
        return json.loads(text)
    except (ValueError, TypeError, RecursionError):  # JSONDecodeError and UnicodeDecodeError are ValueErrors
        return DamagedJSON()


#: Stored JSON columns and the shape each must have: (column, container, item check).
_SHAPES = (("materials", list, "text"), ("geometry", dict, "number"), ("extra", dict, None),
           ("dofs", list, "text"), ("raw_blobs", dict, "text"), ("input_files", dict, "text"),
           ("method_params", dict, None), ("quality", dict, "number"))


def _flat_within_limits(value: dict | list) -> bool:
    """Whether a stored JSON value is certainly within what :func:`check_stored_json` accepts on
    reading back, without walking it there: one level of texts, finite numbers (magnitude
    <= ``MAX_JSON_NUMBER``), booleans and nulls under text keys, few entries, and an encoded size
    that is bounded above (at most 6 bytes per character: UTF-8 or a JSON escape; at most 310
    per number) by ``MAX_RECORD_BYTES``. False means: check it in full (it may still be fine)."""
    if len(value) > MAX_FIELD_ENTRIES:
        return False
    size = 2
    for key, x in (value.items() if isinstance(value, dict) else zip(itertools.repeat(""), value)):
        if not isinstance(key, str):
            return False
        if isinstance(x, str):
            size += 6 * (len(key) + len(x)) + 6
        elif x is None or isinstance(x, bool):
            size += 6 * len(key) + 9
        elif isinstance(x, (int, float)) and x == x and abs(x) <= MAX_JSON_NUMBER:  # x == x: not NaN
            size += 6 * len(key) + 316
        else:
            return False
    return size <= MAX_RECORD_BYTES


def stored_problem(row: Any) -> str | None:
    """Why a stored version row cannot be used (None when its fields have the catalogue's shapes and
    limits): a JSON column that is not JSON, of the wrong shape, or beyond the record limits of
    :mod:`jointdb.schemas._limits` (e.g. nested deeper than a write accepts today)."""
    for column, container, kind in _SHAPES:
        value = getattr(row, column, None)
        if isinstance(value, DamagedJSON):
            return f"column {column} is not readable JSON"
        if not isinstance(value, container):
            return f"column {column} is not a JSON {'list' if container is list else 'object'}"
        if not value:  # empty (extra, raw_blobs, parameters often are): of every kind and within limits
            continue
        items = value.values() if isinstance(value, dict) else value
        if kind == "text":  # inlined: this runs for every row of every read
            fine = all(isinstance(x, str) for x in items)
        elif kind == "number":
            fine = all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in items)
        else:
            fine = True
        if not fine:
            return f"column {column} holds values of the wrong kind"
        if _flat_within_limits(value):  # the usual row: nothing to walk
            continue
        try:
            check_stored_json(value, column, max_bytes=MAX_RECORD_BYTES, texts=False)
        except InputError as exc:
            return f"column {exc}"
    for column in ("uuid", "author", "model_kind", "quantity", "blob_sha256", "method", "software_version",
                   "record_sha256"):
        if not isinstance(getattr(row, column, None), str):
            return f"column {column} is not text"
    return None


def check_record(joint_name: str, joint_type: str, row: "VersionRow") -> None:
    """Refuse a version row that is damaged (:func:`stored_problem`) or whose content no longer hashes
    to its ``record_sha256``.

    Raises
    ------
    IntegrityError
        Naming joint and version: the row (or the joint's name or type) was altered after it was
        written, or the database file is damaged there.
    """
    problem = stored_problem(row)
    if problem:
        raise IntegrityError(f"{joint_name} v{row.version}: stored record is damaged ({problem}); refusing to use "
                             "it - run `jointdb db check`")
    try:
        ok = record_sha256(record_dict(joint_name, joint_type, row)) == row.record_sha256
    except (TypeError, ValueError, AttributeError, RecursionError):  # a stored field of the wrong shape
        ok = False
    if not ok:
        raise IntegrityError(
            f"{joint_name} v{row.version}: stored record does not match its record hash (the row was altered "
            "or the database is damaged); refusing to use it - run `jointdb db check`"
        )


def row_from_record(record: Mapping[str, Any], joint_id: int) -> "VersionRow":
    """A new VersionRow from a record dict (bundle import)."""
    from jointdb.store._models import VersionRow

    c = record["conditions"]
    p = record["provenance"]
    return VersionRow(
        joint_id=joint_id,
        version=int(record["version"]),
        uuid=str(record["uuid"]),
        created_at=datetime.fromisoformat(record["created_at"]),
        author=str(record["author"]),
        materials=list(c["materials"]),
        preload_n=c["preload_n"],
        torque_nm=c["torque_nm"],
        geometry=dict(c["geometry"]),
        extra=dict(c["extra"]),
        model_kind=str(record["model_kind"]),
        dofs=list(record["dofs"]),
        quantity=str(record["quantity"]),
        n_freq=int(record["n_freq"]),
        freq_min_hz=float(record["freq_min_hz"]),
        freq_max_hz=float(record["freq_max_hz"]),
        blob_sha256=str(record["blob_sha256"]),
        raw_blobs=dict(record["raw_blobs"]),
        input_files=dict(p["input_files"]),
        method=str(p["method"]),
        method_params=dict(p["parameters"]),
        software_version=str(p["software_version"]),
        parent_version=record["parent_version"],
        quality=dict(record["quality"]),
        record_sha256=record_sha256(record),
    )


def state_of(version: int, states: Iterable["StateRow"]) -> str:
    """State of one version given the joint's state rows (already filtered by time)."""
    best: tuple[datetime, int] | None = None
    state = "active"
    for s in states:
        if s.version is not None and s.version != version:
            continue
        key = (s.at, s.id)
        if best is None or key > best:
            best, state = key, s.state
    return state


def to_version(joint: "JointRow", row: "VersionRow", state: str = "active", labels: Iterable[str] = (),
               verify: bool = True) -> JointVersion:
    """The public value of a row, after :func:`check_record` (every read verifies the record hash;
    ``verify=False`` only for the row a writer just built and hashed itself, never for one read)."""
    if verify:
        check_record(joint.name, joint.joint_type, row)
    conditions = Conditions.__new__(Conditions)  # stored data was validated on the way in
    object.__setattr__(conditions, "materials", tuple(row.materials))
    object.__setattr__(conditions, "preload_n", row.preload_n)
    object.__setattr__(conditions, "torque_nm", row.torque_nm)
    object.__setattr__(conditions, "geometry", dict(row.geometry))
    object.__setattr__(conditions, "extra", dict(row.extra))
    provenance = Provenance.__new__(Provenance)
    object.__setattr__(provenance, "method", row.method)
    object.__setattr__(provenance, "parameters", dict(row.method_params))
    object.__setattr__(provenance, "input_files", dict(row.input_files))
    object.__setattr__(provenance, "software_version", row.software_version)
    object.__setattr__(provenance, "author", row.author)
    return JointVersion(
        name=joint.name,
        joint_type=joint.joint_type,
        version=row.version,
        uuid=row.uuid,
        created_at=row.created_at,
        conditions=conditions,
        model_kind=row.model_kind,
        dofs=tuple(row.dofs),
        quantity=row.quantity,
        n_freq=row.n_freq,
        freq_min_hz=row.freq_min_hz,
        freq_max_hz=row.freq_max_hz,
        blob_sha256=row.blob_sha256,
        provenance=provenance,
        parent_version=row.parent_version,
        quality=dict(row.quality),
        raw_blobs=dict(row.raw_blobs),
        record_sha256=row.record_sha256,
        state=state,
        labels=tuple(sorted(labels)),
    )
