"""Value types of the joint database: conditions, provenance, versions, matches.

Everything here is a small frozen dataclass validated on construction; the
validation is what guarantees that bad input never reaches the database
(bad input never writes anything).
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from datetime import datetime
from typing import Any

from jointdb.schemas import _limits
from jointdb.errors import InputError
from jointdb.frf import FRF
from jointdb.store._vocabulary import (  # re-exported (__all__): the vocabulary of the value types
    KNOWN_MATERIALS,
    MATERIAL_ALIASES,
    MODEL_KINDS,
    check_joint_type,
    check_label,
    check_model_kind,
    check_name,
    finite_nonneg,
    known_materials,
    normalise_material,
    register_material,
)

__all__ = [
    "KNOWN_MATERIALS",
    "MATERIAL_ALIASES",
    "MODEL_KINDS",
    "Conditions",
    "Provenance",
    "JointVersion",
    "Match",
    "InterpolatedJoint",
    "known_materials",
    "register_material",
    "normalise_material",
    "check_model_kind",
    "check_joint_type",
    "check_name",
    "check_label",
]

@dataclass(frozen=True)
class Conditions:
    """The conditions a joint was identified under (part of every joint record).

    Parameters
    ----------
    materials
        Interface materials, e.g. ``("tungsten-carbide", "steel")``; names from
        :func:`known_materials` (aliases such as ``carbide`` are normalised).
    preload_n
        Axial preload in N (>= 0), or None when not applicable / unknown.
    torque_nm
        Tightening torque in N·m (>= 0), or None.
    geometry
        Geometry numbers in SI units, e.g. ``{"diameter_m": 0.02, "insertion_m": 0.045}``.
    extra
        Free-form JSON-serialisable details (not used for ranking).

    Raises
    ------
    InputError
        For unknown materials, negative or non-finite numbers, non-numeric geometry.
    """

    materials: tuple[str, ...] = ()
    preload_n: float | None = None
    torque_nm: float | None = None
    geometry: Mapping[str, float] = field(default_factory=dict)
    extra: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        mats = self.materials
        if isinstance(mats, str):
            mats = tuple(m for m in re.split(r"[,+/]", mats) if m.strip())
        object.__setattr__(self, "materials", tuple(normalise_material(m) for m in mats))
        object.__setattr__(self, "preload_n", finite_nonneg(self.preload_n, "preload_n [N]"))
        object.__setattr__(self, "torque_nm", finite_nonneg(self.torque_nm, "torque_nm [N·m]"))
        geometry: dict[str, float] = {}
        for key, value in dict(self.geometry or {}).items():
            k = str(key).strip()
            if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_.-]*", k) or len(k) > _limits.MAX_KEY_CHARS:
                raise InputError(f"geometry key {key!r} must be a simple name like 'diameter_m'")
            x = finite_nonneg(value, f"geometry[{k!r}]")
            geometry[k] = x  # type: ignore[assignment]
        object.__setattr__(self, "geometry", dict(sorted(geometry.items())))
        _limits.check_count(len(self.materials), "conditions.materials", _limits.MAX_MATERIALS, "materials")
        _limits.check_count(len(geometry), "conditions.geometry", _limits.MAX_GEOMETRY_KEYS, "keys")
        if not isinstance(self.extra or {}, Mapping):
            raise InputError(f"conditions.extra must be a JSON object, got {type(self.extra).__name__}")
        extra = dict(self.extra or {})
        _limits.check_stored_json(extra, "conditions.extra")  # depth, size, text, finite numbers
        object.__setattr__(self, "extra", extra)

    def to_dict(self) -> dict[str, Any]:
        """The conditions as a JSON-ready dict (read back by :meth:`from_dict`).

        Returns
        -------
        dict
            ``materials``, ``preload_n``, ``torque_nm``, ``geometry``, ``extra``.
        """
        return {
            "materials": list(self.materials),
            "preload_n": self.preload_n,
            "torque_nm": self.torque_nm,
            "geometry": dict(self.geometry),
            "extra": dict(self.extra),
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> "Conditions":
        """Conditions from their dict form (as :meth:`to_dict` writes it).

        Parameters
        ----------
        data
            ``materials``, ``preload_n`` [N], ``torque_nm`` [N·m], ``geometry`` [m], ``extra``.

        Returns
        -------
        Conditions
            The conditions in SI units, checked.

        Raises
        ------
        InputError
            A field of the wrong shape, or a value :class:`Conditions` refuses.
        """
        mats = data.get("materials") or ()
        if not isinstance(mats, (str, list, tuple)) or not all(isinstance(m, str) for m in
                                                                 ([mats] if isinstance(mats, str) else mats)):
            raise InputError("conditions.materials must be a list of material names")
        for key in ("geometry", "extra"):
            if not isinstance(data.get(key) or {}, Mapping):
                raise InputError(f"conditions.{key} must be a JSON object, got {type(data.get(key)).__name__}")
        return cls(
            materials=tuple([mats] if isinstance(mats, str) else mats),
            preload_n=data.get("preload_n"),
            torque_nm=data.get("torque_nm"),
            geometry=dict(data.get("geometry") or {}),
            extra=dict(data.get("extra") or {}),
        )


@dataclass(frozen=True)
class Provenance:
    """Where a joint version came from.

    Parameters
    ----------
    method
        How the joint was obtained (``"irc-planar"``, ``"output-error"``, ...).
    parameters
        The method's settings (JSON-serialisable).
    input_files
        File name → SHA-256 (hex) of its bytes (see :func:`jointdb.store.file_sha256`).
    software_version
        The jointdb version that produced it (filled in when catalogued).
    author
        Who produced it.
    """

    method: str = "unspecified"
    parameters: Mapping[str, Any] = field(default_factory=dict)
    input_files: Mapping[str, str] = field(default_factory=dict)
    software_version: str = ""
    author: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.method, str) or not self.method.strip():
            raise InputError("provenance method must be a non-empty text")
        _limits.check_text(self.method.strip(), "provenance.method", 200, strict=True)
        for attr, limit in (("software_version", 50), ("author", 200)):
            if getattr(self, attr):
                _limits.check_text(getattr(self, attr), f"provenance.{attr}", limit, strict=True)
        for attr in ("parameters", "input_files"):
            if not isinstance(getattr(self, attr) or {}, Mapping):
                raise InputError(f"provenance.{attr} must be a JSON object, got {type(getattr(self, attr)).__name__}")
        _limits.check_stored_json(dict(self.parameters or {}), "provenance.parameters")
        files = {}
        _limits.check_count(len(self.input_files or {}), "provenance.input_files", _limits.MAX_INPUT_FILES, "files")
        for key, digest in dict(self.input_files or {}).items():
            _limits.check_text(key, "provenance.input_files key", _limits.MAX_KEY_CHARS, strict=True)
            d = str(digest).lower()
            if not re.fullmatch(r"[0-9a-f]{64}", d):
                raise InputError(f"input file hash for {key!r} must be a SHA-256 hex digest, got {str(digest)[:80]!r}")
            files[str(key)] = d
        object.__setattr__(self, "input_files", dict(sorted(files.items())))
        object.__setattr__(self, "parameters", dict(self.parameters or {}))
        object.__setattr__(self, "method", str(self.method).strip())


# --------------------------------------------------------------------------- records
@dataclass(frozen=True)
class JointVersion:
    """One immutable catalogued version of a joint (a database row, detached).

    ``state`` and ``labels`` are as of the time of the query that returned it; every other
    field never changes.

    Attributes
    ----------
    name, joint_type, version
        The joint's name and type, and the version number (1, 2, ...).
    uuid
        A unique id of this version.
    created_at
        When it was catalogued (UTC).
    conditions
        The :class:`Conditions` it was identified under.
    model_kind
        One of :data:`MODEL_KINDS`.
    dofs
        DOF labels of the joint FRF.
    quantity
        The FRF's quantity (``"receptance"``).
    n_freq, freq_min_hz, freq_max_hz
        Number of lines and band [Hz] of the FRF.
    blob_sha256
        SHA-256 of the FRF's canonical form (its blob's name).
    provenance
        The :class:`Provenance`.
    parent_version
        The version this one derives from, or None.
    quality
        Named quality numbers.
    raw_blobs
        Raw measurement key → blob SHA-256.
    record_sha256
        SHA-256 of the version record (verified on every read).
    state
        ``"active"`` or ``"deprecated"``.
    labels
        The labels pointing at this version.
    """

    name: str
    joint_type: str
    version: int
    uuid: str
    created_at: datetime
    conditions: Conditions
    model_kind: str
    dofs: tuple[str, ...]
    quantity: str
    n_freq: int
    freq_min_hz: float
    freq_max_hz: float
    blob_sha256: str
    provenance: Provenance
    parent_version: int | None
    quality: Mapping[str, float]
    raw_blobs: Mapping[str, str]
    record_sha256: str
    state: str = "active"
    labels: tuple[str, ...] = ()

    def summary(self) -> dict[str, Any]:
        """A flat row for tables.

        Returns
        -------
        dict
            name, type, version, state, labels, materials, preload, torque, model kind, band, date, author.
        """
        c = self.conditions
        return {
            "name": self.name,
            "type": self.joint_type,
            "version": self.version,
            "state": self.state,
            "labels": ",".join(self.labels) or None,
            "materials": "+".join(c.materials) or None,
            "preload_n": c.preload_n,
            "torque_nm": c.torque_nm,
            "model_kind": self.model_kind,
            "f_hz": f"{self.freq_min_hz:g}-{self.freq_max_hz:g}",
            "created_at": self.created_at.strftime("%Y-%m-%d %H:%M:%S"),
            "author": self.provenance.author,
        }


@dataclass(frozen=True)
class Match:
    """One answer of :meth:`Repository.nearest`.

    Attributes
    ----------
    version
        The catalogued :class:`JointVersion`.
    distance
        The Euclidean norm of ``per_condition`` (dimensionless).
    per_condition
        Condition name → normalised distance (defined in :mod:`jointdb.store._query`).
    extrapolating
        True when the request lies outside the catalogued range of some condition.
    outside_range
        Those conditions.
    """

    version: JointVersion
    distance: float
    per_condition: Mapping[str, float]
    extrapolating: bool = False
    outside_range: tuple[str, ...] = ()


@dataclass(frozen=True)
class InterpolatedJoint:
    """A joint FRF interpolated between catalogued neighbours (NOT a catalogued joint).

    ``frf`` is a receptance obtained by weighting the neighbours' dynamic
    stiffness ``Z = H⁻¹`` on their common frequency band (weights of the joints
    bracketing the request along the condition axes, or inverse distance; see
    :mod:`jointdb.store._query`).

    Attributes
    ----------
    frf
        The interpolated receptance.
    joint_type
        The neighbours' joint type.
    conditions
        The request.
    neighbours
        ``(name, version, weight)`` of the neighbours with weight > 0.
    label
        ``"interpolated"``.
    passivity_moved
        ``(name, version, n_lines)`` of the neighbours whose weight for the loss (Im Z) was given to the
        passive ones on ``n_lines`` lines where they are non-passive and the weighted average would be too
        (:func:`jointdb.store._query.passive_line_weights`).
    """

    frf: FRF
    joint_type: str
    conditions: Conditions
    neighbours: tuple[tuple[str, int, float], ...]
    label: str = "interpolated"
    passivity_moved: tuple[tuple[str, int, int], ...] = ()

    def describe(self) -> str:
        """One line naming the neighbours and their weights.

        Returns
        -------
        str
        """
        parts = ", ".join(f"{n} v{v} (w={w:.3f})" for n, v, w in self.neighbours)
        return f"INTERPOLATED {self.joint_type} joint from {parts}"


def as_conditions(value: "Conditions | Mapping[str, Any] | None") -> Conditions:
    if value is None:
        return Conditions()
    if isinstance(value, Conditions):
        return value
    if isinstance(value, Mapping):
        return Conditions.from_dict(value)
    raise InputError(f"conditions must be a Conditions or a mapping, got {type(value).__name__}")


def as_provenance(value: "Provenance | Mapping[str, Any] | None") -> Provenance:
    if value is None:
        return Provenance()
    if isinstance(value, Provenance):
        return value
    if isinstance(value, Mapping):
        unknown = sorted(str(k)[:40] for k in value if k not in _PROVENANCE_FIELDS)
        if unknown:
            raise InputError(f"provenance has unknown fields {', '.join(unknown)}; "
                             f"known: {', '.join(_PROVENANCE_FIELDS)}")
        return Provenance(**dict(value))
    raise InputError(f"provenance must be a Provenance or a mapping, got {type(value).__name__}")


_PROVENANCE_FIELDS = ("method", "parameters", "input_files", "software_version", "author")


def as_quality(value: Mapping[str, Any] | None) -> dict[str, float]:
    """Quality metrics as ``{name: finite float}``; InputError naming the metric otherwise."""
    if not isinstance(value or {}, Mapping):
        raise InputError(f"quality must map metric names to numbers, got {type(value).__name__}")
    _limits.check_count(len(value or {}), "quality", _limits.MAX_QUALITY_METRICS, "metrics")
    out: dict[str, float] = {}
    for key, v in dict(value or {}).items():
        _limits.check_text(key, "quality metric name", _limits.MAX_KEY_CHARS, strict=True)
        if isinstance(v, bool):
            raise InputError(f"quality metric {key!r} must be a number, got {v!r}")
        try:
            x = float(v)
        except (TypeError, ValueError):
            raise InputError(f"quality metric {key!r} must be a number, got {str(v)[:40]!r}") from None
        if not math.isfinite(x) or abs(x) > _limits.MAX_JSON_NUMBER:
            raise InputError(f"quality metric {key!r} must be finite and of magnitude <= "
                             f"{_limits.MAX_JSON_NUMBER:g}, got {v!r}")
        out[str(key)] = x
    return dict(sorted(out.items()))
