"""Schema of a beam model file (``jointdb-beam-model/1``; read by :func:`jointdb.fe.load_model`)."""

from __future__ import annotations

from typing import Annotated, Literal, Union

from pydantic import Field

from jointdb.schemas._base import DirectionMap, Finite, Length, Name, NonNeg, Position, Positive, Strict

__all__ = ["BeamModelFile", "InlineMaterial"]


class InlineMaterial(Strict):
    """An isotropic material given by its constants."""

    name: Name | None = None
    E: Annotated[float, Field(allow_inf_nan=False, ge=1e5, le=1e13, description="Young's modulus [Pa]")]
    nu: Annotated[float, Field(allow_inf_nan=False, gt=-1.0, lt=0.5, description="Poisson's ratio [-]")]
    rho: Annotated[float, Field(allow_inf_nan=False, ge=1.0, le=1e5, description="density [kg/m^3]")]


MaterialRef = Union[Annotated[str, Field(min_length=1, description="a library or file-defined material name")],
                    InlineMaterial]


class Segment(Strict):
    length: Length
    outer_diameter: Length
    inner_diameter: Annotated[float, Field(allow_inf_nan=False, ge=0.0, le=100.0, description="m (0: solid)")] = 0.0
    material: MaterialRef = "steel"
    label: str | None = None


class Point(Strict):
    name: Name
    position: Position
    node: Annotated[int, Field(ge=0, le=10**9, description="measurement node number")]


class Clamp(Strict):
    position: Position
    directions: list[Literal["x", "y", "z", "rx", "ry", "rz"]] | None = None


class Support(Strict):
    position: Position
    stiffness: DirectionMap = Field(default_factory=dict, description="N/m or N·m/rad per direction")
    damping: DirectionMap = Field(default_factory=dict, description="N·s/m or N·m·s/rad per direction")


class PointMass(Strict):
    position: Position
    mass: Annotated[float, Field(allow_inf_nan=False, ge=0.0, le=1e300, description="kg")]
    rotary_inertia: NonNeg | None = Field(default=None, description="kg·m² about a transverse axis")
    polar_inertia: NonNeg | None = Field(default=None, description="kg·m² about the axis")
    label: str | None = None


class Joint(Strict):
    position: Position
    stiffness: DirectionMap = Field(description="N/m or N·m/rad per direction; directions not given stay rigid")
    damping: DirectionMap | None = None
    loss_factor: NonNeg | None = None
    label: str | None = None


class ContactLayer(Strict):
    stiffness_per_length: DirectionMap = Field(description="N/m² per direction (a Winkler layer)")
    loss_factor: NonNeg | None = None


class Insertion(Strict):
    start: Position
    end: Position
    outer_diameter: Length
    inner_diameter: Annotated[float, Field(allow_inf_nan=False, ge=0.0, le=100.0)] = 0.0
    material: MaterialRef = "steel"
    joined_at: Literal["start", "end"] = Field(default="end", description="the end that continues as the main beam (the mouth)")
    contact: Literal["rigid"] | ContactLayer = "rigid"
    label: str | None = None


class ModalDamping(Strict):
    type: Literal["modal"]
    zeta: NonNeg | list[NonNeg] = Field(description="damping ratio, one for all modes or one per mode")


class RayleighDamping(Strict):
    type: Literal["rayleigh"]
    alpha: NonNeg = 0.0
    beta: NonNeg = 0.0


class HystereticDamping(Strict):
    type: Literal["hysteretic"]
    eta: NonNeg = Field(description="loss factor")


Damping = Annotated[Union[ModalDamping, RayleighDamping, HystereticDamping], Field(discriminator="type")]


class BeamModelFile(Strict):
    """A stepped shaft of circular segments (SI units); positions are metres from z = 0."""

    format: Literal["jointdb-beam-model/1"] = "jointdb-beam-model/1"
    name: str | None = None
    description: str | None = None
    source: str | None = None
    kind: Literal["planar", "frame3d"] = "planar"
    theory: Literal["timoshenko", "euler-bernoulli"] = "timoshenko"
    max_element_length: Positive = Field(default=0.005, description="m")
    materials: dict[str, MaterialRef] = Field(default_factory=dict,
                                              description="materials defined in this file, by name")
    segments: list[Segment] = Field(min_length=1, max_length=1000)
    points: list[Point] = Field(default_factory=list, max_length=1000)
    clamps: list[Clamp] = Field(default_factory=list, max_length=1000)
    supports: list[Support] = Field(default_factory=list, max_length=1000)
    point_masses: list[PointMass] = Field(default_factory=list, max_length=1000)
    joints: list[Joint] = Field(default_factory=list, max_length=1000)
    insertions: list[Insertion] = Field(default_factory=list, max_length=1000)
    damping: Damping | list[Damping] = Field(default_factory=list)
