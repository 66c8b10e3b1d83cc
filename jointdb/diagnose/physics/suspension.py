"""Soft suspension in a free–free test.

A "free–free" test piece hangs on elastic cords or lies on foam: the rigid-body
modes become low-frequency suspension modes and the first flexible modes rise
slightly. Offered only for models with no clamp and no support; the candidate
adds equal translational springs at both ends.
"""

from __future__ import annotations

import numpy as np

from jointdb.diagnose.physics._candidate import Candidate, Param, register
from jointdb.fe import Clamp, Support


class SoftSuspension(Candidate):
    name = "soft_suspension"
    family = "soft_suspension"
    slot = "suspension"
    explanation = "a soft suspension (cords or foam) in a free–free test"

    def __init__(self, model, mass):
        self.length = model.length
        k0 = mass * (2 * np.pi * 20.0) ** 2 / 2
        self.params = (Param("k_suspension", "N/m", k0 * 1e-3, k0 * 1e3, k0, show=1e-3, show_unit="N/mm"),)

    def apply(self, model, values, level=0):
        k = {"x": values["k_suspension"]}
        return model.with_ingredient(Support(0.0, stiffness=k), Support(self.length, stiffness=k))


@register
def _factory(ctx):
    from jointdb.fe import get_material

    if any(isinstance(i, (Clamp, Support)) for i in ctx.model.ingredients):
        return []
    mass = sum(get_material(s.material).rho * np.pi * (s.outer_diameter**2 - s.inner_diameter**2) / 4 * s.length
               for s in ctx.model.segments)
    return [SoftSuspension(ctx.model, mass)]
