"""Shared pieces of the file schemas: strict objects, finite numbers, SI ranges."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field

from jointdb.schemas._limits import LENGTH_RANGE

__all__ = ["Strict", "Finite", "NonNeg", "Positive", "Length", "Position", "Direction", "DirectionMap", "Name",
           "DofLabel"]


class Strict(BaseModel):
    """An object that refuses unknown fields and values of the wrong JSON type."""

    model_config = ConfigDict(extra="forbid", strict=True, frozen=True)


#: a finite JSON number (no NaN, no infinity); integers are accepted
Finite = Annotated[float, Field(allow_inf_nan=False, ge=-1e300, le=1e300)]
NonNeg = Annotated[float, Field(allow_inf_nan=False, ge=0.0, le=1e300)]
Positive = Annotated[float, Field(allow_inf_nan=False, gt=0.0, le=1e300)]
#: a length or diameter in m, within the physical range of jointdb.schemas._limits
Length = Annotated[float, Field(allow_inf_nan=False, ge=LENGTH_RANGE[0], le=LENGTH_RANGE[1],
                                description="m")]
#: a position along the axis in m
Position = Annotated[float, Field(allow_inf_nan=False, ge=-1000.0, le=1000.0, description="m from z = 0")]
Direction = Literal["x", "y", "z", "rx", "ry", "rz"]
#: a value per direction, e.g. {"x": 2e8, "ry": 4e5}
DirectionMap = dict[Direction, NonNeg]
Name = Annotated[str, Field(min_length=1, max_length=200)]
#: a DOF label "<node><direction>", e.g. "3x", "2ry" (positive directions only)
DofLabel = Annotated[str, Field(pattern=r"^\s*[0-9]+\s*[:.\s]?\s*\+?\s*([xyzXYZ]|[rR][xyzXYZ])\s*$",
                                description="node and direction, e.g. 3x, 2ry")]
