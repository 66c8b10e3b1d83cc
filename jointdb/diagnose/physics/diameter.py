"""Effective-diameter error of a section (e.g. the fluted part of a tool).

A fluted section is not a circle: its bending stiffness and mass follow an
*effective* diameter that is usually guessed (0.75–0.85 × the nominal). One
candidate per segment scales that segment's outer diameter.
"""

from __future__ import annotations

import dataclasses

from jointdb.diagnose.physics import Candidate, Param, register


class EffectiveDiameter(Candidate):
    family = "fluted_diameter"

    def __init__(self, index, segment):
        self.index = index
        self.slot = f"diameter[{index}]"
        self.name = f"diameter@segment{index}"
        self.d0 = segment.outer_diameter
        self.explanation = (f"a wrong effective diameter of segment {index} "
                            f"(nominal {segment.outer_diameter * 1e3:.3g} mm, e.g. a fluted section)")
        self.params = (Param("diameter", "m", 0.6 * self.d0, 1.4 * self.d0, self.d0, show=1e3, show_unit="mm"),)

    def apply(self, model, values, level=0):
        segs = list(model.segments)
        segs[self.index] = dataclasses.replace(segs[self.index], outer_diameter=values["diameter"])
        return model.replace(segments=tuple(segs))


@register
def _factory(ctx):
    return [EffectiveDiameter(i, s) for i, s in enumerate(ctx.model.segments)]
