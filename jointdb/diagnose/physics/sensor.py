"""An unmodelled sensor (or other added mass) at a measurement point.

An accelerometer glued to a slender tool adds mass (and rotary inertia) where
it sits: every mode with motion there drops in frequency, most where the mode
shape is large at that point. One candidate per measured point: mass only,
and mass with rotary inertia.
"""

from __future__ import annotations

from jointdb.diagnose.physics._candidate import Candidate, Param, register
from jointdb.fe import PointMass


class SensorMass(Candidate):
    family = "sensor_mass"

    def __init__(self, point, position, inertia: bool, length: float | None = None, offset: bool = False):
        self.point = point
        self.position = position
        self.slot = f"mass@{point}"
        self.name = f"sensor_mass{'_inertia' if inertia else ''}@{point}"
        self.explanation = (f"an unmodelled sensor (added mass{' and rotary inertia' if inertia else ''}) "
                            f"at point {point!r}")
        # tap-test accelerometers weigh 0.2–30 g (with cable and mount); 0.2 kg is not a sensor
        ps = [Param("mass", "kg", 1e-4, 0.2, 0.005, show=1e3, show_unit="g", starts=(0.03,), plausible=(1e-4, 0.04))]
        if inertia:
            ps.append(Param("rotary_inertia", "kg·m²", 1e-10, 1e-4, 1e-6, show=1e9, show_unit="g·mm²", key=False))
        if offset:
            # a sensor has a size: its centre of mass sits up to ~10 mm from the measured point
            lo, hi = max(-0.010, -position), min(0.010, (length or position) - position)
            start = min(max(0.0, lo + 0.2 * (hi - lo)), hi - 0.2 * (hi - lo))
            ps.append(Param("offset", "m", lo, hi, start, log=False, show=1e3, show_unit="mm", key=False))
            self.name = f"sensor_mass_offset@{point}"
            self.explanation = (f"an unmodelled sensor of finite size (added mass and rotary inertia, centre of "
                                f"mass offset along the axis) at point {point!r}")
        self.params = tuple(ps)

    def apply(self, model, values, level=0):
        pos = model.point(self.point).position + values.get("offset", 0.0)  # (model may have been shifted)
        return model.with_ingredient(PointMass(pos, values["mass"], values.get("rotary_inertia", 0.0)))

    def describe(self, values, sigmas=None):
        sigmas = sigmas or {}
        text = f"an unmodelled {self.params[0].fmt(values['mass'], sigmas.get('mass'))} sensor at point {self.point!r}"
        if "rotary_inertia" in values:
            text += f" with rotary inertia {self.params[1].fmt(values['rotary_inertia'], sigmas.get('rotary_inertia'))}"
        if "offset" in values:
            text += (f", centre of mass {self.params[2].fmt(values['offset'], sigmas.get('offset'))} "
                     "along the axis from the point")
        return text


@register
def _factory(ctx):
    out = []
    for name in ctx.points:
        pos = ctx.model.point(name).position
        out += [SensorMass(name, pos, False), SensorMass(name, pos, True),
                SensorMass(name, pos, True, length=ctx.model.length, offset=True)]
    return out
