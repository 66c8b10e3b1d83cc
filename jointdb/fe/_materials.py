"""Isotropic materials and the small library of the thesis's values."""

from __future__ import annotations

import math
from dataclasses import dataclass

from jointdb.errors import InputError

__all__ = ["Material", "MATERIALS", "get_material"]


@dataclass(frozen=True)
class Material:
    """An isotropic linear-elastic material.

    Parameters
    ----------
    name
        Label (free text).
    E
        Young's modulus [Pa], > 0.
    nu
        Poisson's ratio [-], in (-1, 0.5).
    rho
        Density [kg/m^3], > 0.

    Raises
    ------
    InputError
        If a value is out of range or not finite.
    """

    name: str
    E: float
    nu: float
    rho: float

    def __post_init__(self) -> None:
        for field_name in ("E", "nu", "rho"):
            value = getattr(self, field_name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise InputError(f"material {self.name!r}: {field_name} must be a finite number, got {value!r}")
            object.__setattr__(self, field_name, float(value))
        if self.E <= 0:
            raise InputError(f"material {self.name!r}: E must be > 0 Pa, got {self.E:g}")
        if self.rho <= 0:
            raise InputError(f"material {self.name!r}: rho must be > 0 kg/m^3, got {self.rho:g}")
        if not -1.0 < self.nu < 0.5:
            raise InputError(f"material {self.name!r}: nu must be in (-1, 0.5), got {self.nu:g}")

    @property
    def G(self) -> float:
        """Shear modulus ``E / (2 (1 + ν))`` [Pa]."""
        return self.E / (2.0 * (1.0 + self.nu))


#: Material library. Values from the reference thesis (Mehrpouya 2014, see
#: docs/theory.md, References): tool-holder steel 210 GPa / 7800 kg/m^3 and
#: carbide tools 550 GPa / 15630 kg/m^3 (ch. 5); tungsten-carbide test shanks
#: 405 GPa / 14800 kg/m^3 and SCM440 tool steel 205 GPa / 7800 kg/m^3 (§4.4);
#: simulation steel 200 GPa / 7850 kg/m^3 (§4.3); Al6061 68.9 GPa, ν 0.3,
#: 2712 kg/m^3 (ch. 6); cast iron 89 GPa, ν 0.25, 7250 kg/m^3 (§3.6).
#: The thesis gives no Poisson's ratio for steel or carbide; 0.3 (steel) and
#: 0.22 (cemented tungsten carbide, a typical handbook value) are assumed.
MATERIALS: dict[str, Material] = {
    "steel": Material("steel", 210e9, 0.3, 7800.0),
    "steel-200": Material("steel-200", 200e9, 0.3, 7850.0),
    "scm440": Material("scm440", 205e9, 0.3, 7800.0),
    "tungsten-carbide": Material("tungsten-carbide", 550e9, 0.22, 15630.0),
    "carbide-shank": Material("carbide-shank", 405e9, 0.22, 14800.0),
    "aluminium": Material("aluminium", 68.9e9, 0.3, 2712.0),
    "cast-iron": Material("cast-iron", 89e9, 0.25, 7250.0),
}
_ALIASES = {
    "carbide": "tungsten-carbide",
    "wc": "tungsten-carbide",
    "aluminum": "aluminium",
    "al6061": "aluminium",
}
MATERIALS.update({alias: MATERIALS[target] for alias, target in _ALIASES.items()})


def get_material(name_or_material: "str | Material") -> Material:
    """Look a material up by name (case-insensitive), or pass a :class:`Material` through.

    Parameters
    ----------
    name_or_material
        A name of :data:`MATERIALS` (``"steel"``, ``"carbide"``, ...) or a :class:`Material`.

    Returns
    -------
    Material
        E [Pa], ν, ρ [kg/m³].

    Raises
    ------
    InputError
        On an unknown name; the message lists the known ones.
    """
    if isinstance(name_or_material, Material):
        return name_or_material
    key = str(name_or_material).strip().lower()
    if key not in MATERIALS:
        known = ", ".join(sorted(MATERIALS))
        raise InputError(f"unknown material {name_or_material!r}; known: {known} (or give E, nu, rho)")
    return MATERIALS[key]
