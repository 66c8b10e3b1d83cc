"""A segment of a stepped shaft: a uniform (hollow) circular section of one material."""

from __future__ import annotations

from dataclasses import dataclass

from jointdb.errors import InputError
from jointdb.fe._fields import FieldError, _number
from jointdb.fe._materials import Material, get_material

__all__ = ["Segment"]


@dataclass(frozen=True)
class Segment:
    """A uniform (hollow) circular shaft segment.

    Parameters
    ----------
    length, outer_diameter, inner_diameter
        Metres; ``length > 0``, ``outer_diameter > 0``, ``0 <= inner_diameter < outer_diameter``.
    material
        A material name from :data:`MATERIALS` or a :class:`Material`.

    Raises
    ------
    InputError
        Naming the field that is wrong.
    """

    length: float
    outer_diameter: float
    inner_diameter: float = 0.0
    material: "str | Material" = "steel"

    def __post_init__(self) -> None:
        _number(self, "length", minimum=0.0, strict=True)
        _number(self, "outer_diameter", minimum=0.0, strict=True)
        _number(self, "inner_diameter", minimum=0.0)
        if self.inner_diameter >= self.outer_diameter:
            raise FieldError(
                "inner_diameter",
                f"must be < outer_diameter ({self.outer_diameter:g} m), got {self.inner_diameter:g}",
            )
        try:
            get_material(self.material)
        except InputError as exc:
            raise FieldError("material", str(exc)) from None
        if isinstance(self.material, str):
            object.__setattr__(self, "material", self.material.strip().lower())

    @property
    def mat(self) -> Material:
        return get_material(self.material)
