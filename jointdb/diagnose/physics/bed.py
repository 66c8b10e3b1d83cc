"""Distributed joint: the shank continues into the holder on a bed of springs.

A real tool holder does not grip the shank at one point: the shank is
inserted over a length ``L`` and touches the bore along it. A point joint at
the holder face cannot represent the inserted mass and the spread of contact,
so fitting one to such a recording leaves a systematic residual that other
candidates (e.g. a diameter change) then try to absorb. This candidate models
the contact directly: the rigid clamp is replaced by a continuation of the
adjacent segment over ``L`` (the insertion), resting on ``N_SPRINGS`` equal
translational :class:`jointdb.fe.Support` s spread evenly over it (a discrete
Winkler bed of stiffness ``k'`` per unit length, N/m², each spring
``k' L / N``). The damped variant adds dampers with one bed loss factor η
(``c = η k / ω₁``). Fitted: ``k'`` and ``L`` (and η).

The model's coordinates shift by ``L`` when the clamp is at ``z = 0`` (the
insertion is prepended); named points keep their names and node numbers.
"""

from __future__ import annotations

import dataclasses

from jointdb.diagnose.physics._candidate import Candidate, Param, register
from jointdb.diagnose.physics._util import AtClamp, first_mode_rad_s, single_clamp, without_ingredient
from jointdb.fe import Support

#: Springs spread over the insertion length (evenly, at the centres of N equal parts).
N_SPRINGS = 6


class DistributedJoint(AtClamp, Candidate):
    family = "joint_compliance"
    slot = "clamp"
    #: changes the model's coordinates: applied after other candidates in a combination
    reshapes = True

    def __init__(self, model, clamp, omega1: float, damped: bool = False):
        self.clamp = clamp
        self.omega1 = omega1
        self.damped = damped
        self.at_start = clamp.position <= 1e-12
        seg = model.segments[0] if self.at_start else model.segments[-1]
        self.segment = seg
        d = seg.outer_diameter
        self.name = "joint_distributed_damped" if damped else "joint_distributed"
        if damped:
            self.family = "joint_damping"
        self.explanation = (("a damped " if damped else "a compliant ") +
                            f"distributed joint: the shank continues into the holder beyond the clamp face "
                            f"(z = {clamp.position:g} m) and rests on a bed of springs"
                            f"{' with its own damping' if damped else ''} over the insertion length, "
                            "instead of a rigid clamp")
        ps = [Param("k_bed", "N/m²", 1e10, 1e14, 1e12, show=1e-9, show_unit="GN/m²", starts=(2e11, 5e12),
                    equivalent=True, either="contact"),
              Param("insertion", "m", 0.5 * d, 4.0 * d, 2.5 * d, show=1e3, show_unit="mm", equivalent=True,
                    either="contact")]
        if damped:
            ps.append(Param("eta_joint", "-", 1e-3, 2.0, 0.1, starts=(0.5,), key=False))
        self.params = tuple(ps)

    def apply(self, model, values, level=0):
        L = float(values["insertion"])
        kb = float(values["k_bed"])
        eta = float(values.get("eta_joint", 0.0))
        model = without_ingredient(model, self.clamp)
        segs = list(model.segments)
        ext = dataclasses.replace(self.segment, length=L)
        k = kb * L / N_SPRINGS
        c = eta * k / self.omega1 if eta > 0 else 0.0
        if self.at_start:
            shift = L
            model = _shifted(model, shift, (ext, *segs))
            z0 = 0.0
        else:
            z0 = model.length
            model = model.replace(segments=(*segs, ext))
        springs = [Support(z0 + L * (i + 0.5) / N_SPRINGS, stiffness={"x": k},
                           damping={"x": c} if c > 0 else {}) for i in range(N_SPRINGS)]
        return model.with_ingredient(*springs)


def _shifted(model, shift, segments):
    """``model`` with new ``segments`` and every position moved by ``shift`` [m]."""
    pts = tuple(dataclasses.replace(p, position=p.position + shift) for p in model.points)
    ings = tuple(dataclasses.replace(i, position=i.position + shift) if hasattr(i, "position") else i
                 for i in model.ingredients)
    return model.replace(segments=segments, points=pts, ingredients=ings)


@register
def _factory(ctx):
    clamp = single_clamp(ctx.model)
    if clamp is None:
        return []
    if not (clamp.position <= 1e-12 or abs(clamp.position - ctx.model.length) <= 1e-9):
        return []
    omega1 = first_mode_rad_s(ctx)
    return [DistributedJoint(ctx.model, clamp, omega1), DistributedJoint(ctx.model, clamp, omega1, damped=True)]
