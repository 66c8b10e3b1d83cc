"""Which frequencies a beam model can represent (the criterion a recording is checked against)."""

from __future__ import annotations

import numpy as np

from jointdb.errors import InputError

__all__ = ["BEAM_WAVELENGTH_DIAMETERS", "beam_limit_hz", "check_beam_range"]


#: A beam model represents bending while the bending wavelength is at least this many section diameters
#: (Timoshenko's shear and rotary-inertia corrections hold to a wavelength of a few diameters; shorter
#: waves are three-dimensional: cross-section and Lamb-type modes a beam model does not have).
BEAM_WAVELENGTH_DIAMETERS = 4.0


def beam_limit_hz(model) -> tuple[float, str]:
    """The highest frequency [Hz] a beam model represents, and the section that sets it (in words).

    For each segment, ``f = (2π / (n D))² √(EI/ρA) / (2π)``: the frequency at which its bending
    wavelength ``λ = 2π (EI/ρA)^¼ / √ω`` falls to ``n D`` (``n`` =
    :data:`BEAM_WAVELENGTH_DIAMETERS`, ``D`` its outer diameter); the lowest over the segments.
    """
    from jointdb.fe import get_material

    best, where, z = float("inf"), "", 0.0
    for seg in model.segments:
        m = get_material(seg.material)
        do, di = seg.outer_diameter, seg.inner_diameter
        area = np.pi * (do**2 - di**2) / 4
        ei = m.E * np.pi * (do**4 - di**4) / 64
        f = (2 * np.pi / (BEAM_WAVELENGTH_DIAMETERS * do)) ** 2 * np.sqrt(ei / (m.rho * area)) / (2 * np.pi)
        if f < best:
            best = float(f)
            where = f"the ⌀{do * 1e3:.3g} mm {m.name} section at z = {z * 1e3:.0f}–{(z + seg.length) * 1e3:.0f} mm"
        z += seg.length
    return best, where


def check_beam_range(obs, model):
    """InputError when the whole recording lies above the frequency a beam model can represent; a note
    when part of it does."""
    limit, where = beam_limit_hz(model)
    lo, hi = float(obs.full_freq[0]), float(obs.full_freq[-1])
    if lo > limit:
        raise InputError(
            f"the recording ({lo:g}–{hi:g} Hz) lies above {limit:.0f} Hz, where the bending wavelength of {where} "
            f"falls below {BEAM_WAVELENGTH_DIAMETERS:g} diameters: a beam model cannot represent it; "
            "record (or choose with --band) a range below that, or compare with a 3-D model"
        )
    if hi > limit:
        import dataclasses

        obs = dataclasses.replace(obs, notes=obs.notes + (
            f"lines above {limit:.0f} Hz lie beyond what a beam model represents (bending wavelength of {where} "
            f"below {BEAM_WAVELENGTH_DIAMETERS:g} diameters): read the mismatch there with care",))
    return obs
