"""Schema of a campaign file (``jointdb-campaign/1``; read by :func:`jointdb.campaign.load_campaign`)."""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import ConfigDict, Field, model_validator

from jointdb.schemas._base import DofLabel, Finite, Name, NonNeg, Positive, Strict

__all__ = ["CampaignFile"]

FilePath = Annotated[str, Field(min_length=1, description="path relative to the campaign file")]


class Substructure(Strict):
    """A substructure: a beam model file or a UFF58 file of its FRFs (exactly one of the two)."""

    model_config = ConfigDict(json_schema_extra={"oneOf": [{"required": ["model"]}, {"required": ["uff58"]}]})

    model: FilePath | None = Field(default=None, description="beam model file (jointdb-beam-model/1)")
    uff58: FilePath | None = Field(default=None,
                                   description="UFF58 file with the substructure's FRFs (rotations included)")
    dofs: list[DofLabel] | None = None
    provenance: dict[str, Any] | None = Field(
        default=None, description="where a derived substructure came from: the catalogued parts and joint "
                                  "versions `jointdb campaign init --spindle --holder --through-joint` built it from "
                                  "(recorded, not read by identify)")

    @model_validator(mode="after")
    def _one_source(self):
        if (self.model is None) == (self.uff58 is None):
            raise ValueError('give exactly one of "model" (beam model JSON) or "uff58" (FRF file)')
        return self


class Interface(Strict):
    a: Name
    a_dofs: list[DofLabel] = Field(min_length=1)
    b: Name
    b_dofs: list[DofLabel] = Field(min_length=1)


class Conditions(Strict):
    materials: list[Annotated[str, Field(min_length=1, max_length=100)]] | None = Field(
        default=None, max_length=10, description="interface materials, names the catalogue knows (extensible: JOINTDB_MATERIALS)")
    torque_nm: NonNeg | None = Field(default=None, description="tightening torque, N·m")
    preload_n: NonNeg | None = Field(default=None, description="axial preload, N")
    geometry: dict[str, NonNeg] | None = Field(default=None, description="geometry numbers in SI, e.g. diameter_m")
    extra: dict[str, Any] | None = None


class PlanarOptions(Strict):
    b_tip: int = Field(description="node number of B's free end (the tip)")


class NPointOptions(Strict):
    internal: list[DofLabel] = Field(min_length=1, description="measured DOFs on A")


class MatrixOptions(Strict):
    measured: list[Annotated[list[str], Field(min_length=2, max_length=2)]] = Field(
        min_length=1, description="[substructure, DOF] pairs measured on the assembly")


class Options(Strict):
    smoothing: Annotated[int, Field(ge=3)] | None = Field(default=None, description="Savitzky–Golay window (odd)")
    smoothing_order: Annotated[int, Field(ge=0)] | None = None
    regularisation: str | None = Field(default=None, description="none, tsvd:r or tikhonov:r")
    fit_band: Annotated[list[NonNeg], Field(min_length=2, max_length=2)] | None = Field(
        default=None, description="band of the constant (k, c) fit, Hz")
    symmetrize: bool | None = None
    diagonal: bool | None = None
    method: Literal["output-error", "irc"] | None = Field(
        default=None, description="output-error: fit k, c to all lines at once, with standard errors (default for "
                                  "planar and n-point); irc: the per-line joint (default for the matrix model)")


class Validation(Strict):
    substructures: dict[str, Substructure] = Field(min_length=1)
    measurements: list[FilePath] = Field(min_length=1)


class SpringDamper(Strict):
    """A joint of independent spring–dampers on the interface's ``a_dofs`` (in their order)."""

    k: list[Positive] = Field(min_length=1, max_length=1000,
                              description="stiffness per a_dof: N/m (translation), N·m/rad (rotation)")
    c: list[NonNeg] = Field(min_length=1, max_length=1000,
                            description="viscous damping per a_dof: N·s/m, N·m·s/rad")


class CoupleFrequency(Strict):
    """Frequency lines of `jointdb couple` when the campaign has no measurements to take them from."""

    min: Positive = Field(description="first line, Hz (> 0: a free part has no static receptance)")
    max: Positive = Field(description="last line, Hz")
    step: Positive = Field(description="line spacing, Hz")


DofPair = Annotated[list[Annotated[str, Field(min_length=1, max_length=100)]],
                    Field(min_length=2, max_length=2, description='[substructure, DOF], e.g. ["tool", "1x"]')]


class Couple(Strict):
    """What `jointdb couple` computes (docs/file-formats.md, *The couple section*)."""

    joint: Annotated[str, Field(min_length=1)] | SpringDamper | None = Field(
        default=None, description='"rigid" (default), a joint HDF5 file from `jointdb identify` (relative to the '
                                  'campaign file), or {"k": [...], "c": [...]} per a_dof; `--joint FILE` overrides it')
    outputs: list[DofPair] | None = Field(
        default=None, max_length=1000, description="response DOFs [substructure, DOF] (rotations allowed, e.g. "
                                                   '["holder", "3ry"]); default: the measured ones')
    inputs: list[DofPair] | None = Field(
        default=None, max_length=1000, description="excitation DOFs [substructure, DOF]; default: the outputs")
    frequency: CoupleFrequency | None = Field(
        default=None, description="lines to couple on; default: the measurements' lines")


class CampaignFile(Strict):
    """A joint identification test: substructures, interface, measured assembly FRFs, joint model."""

    format: Literal["jointdb-campaign/1"]
    name: Name | None = None
    description: str | None = None
    joint_type: Name | None = None
    conditions: Conditions | None = None
    joint_model: Literal["planar", "n-point", "matrix"]
    substructures: dict[str, Substructure] = Field(min_length=1)
    interface: Interface
    measurements: list[FilePath] = Field(default_factory=list, description="UFF58 files of the assembly")
    band: Annotated[list[NonNeg], Field(min_length=2, max_length=2)] | None = Field(default=None, description="Hz")
    planar: PlanarOptions | None = None
    n_point: NPointOptions | None = None
    matrix: MatrixOptions | None = None
    options: Options | None = None
    validation: Validation | None = None
    couple: Couple | None = Field(default=None, description="what `jointdb couple` computes")
