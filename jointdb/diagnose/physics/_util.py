"""Small helpers shared by the physics modules (model geometry, clamps)."""

from __future__ import annotations

import numpy as np

from jointdb.fe import Clamp, get_material


def full_clamps(model) -> list:
    """Clamps that fix every DOF of their node."""
    return [i for i in model.ingredients if isinstance(i, Clamp) and i.directions is None]


def single_clamp(model):
    """The model's one full clamp, or None (no clamp, or several): where a joint at the clamp sits."""
    clamps = full_clamps(model)
    return clamps[0] if len(clamps) == 1 else None


def first_mode_rad_s(ctx) -> float:
    """ω₁ [rad/s], the nominal model's first natural frequency (1.0 when none is known): where a joint's
    loss factor is matched by its viscous damping."""
    return 2 * np.pi * float(ctx.modes_hz[0]) if len(ctx.modes_hz) else 1.0


def bending_stiffness_at(model, position: float) -> float:
    """E·I [N·m²] of the segment at ``position``."""
    z = 0.0
    for s in model.segments:
        if position <= z + s.length + 1e-12:
            break
        z += s.length
    mat = get_material(s.material)
    return mat.E * np.pi * (s.outer_diameter**4 - s.inner_diameter**4) / 64.0


def point_position(model, name: str) -> float:
    return model.point(name).position


def without_ingredient(model, ingredient):
    return model.without(lambda i: i is ingredient)


def swap_ingredients(model, drop, *new):
    """``model.without(drop).with_ingredient(*new)`` built as one model: the same model, validated
    once (the intermediate one, which a fit would build and check at every evaluation, is skipped).

    Parameters
    ----------
    model
        A :class:`jointdb.fe.BeamModel`.
    drop
        ``Ingredient -> bool``: True for the ingredients to leave out.
    *new
        Ingredients appended after the kept ones.

    Returns
    -------
    BeamModel
    """
    return model.replace(ingredients=tuple(i for i in model.ingredients if not drop(i)) + tuple(new))


class AtClamp:
    """Mixin for candidates that sit at a model's clamp (``self.clamp``): where they are, in metres and words."""

    clamp: object

    @property
    def position(self) -> float:
        """Where the joint is [m] (nominal coordinates): the clamp."""
        return self.clamp.position

    @property
    def location(self) -> str:
        return f"the clamp (z = {self.clamp.position * 1e3:.4g} mm)"
