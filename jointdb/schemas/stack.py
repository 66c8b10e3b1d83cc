"""Schema of a stack file (``jointdb-stack/1``; read by :func:`jointdb.usecases.load_stack`)."""

from __future__ import annotations

from typing import Annotated, Any, Literal, Union

from pydantic import Field

from jointdb.schemas._base import Length, Name, NonNeg, Positive, Strict
from jointdb.schemas.model import BeamModelFile
from jointdb.stack._spec import KOPS_VO_RATIO

__all__ = ["StackFile"]


class ToolSegment(Strict):
    length: Length
    diameter: Length
    fluted: bool = Field(default=False, description="a fluted section (modelled at fluted_ratio × diameter)")


class Tool(Strict):
    """The tool, described from its tip; fluted sections first."""

    material: str = "carbide"
    segments: list[ToolSegment] = Field(min_length=1, max_length=1000)
    fluted_ratio: Annotated[float, Field(allow_inf_nan=False, gt=0.0, le=1.0)] = Field(
        default=KOPS_VO_RATIO, description="equivalent diameter of a fluted section over the cutter diameter "
                                           "(Kops & Vo)")
    fluted_area_ratio: Annotated[float, Field(allow_inf_nan=False, gt=0.0, le=1.0)] | None = Field(
        default=None, description="cross-section area of a fluted section over that of the full diameter (its true "
                                  "mass); default: the stiffness-equivalent diameter's area")
    loss_factor: NonNeg = 0.0


class HolderSegment(Strict):
    length: Length
    outer_diameter: Length
    inner_diameter: Annotated[float, Field(allow_inf_nan=False, ge=0.0, le=100.0, description="bore, m")] = 0.0


class Holder(Strict):
    """The holder, described from its mouth (tool side) towards the spindle."""

    material: str = "steel"
    segments: list[HolderSegment] = Field(min_length=1, max_length=1000)
    loss_factor: NonNeg = 0.0


class SpindleEstimate(Strict):
    """The extension-bar taps a measured spindle was estimated from (``jointdb rotations --method extension``)."""

    taps: str = Field(min_length=1, description="the bar's measured translational FRFs (G11, G12, G22), relative "
                                                "to this file")
    extension: Union[str, BeamModelFile] = Field(description="the bar's beam model, inline or as a file path")
    joint_point: str = Field(min_length=1, description="the bar's named point fixed to the spindle nose")
    points: list[Annotated[str, Field(min_length=1)]] = Field(min_length=2, max_length=2,
                                                             description="the bar's two tapped named points")
    noise: Union[Annotated[float, Field(ge=0.0, lt=1.0)], None] = Field(
        default=None, description="relative noise level of the taps (e.g. 0.0075); omitted: estimated from them")


class MeasuredSpindle(Strict):
    file: str = Field(min_length=1, description="FRF file with rotations (.uff, .h5, .csv), relative to this file")
    node: Annotated[int, Field(ge=0)]
    estimate: Union[SpindleEstimate, None] = Field(
        default=None, description="the extension-bar taps the FRF was estimated from: the band samples their noise")


class ModelledSpindle(Strict):
    model: Union[str, BeamModelFile] = Field(description="a beam model, inline or as a file path")
    point: str = Field(min_length=1, description="the named point of the model the holder sits on")


PinnedRef = Annotated[str, Field(pattern=r"^\s*[^@\s]+\s*@\s*[^@\s]+\s*$", description="name@version or name@label")]


class PartRef(Strict):
    """A catalogued part (``jointdb parts``) in place of the inline object, resolved from the database."""

    part: Annotated[str, Field(pattern=r"^\s*[^@\s]+\s*@\s*[^@\s]+\s*$",
                               description="a catalogued part: name@version or name@label")]


class RigidChoice(Strict):
    rigid: Literal[True]


class PinnedChoice(Strict):
    joint: PinnedRef


class ExplicitChoice(Strict):
    k: Annotated[list[Positive], Field(min_length=2, max_length=2, description="[N/m, N·m/rad]")]
    c: Annotated[list[NonNeg], Field(min_length=2, max_length=2, description="[N·s/m, N·m·s/rad]")] = [0.0, 0.0]


class Query(Strict):
    joint_type: Name
    materials: Union[str, list[Annotated[str, Field(min_length=1)]]] | None = None
    torque_nm: NonNeg | None = None
    preload_n: NonNeg | None = None
    geometry: dict[str, NonNeg] | None = None
    extra: dict[str, Any] | None = None
    neighbours: Annotated[int, Field(ge=1)] = 3
    interpolate: bool = False


class QueryChoice(Strict):
    query: Query


JointChoice = Union[Literal["rigid"], PinnedRef, RigidChoice, PinnedChoice, ExplicitChoice, QueryChoice]


class Interfaces(Strict):
    tool_holder: JointChoice = Field(default="rigid", alias="tool-holder")
    holder_spindle: JointChoice = Field(default="rigid", alias="holder-spindle")


class FrequencyGrid(Strict):
    min: Positive
    max: Positive
    step: Positive


class StackFile(Strict):
    """A tool / holder / spindle stack; the tool-tip FRF is predicted by three-component RC.

    Each substructure (``tool``, ``holder``, ``spindle``) is one field typed by its own
    model; another way of giving one (a catalogued part) is one more branch of that
    field's union, read by the matching function of :mod:`jointdb.stack._stackfile`.
    """

    format: Literal["jointdb-stack/1"] = "jointdb-stack/1"
    name: str = "stack"
    tool: Union[Tool, PartRef]
    holder: Union[Holder, PartRef]
    spindle: Union[MeasuredSpindle, ModelledSpindle, PartRef]
    gauge_length: Positive | None = Field(default=None, description="tool length outside the holder, m")
    insertion_length: NonNeg | None = Field(default=None, description="tool length inside the holder, m")
    interfaces: Interfaces
    frequency: FrequencyGrid | None = None
