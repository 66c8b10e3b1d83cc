"""Shear deformation and rotary inertia (Timoshenko instead of Euler–Bernoulli).

Euler–Bernoulli beams ignore shear deformation and the rotary inertia of the
cross-sections; for a stubby tool (length/diameter below ~10) the higher
bending modes come out too high, the more so the higher the mode. No
parameter: the candidate switches the theory.
"""

from __future__ import annotations

from jointdb.diagnose.physics._candidate import Candidate, register


class ShearRotary(Candidate):
    name = "timoshenko"
    family = "shear_rotary"
    slot = "theory"
    explanation = "shear deformation and rotary inertia (Timoshenko) left out of an Euler–Bernoulli model"

    def apply(self, model, values, level=0):
        return model.replace(theory="timoshenko")


@register
def _factory(ctx):
    return [ShearRotary()] if ctx.model.theory == "euler-bernoulli" else []
