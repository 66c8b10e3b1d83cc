"""Effective-diameter error of a section (e.g. the fluted part of a tool).

A fluted section is not a circle: its bending stiffness and its mass follow
*effective* diameters that are usually guessed (0.75–0.85 × the nominal), and
the two are not the same (the second moment of a fluted section falls faster
than its area). Only the section at the free end (the cutting part) may
plausibly be off by much (±20 %); any other section is plausible within ±3 %
of its drawing, and a fit beyond that is penalised and reported. One candidate per segment fits the bending-effective diameter
(the segment's outer diameter) and the mass-effective one (realised as a
density scaled by ``(d_mass/d_bend)²`` on that segment).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from jointdb.diagnose.physics._candidate import Candidate, Param, register
from jointdb.diagnose.physics._util import full_clamps
from jointdb.fe import Material, get_material


class EffectiveDiameter(Candidate):
    family = "fluted_diameter"

    def __init__(self, index, segment, free_end: bool = False, start: float = 0.0):
        self.index = index
        self.slot = f"diameter[{index}]"
        z0, z1 = start * 1e3, (start + segment.length) * 1e3
        self.name = f"diameter@z={z0:.0f}-{z1:.0f}mm"
        self.d0 = segment.outer_diameter
        what = f"⌀{segment.outer_diameter * 1e3:.3g} mm {get_material(segment.material).name}"
        self.location = (f"the free end (the fluted part), z = {z0:.0f}–{z1:.0f} mm" if free_end
                         else f"the section at z = {z0:.0f}–{z1:.0f} mm")
        self.explanation = (f"a wrong effective diameter of {self.location} (nominal {what}"
                            + (", e.g. flutes)" if free_end else ")"))
        # a fluted section (at the free end: the cutting part) can have an effective diameter far
        # from its nominal; a plain turned or ground section is within a few per cent of its drawing
        band = FLUTED_BAND if free_end else PLAIN_BAND
        pl = (self.d0 * (1 - band), self.d0 * (1 + band))
        self.params = (Param("diameter", "m", 0.6 * self.d0, 1.4 * self.d0, self.d0, show=1e3, show_unit="mm",
                             plausible=pl),
                       Param("mass_diameter", "m", 0.6 * self.d0, 1.4 * self.d0, self.d0, show=1e3,
                             show_unit="mm", plausible=pl))

    def apply(self, model, values, level=0):
        segs = list(model.segments)
        seg = segs[self.index]
        mat = get_material(seg.material)
        d, dm = values["diameter"], values["mass_diameter"]
        ratio = (dm**2 - seg.inner_diameter**2) / (d**2 - seg.inner_diameter**2)
        new_mat = Material(f"{mat.name} (mass-effective)", mat.E, mat.nu, mat.rho * ratio)
        segs[self.index] = dataclasses.replace(seg, outer_diameter=d, material=new_mat)
        return model.replace(segments=tuple(segs))


#: Plausible effective-diameter error of the section at the free end (flutes), and of any other section.
FLUTED_BAND = 0.20
PLAIN_BAND = 0.03


def _free_end_segment(model) -> int | None:
    """Index of the segment at the free end (the end farthest from the clamps), if the model is clamped."""
    clamps = full_clamps(model)
    if not clamps:
        return None
    mid = 0.5 * model.length
    return len(model.segments) - 1 if clamps[0].position <= mid else 0


@register
def _factory(ctx):
    tip = _free_end_segment(ctx.model)
    starts = np.concatenate([[0.0], np.cumsum([s.length for s in ctx.model.segments])])
    return [EffectiveDiameter(i, s, free_end=(tip is None or i == tip), start=float(starts[i])) for i, s in
            enumerate(ctx.model.segments)]
