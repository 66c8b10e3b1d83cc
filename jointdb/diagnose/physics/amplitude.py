"""Amplitude-dependent (micro-slip) joint: softening and extra damping with level.

A joint under load slips at the edges of its contact as the vibration grows:
its stiffness falls and its damping rises with the excitation level. With
recordings at several levels, the candidate replaces the clamp by a joint whose
stiffness ``k·s_l`` and loss factor ``η_l`` are fitted per level (``s`` = 1 at
the first level). Only offered when there are at least two levels.
"""

from __future__ import annotations

from jointdb.diagnose.physics import Param, register
from jointdb.diagnose.physics._util import full_clamps, without_ingredient
from jointdb.diagnose.physics.joint import CompliantJoint


class AmplitudeDependentJoint(CompliantJoint):
    family = "softening_joint"
    per_level = True

    def __init__(self, model, clamp, n_levels, levels, omega1):
        super().__init__(model, clamp, ("x", "ry"))
        self.name = "joint_amplitude_dependent"
        self.omega1 = omega1
        self.levels = levels
        self.n_levels = n_levels
        self.explanation = ("an amplitude-dependent (micro-slip) joint at the clamp whose stiffness and "
                            "damping change with the excitation level")
        extra = [Param(f"s_{i + 1}", "-", 0.2, 3.0, 1.0) for i in range(1, n_levels)]
        extra += [Param(f"eta_{i + 1}", "-", 1e-3, 2.0, 0.05, starts=(0.3,)) for i in range(n_levels)]
        self.params = self.params + tuple(extra)

    def apply(self, model, values, level=0):
        model = without_ingredient(model, self.clamp)
        s = 1.0 if level == 0 else values[f"s_{level + 1}"]
        return model.with_ingredient(self.support(values, scale=s, eta=values[f"eta_{level + 1}"],
                                                  omega=self.omega1))

    def level_table(self, values, sigmas=None, **_):
        """Per level: (level, k_x, k_ry, loss factor)."""
        rows = []
        for i in range(self.n_levels):
            s = 1.0 if i == 0 else values[f"s_{i + 1}"]
            rows.append({"level": self.levels[i], "k_x_n_per_m": values["k_x"] * s,
                         "k_ry_nm_per_rad": values["k_ry"] * s, "loss_factor": values[f"eta_{i + 1}"]})
        return rows


@register
def _factory(ctx):
    import numpy as np

    clamps = full_clamps(ctx.model)
    if ctx.n_levels < 2 or len(clamps) != 1:
        return []
    omega1 = 2 * np.pi * float(ctx.modes_hz[0]) if len(ctx.modes_hz) else 1.0
    return [AmplitudeDependentJoint(ctx.model, clamps[0], ctx.n_levels, ctx.levels, omega1)]
