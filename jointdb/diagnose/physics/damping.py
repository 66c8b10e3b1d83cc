"""Damping laws: hysteretic instead of viscous, and the overall damping level.

Viscous (Rayleigh) damping makes the modal damping ratio change with
frequency; material and friction damping is closer to hysteretic (a constant
loss factor η: every mode has ζ ≈ η/2, and the low-frequency phase is −η
instead of 0). ``hysteretic`` replaces the model's viscous damping by η;
``damping_level`` only rescales the existing viscous damping.
"""

from __future__ import annotations

import dataclasses

from jointdb.diagnose.physics._candidate import Candidate, Param, register
from jointdb.diagnose.physics._util import swap_ingredients
from jointdb.fe import HystereticDamping, ModalDamping, RayleighDamping

VISCOUS = (RayleighDamping, ModalDamping)


class Hysteretic(Candidate):
    name = "hysteretic"
    family = "hysteretic_damping"
    slot = "damping"
    explanation = "hysteretic (structural) damping with a constant loss factor instead of viscous damping"
    params = (Param("eta", "-", 1e-4, 0.3, 0.02),)

    def apply(self, model, values, level=0):
        return swap_ingredients(model, lambda i: isinstance(i, VISCOUS + (HystereticDamping,)),
                                HystereticDamping(values["eta"]))


class DampingLevel(Candidate):
    name = "damping_level"
    family = "damping_level"
    slot = "damping"
    explanation = "the right damping law but the wrong amount of damping"
    params = (Param("factor", "-", 0.05, 20.0, 1.0),)

    def apply(self, model, values, level=0):
        f = values["factor"]
        new = []
        for ing in model.ingredients:
            if isinstance(ing, RayleighDamping):
                ing = RayleighDamping(ing.alpha * f, ing.beta * f)
            elif isinstance(ing, ModalDamping):
                z = ing.zeta
                ing = ModalDamping(tuple(v * f for v in z) if isinstance(z, tuple) else z * f)
            elif isinstance(ing, HystereticDamping):
                ing = dataclasses.replace(ing, eta=ing.eta * f)
            new.append(ing)
        return model.replace(ingredients=tuple(new))


@register
def _factory(ctx):
    has_viscous = any(isinstance(i, VISCOUS) for i in ctx.model.ingredients)
    has_any = has_viscous or any(isinstance(i, HystereticDamping) for i in ctx.model.ingredients)
    return ([Hysteretic()] if has_viscous else []) + ([DampingLevel()] if has_any else [])
