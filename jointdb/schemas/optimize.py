"""The ``jointdb optimize`` spec file (``jointdb-optimize/1``) as a pydantic model.

Units SI. The spec names a template stack (spindle, holder, tool, interface queries), the
holders allowed, the overhang range, the clamping-torque and drawbar-force ranges, the cut and
the objective; :func:`jointdb.usecases.optimize_stack` enumerates the catalogue's conditions
inside those ranges.
"""

from __future__ import annotations

from typing import Literal, Optional

from pydantic import BaseModel, ConfigDict, Field, model_validator

__all__ = ["OptimizeSpecFile", "MATERIAL_COEFFICIENTS"]

#: Cutting coefficients K_t, K_r [N/m²] of a small material library (linear force law, end milling).
#: aluminium-7075: Altintas, *Manufacturing Automation*, 2nd ed. (2012), §3 (K_t = 796 N/mm², K_r = 0.212 K_t);
#: steel-1045 and titanium-6al4v: typical published orders of magnitude (Schmitz & Smith, *Machining Dynamics*, 2019).
MATERIAL_COEFFICIENTS: dict[str, tuple[float, float]] = {
    "aluminium-7075": (7.96e8, 0.212 * 7.96e8),
    "steel-1045": (2.0e9, 0.6e9),
    "titanium-6al4v": (2.2e9, 0.9e9),
}


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid")


class Machine(_Strict):
    speed_rpm: tuple[float, float] = Field(..., description="spindle speed range [rpm], min < max")
    n_speeds: int = Field(300, ge=2, le=100_000)
    power_w: Optional[float] = Field(None, gt=0, description="spindle power available [W]")
    torque_nm: Optional[float] = Field(None, gt=0, description="spindle torque available [N·m]")

    @model_validator(mode="after")
    def _range(self):
        if not 0 < self.speed_rpm[0] < self.speed_rpm[1]:
            raise ValueError("speed_rpm must be [min, max] with 0 < min < max")
        return self


class HolderChoice(_Strict):
    name: str = Field(..., min_length=1, max_length=200)
    holder: Optional[dict] = Field(None, description="holder as in a stack file (default: the template's)")
    taper_diameter_m: Optional[float] = Field(None, gt=0, description="taper of the holder-spindle query")


class ToolChoice(_Strict):
    flutes: int = Field(..., ge=1, le=1000)
    flute_length_m: float = Field(..., gt=0)
    overhang_m: tuple[float, float] = Field(..., description="gauge length range [m]; min = required reach")
    overhang_step_m: float = Field(0.005, gt=0)


class Cut(_Strict):
    radial_immersion: float = Field(..., gt=0, le=1)
    down_milling: bool = True
    feed_per_tooth_m: float = Field(1e-4, gt=0)
    material: Optional[str] = None
    kt: Optional[float] = Field(None, gt=0)
    kr: Optional[float] = Field(None, ge=0)

    @model_validator(mode="after")
    def _coefficients(self):
        if (self.kt is None) != (self.kr is None):
            raise ValueError("give kt and kr together")
        if self.kt is None and self.material is None:
            raise ValueError(f"give kt and kr or a material ({', '.join(MATERIAL_COEFFICIENTS)})")
        if self.kt is None and self.material not in MATERIAL_COEFFICIENTS:
            raise ValueError(f"unknown material {self.material!r}; known: {', '.join(MATERIAL_COEFFICIENTS)}")
        return self

    @property
    def coefficients(self) -> tuple[float, float]:
        return (self.kt, self.kr) if self.kt is not None else MATERIAL_COEFFICIENTS[self.material]


class Objective(_Strict):
    kind: Literal["removal-rate"] = "removal-rate"
    margin: float = Field(0.0, ge=0, lt=1, description="fraction of the limiting depth held back")


class OptimizeSpecFile(_Strict):
    format: Literal["jointdb-optimize/1"]
    stack: str = Field(..., description="template stack file, relative to the spec")
    machine: Machine
    holders: list[HolderChoice] = Field(default_factory=list, max_length=100)
    tool: ToolChoice
    torque_nm: tuple[float, float] = Field(..., description="clamping torque range [N·m]")
    drawbar_n: tuple[float, float] = Field(..., description="drawbar force range [N]")
    cut: Cut
    objective: Objective = Objective()
