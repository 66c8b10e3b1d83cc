"""The ``jointdb optimize`` spec file (``jointdb-optimize/1``) as a pydantic model.

Units SI. The spec names a template stack (spindle, holder, tool, interface queries) — a file
beside the spec, or the stack document inline (the form a service job takes: parts by
``{"part": "name@version"}``, no file paths) — the machine (its spindle part from the catalogue,
speed range, power curve), the holders allowed (inline, one catalogued part, or every catalogued
holder of a family, optionally only the versions a label points at), the overhang range, the
clamping-torque and drawbar-force ranges, the cut and the objective (removal rate, with a margin:
a fraction of the limiting depth, or the lower edge of the joints' 5–95 % lobe band);
:func:`jointdb.usecases.optimize_stack` enumerates the catalogue's conditions inside those ranges.

The body is hostile when it comes through the service: every list and range is bounded here
(:data:`MAX_HOLDERS`, :data:`MAX_OVERHANGS`, :data:`MAX_CURVE_POINTS`, ``n_speeds``), and the
number of candidates (:data:`MAX_CANDIDATES`) and candidate × speed pairs (:data:`MAX_WORK`) when
they are enumerated.
"""

from __future__ import annotations

import math
from typing import Literal, Optional, Union

from pydantic import BaseModel, ConfigDict, Field, model_validator

__all__ = ["OptimizeSpecFile", "MATERIAL_COEFFICIENTS", "MAX_CANDIDATES", "MAX_WORK"]

#: Most holder entries in a spec, and most holders one family entry may expand to.
MAX_HOLDERS = 100
#: Most overhangs on the spec's grid.
MAX_OVERHANGS = 1000
#: Most points of a spindle power curve.
MAX_CURVE_POINTS = 200
#: Most candidate stacks one run evaluates.
MAX_CANDIDATES = 200_000
#: Most (candidate, speed) pairs one run evaluates.
MAX_WORK = 200_000_000
_REF = r"^[^@\s]{1,200}@[^@\s]{1,100}$"

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


class CurvePoint(_Strict):
    speed_rpm: float = Field(..., gt=0, le=1e6, description="spindle speed [rpm]")
    power_w: float = Field(..., ge=0, le=1e8, description="power available at that speed [W]")


class Machine(_Strict):
    speed_rpm: tuple[float, float] = Field(..., description="spindle speed range [rpm], min < max")
    n_speeds: int = Field(300, ge=2, le=20_000)
    spindle: Optional[str] = Field(None, pattern=_REF, description="catalogued spindle part, name@version or "
                                   "name@label (replaces the template's spindle)")
    name: Optional[str] = Field(None, min_length=1, max_length=200, description="the machine: without `spindle`, "
                                "its one catalogued spindle part (latest version)")
    power_w: Optional[float] = Field(None, gt=0, description="spindle power available [W] (flat)")
    torque_nm: Optional[float] = Field(None, gt=0, description="spindle torque available [N·m] (flat)")
    power_curve: Optional[list[CurvePoint]] = Field(
        None, min_length=2, max_length=MAX_CURVE_POINTS,
        description="power available against speed (linear between points, covering speed_rpm) [W]")

    @model_validator(mode="after")
    def _range(self):
        if not (all(math.isfinite(v) for v in self.speed_rpm) and 0 < self.speed_rpm[0] < self.speed_rpm[1]):
            raise ValueError("speed_rpm must be [min, max] with 0 < min < max")
        if self.power_curve is not None:
            n = [p.speed_rpm for p in self.power_curve]
            if any(b <= a for a, b in zip(n, n[1:])):
                raise ValueError("power_curve: speeds must increase strictly")
            if n[0] > self.speed_rpm[0] or n[-1] < self.speed_rpm[1]:
                raise ValueError(f"power_curve: must cover the speed range {list(self.speed_rpm)} rpm "
                                 f"(it spans {n[0]:g}–{n[-1]:g})")
        if self.spindle is not None and self.name is not None:
            raise ValueError("give the spindle part or the machine's name, not both")
        return self


class HolderChoice(_Strict):
    """One entry of ``holders``: inline (``name`` + optional ``holder``), one catalogued ``part``, or every
    catalogued holder of a ``family`` (optionally only the versions ``label`` points at)."""

    name: Optional[str] = Field(None, min_length=1, max_length=200)
    holder: Optional[dict] = Field(None, description="holder as in a stack file (default: the template's)")
    part: Optional[str] = Field(None, pattern=_REF, description="a catalogued holder, name@version or name@label")
    family: Optional[str] = Field(None, min_length=1, max_length=200,
                                  description="every catalogued holder of this family (e.g. ER32)")
    label: Optional[str] = Field(None, min_length=1, max_length=100,
                                 description="with family: only the holder versions this label points at")
    taper_diameter_m: Optional[float] = Field(None, gt=0, description="taper of the holder-spindle query")

    @model_validator(mode="after")
    def _one_form(self):
        forms = [self.name is not None, self.part is not None, self.family is not None]
        if sum(forms) != 1:
            raise ValueError("give one of name (an inline holder), part (name@version) or family")
        if self.holder is not None and self.name is None:
            raise ValueError("holder: an inline holder needs a name")
        if self.label is not None and self.family is None:
            raise ValueError("label: selects versions of a family; a single part names its label as name@label")
        return self


class ToolChoice(_Strict):
    flutes: int = Field(..., ge=1, le=1000)
    flute_length_m: float = Field(..., gt=0)
    overhang_m: tuple[float, float] = Field(..., description="gauge length range [m]; min = required reach")
    overhang_step_m: float = Field(0.005, gt=0)

    @model_validator(mode="after")
    def _grid(self):
        lo, hi = self.overhang_m
        if not (math.isfinite(lo) and math.isfinite(hi) and 0 < lo <= hi):
            raise ValueError("overhang_m must be [min, max] with 0 < min <= max")
        if (hi - lo) / self.overhang_step_m + 1 > MAX_OVERHANGS:
            raise ValueError(f"overhang grid: more than {MAX_OVERHANGS} overhangs (raise overhang_step_m)")
        return self


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
    margin_from: Literal["fraction", "band"] = Field(
        "fraction", description="band: the stability limit is also the lower (5 %) edge of the lobe band from the "
        "joints' uncertainty (checked for the best candidates, as semi-discretization is)")


class OptimizeSpecFile(_Strict):
    format: Literal["jointdb-optimize/1"]
    stack: Union[str, dict] = Field(..., description="template stack: a file relative to the spec, or the stack "
                                    "document inline (parts as {\"part\": \"name@version\"})")
    machine: Machine
    holders: list[HolderChoice] = Field(default_factory=list, max_length=MAX_HOLDERS)
    tool: ToolChoice
    torque_nm: tuple[float, float] = Field(..., description="clamping torque range [N·m]")
    drawbar_n: tuple[float, float] = Field(..., description="drawbar force range [N]")
    cut: Cut
    objective: Objective = Objective()

    @model_validator(mode="after")
    def _ranges(self):
        for name in ("torque_nm", "drawbar_n"):
            lo, hi = getattr(self, name)
            if not (math.isfinite(lo) and math.isfinite(hi) and 0 <= lo <= hi):
                raise ValueError(f"{name} must be [min, max] with 0 <= min <= max")
        if isinstance(self.stack, str) and not 0 < len(self.stack) <= 1000:
            raise ValueError("stack: a file name of 1-1000 characters, or the stack document")
        return self
