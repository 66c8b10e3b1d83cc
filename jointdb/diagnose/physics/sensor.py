"""An unmodelled sensor (or other added mass) at a measurement point.

An accelerometer glued to a slender tool adds mass (and rotary inertia) where
it sits: every mode with motion there drops in frequency, most where the mode
shape is large at that point. One candidate per measured point: mass only,
and mass with rotary inertia.
"""

from __future__ import annotations

from jointdb.diagnose.physics import Candidate, Param, register
from jointdb.fe import PointMass


class SensorMass(Candidate):
    family = "sensor_mass"

    def __init__(self, point, position, inertia: bool):
        self.point = point
        self.position = position
        self.slot = f"mass@{point}"
        self.name = f"sensor_mass{'_inertia' if inertia else ''}@{point}"
        self.explanation = (f"an unmodelled sensor (added mass{' and rotary inertia' if inertia else ''}) "
                            f"at point {point!r}")
        ps = [Param("mass", "kg", 1e-4, 0.2, 0.005, show=1e3, show_unit="g", starts=(0.03,))]
        if inertia:
            ps.append(Param("rotary_inertia", "kg·m²", 1e-10, 1e-4, 1e-6, show=1e9, show_unit="g·mm²"))
        self.params = tuple(ps)

    def apply(self, model, values, level=0):
        return model.with_ingredient(PointMass(self.position, values["mass"], values.get("rotary_inertia", 0.0)))

    def describe(self, values, sigmas=None):
        sigmas = sigmas or {}
        text = f"an unmodelled {self.params[0].fmt(values['mass'], sigmas.get('mass'))} sensor at point {self.point!r}"
        if "rotary_inertia" in values:
            text += f" with rotary inertia {self.params[1].fmt(values['rotary_inertia'], sigmas.get('rotary_inertia'))}"
        return text


@register
def _factory(ctx):
    out = []
    for name in ctx.points:
        pos = ctx.model.point(name).position
        out += [SensorMass(name, pos, False), SensorMass(name, pos, True)]
    return out
