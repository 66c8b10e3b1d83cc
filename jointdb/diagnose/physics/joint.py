"""Compliant (and damped) joint instead of a rigid clamp.

A rigid clamp is an idealisation: a shank held over its insertion length has
finite translational and rotational stiffness at the holder face. The
candidates replace the clamp by a :class:`jointdb.fe.Support` with springs on
``x`` (translation), ``ry`` (rotation) or both; the damped variant adds
dampers with one joint loss factor η (``c = η k / ω₁``).
"""

from __future__ import annotations

from jointdb.diagnose.physics._candidate import Candidate, Param, register
from jointdb.diagnose.physics._util import (
    AtClamp,
    bending_stiffness_at,
    first_mode_rad_s,
    single_clamp,
    swap_ingredients,
)
from jointdb.fe import Clamp, Support


def joint_params(model, clamp, dirs):
    EI = bending_stiffness_at(model, clamp.position)
    L = model.length
    kx = 3 * EI / L**3
    kr = EI / L
    out = []
    if "x" in dirs:
        out.append(Param("k_x", "N/m", 1.0 * kx, 1e5 * kx, 300 * kx, show=1e-6, show_unit="N/µm",
                         starts=(30 * kx, 3000 * kx), either="stiffness"))
    if "ry" in dirs:
        out.append(Param("k_ry", "N·m/rad", 0.1 * kr, 1e4 * kr, 30 * kr, show=1e-3, show_unit="kN·m/rad",
                         starts=(3 * kr, 300 * kr), either="stiffness"))
    return tuple(out)


class CompliantJoint(AtClamp, Candidate):
    family = "joint_compliance"
    slot = "clamp"

    def __init__(self, model, clamp, dirs):
        self.clamp = clamp
        self.dirs = dirs
        kind = {("x",): "translational", ("ry",): "rotational", ("x", "ry"): "translational and rotational"}[dirs]
        self.name = f"joint_{'both' if len(dirs) == 2 else ('translational' if dirs == ('x',) else 'rotational')}"
        self.explanation = (f"a compliant {kind} joint at the clamp (z = {clamp.position:g} m) "
                            "instead of a rigid one")
        self.params = joint_params(model, clamp, dirs)

    def support(self, values, scale=1.0, eta=0.0, omega=1.0):
        k = {d: values[f"k_{d}"] * scale for d in self.dirs}
        c = {d: eta * v / omega for d, v in k.items()} if eta > 0 else {}
        return Support(self.clamp.position, stiffness=k, damping=c)

    def apply(self, model, values, level=0):
        keep = tuple(d for d in ("x", "ry") if d not in self.dirs)
        extra = (Clamp(self.clamp.position, directions=keep),) if keep else ()
        return swap_ingredients(model, lambda i: i is self.clamp, *extra, self.support(values))


class DampedJoint(CompliantJoint):
    family = "joint_damping"

    def __init__(self, model, clamp, omega1):
        super().__init__(model, clamp, ("x", "ry"))
        self.name = "joint_damped"
        self.omega1 = omega1
        self.explanation = (f"a compliant joint with its own damping at the clamp (z = {clamp.position:g} m) "
                            "instead of a rigid, undamped one")
        self.params = self.params + (Param("eta_joint", "-", 1e-3, 2.0, 0.1, starts=(0.5,), key=False),)

    def apply(self, model, values, level=0):
        return swap_ingredients(model, lambda i: i is self.clamp,
                                self.support(values, eta=values["eta_joint"], omega=self.omega1))


@register
def _factory(ctx):
    clamp = single_clamp(ctx.model)
    if clamp is None:
        return []
    omega1 = first_mode_rad_s(ctx)
    return [CompliantJoint(ctx.model, clamp, ("x",)), CompliantJoint(ctx.model, clamp, ("ry",)),
            CompliantJoint(ctx.model, clamp, ("x", "ry")), DampedJoint(ctx.model, clamp, omega1)]
