"""Amplitude-dependent (micro-slip) joint: softening and extra damping with level.

A joint under load slips at the edges of its contact as the vibration grows:
its stiffness falls and its damping rises with the excitation level. With
recordings at several levels, the candidate replaces the clamp by a joint whose
stiffness and loss follow the micro-slip law of
:mod:`jointdb.diagnose.physics.microslip` in the excitation level (all levels
jointly; per-level values when the levels' amplitudes are unknown). Only
offered when there are at least two levels.
"""

from __future__ import annotations

from jointdb.diagnose.physics._candidate import register
from jointdb.diagnose.physics._util import first_mode_rad_s, single_clamp, swap_ingredients
from jointdb.diagnose.physics.joint import CompliantJoint
from jointdb.diagnose.physics.microslip import _law_params, _state


class AmplitudeDependentJoint(CompliantJoint):
    family = "softening_joint"
    per_level = True

    def __init__(self, model, clamp, n_levels, levels, omega1):
        super().__init__(model, clamp, ("x", "ry"))
        self.name = "joint_amplitude_dependent"
        self.omega1 = omega1
        self.levels = tuple(levels)
        self.n_levels = n_levels
        self.explanation = ("an amplitude-dependent (micro-slip) joint at the clamp whose stiffness falls and "
                            "damping rises with the excitation level")
        self.law, extra = _law_params(self.levels)
        self.params = self.params + tuple(extra)

    def state(self, values, level: int) -> tuple[float, float]:
        """(stiffness scale, loss factor) at ``level`` (0-based)."""
        return _state(self.law, self.levels, values, level)

    def apply(self, model, values, level=0):
        s, eta = self.state(values, level)
        return swap_ingredients(model, lambda i: i is self.clamp, self.support(values, scale=s, eta=eta, omega=self.omega1))

    def level_table(self, values, sigmas=None, **_):
        """Per level: (level, k_x, k_ry, loss factor)."""
        rows = []
        for i in range(self.n_levels):
            s, eta = self.state(values, i)
            rows.append({"level": self.levels[i], "k_x_n_per_m": values["k_x"] * s,
                         "k_ry_nm_per_rad": values["k_ry"] * s, "loss_factor": eta,
                         "position_m": self.clamp.position})
        return rows


@register
def _factory(ctx):
    clamp = single_clamp(ctx.model)
    if ctx.n_levels < 2 or clamp is None:
        return []
    return [AmplitudeDependentJoint(ctx.model, clamp, ctx.n_levels, ctx.levels, first_mode_rad_s(ctx))]
