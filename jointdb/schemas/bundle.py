"""Schema of the metadata in a joint bundle (``jointdb joints export``): the version record
(JSON attribute ``record`` of each version group) and the joint's labels and states."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import Field

from jointdb.schemas._base import Finite, Name, NonNeg, Strict

__all__ = ["VersionRecord", "JointStates"]

Sha256 = Annotated[str, Field(pattern=r"^[0-9a-f]{64}$")]


class RecordConditions(Strict):
    materials: list[str]
    preload_n: NonNeg | None
    torque_nm: NonNeg | None
    geometry: dict[str, NonNeg]
    extra: dict[str, Any]


class Provenance(Strict):
    input_files: dict[str, Sha256] = Field(description="file name -> SHA-256 of the inputs")
    method: str
    parameters: dict[str, Any]
    software_version: Annotated[str, Field(max_length=50)]


class VersionRecord(Strict):
    """Everything that identifies one catalogued version (hashed into its record_sha256)."""

    name: Name
    joint_type: Name
    version: Annotated[int, Field(ge=1)]
    uuid: Annotated[str, Field(pattern=r"^[0-9a-fA-F-]{32,36}$")]
    created_at: str = Field(description="ISO 8601 time")
    author: str
    conditions: RecordConditions
    model_kind: Literal["spring-damper-planar", "n-point-translational", "full-matrix"]
    dofs: list[str]
    quantity: Literal["receptance", "mobility", "accelerance"]
    n_freq: Annotated[int, Field(ge=1)]
    freq_min_hz: Finite
    freq_max_hz: Finite
    blob_sha256: Sha256
    raw_blobs: dict[str, Sha256]
    provenance: Provenance
    parent_version: Annotated[int, Field(ge=1)] | None
    quality: dict[str, Finite]


class State(Strict):
    version: Annotated[int, Field(ge=1)] | None
    state: Literal["active", "deprecated"]
    reason: str
    author: str
    at: str = Field(description="ISO 8601 time")


class JointStates(Strict):
    """A bundled joint's labels (label -> version) and its state changes, in order."""

    labels: dict[str, Annotated[int, Field(ge=1)]]
    states: list[State] = Field(max_length=100_000)
