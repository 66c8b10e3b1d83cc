"""The inserted shank's inertia in an interpolated tool–holder joint (issue 22; docs/stacks.md, *The shank inside
the holder*; :mod:`jointdb.stack._shank`).

A catalogued tool–holder joint carries the mass of the shank its campaign clamped (``Z_J ≈ K_c + iωC_c − ω²M_s``).
Interpolating joints of Ø6 and Ø10 shanks for a Ø7 tool mixes their shanks' masses by the weights instead of
using the Ø7 shank's, which puts the shank's resonance on its contact layer at the wrong frequency. The
prediction therefore exchanges the mixed catalogued shanks' inertia for the stack's own (diameter, insertion,
material), and the leave-one-out behind the band's joint-choice term does the same for every joint it predicts.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from jointdb.errors import InputError
from jointdb.fe import get_material
from jointdb.stack._parts import _inserted_shank
from jointdb.stack._shank import exchange_shanks, inserted_shank_mass

__all__ = ["ShankInertia", "shank_inertia"]


@dataclass(frozen=True, eq=False)
class ShankInertia:
    """The stack's inserted shank and how a catalogued joint's shank is read from its conditions.

    ``target``: the stack's ``(2, 2)`` shank mass matrix over (x, ry) about the holder face; ``insertion`` [m]
    and ``density`` [kg/m³]: used for a catalogued joint whose conditions do not record its own
    (``geometry.insertion_m``; its first material).
    """

    target: np.ndarray
    insertion: float
    density: float

    def of(self, conditions) -> np.ndarray | None:
        """The shank mass matrix of a catalogued joint with these :class:`jointdb.store.Conditions`, or None when
        they do not record a shank diameter (``geometry.shank_diameter_m``) or record one with no finite mass."""
        geo = dict(getattr(conditions, "geometry", None) or {})
        d = geo.get("shank_diameter_m")
        if isinstance(d, bool) or not isinstance(d, (int, float)) or not d > 0:
            return None
        length = geo.get("insertion_m")
        if isinstance(length, bool) or not isinstance(length, (int, float)) or not length > 0:
            length = self.insertion
        density = self.density
        materials = tuple(getattr(conditions, "materials", ()) or ())
        if materials:
            try:
                density = get_material(materials[0]).rho
            except InputError:
                pass  # a material the FE library does not know: the stack's tool material's density
        try:
            return inserted_shank_mass(float(d), float(length), density)
        except InputError:  # a recorded shank with no finite mass (a corrupt or hostile record): unknown
            return None

    def moved(self, frf, mixed: Sequence[tuple[float, object]]):
        """``(frf, moved)``: the joint mixed from ``(weight, conditions)`` with their shanks' inertia exchanged for
        the stack's; unchanged (``moved`` False) when some mixed joint records no shank diameter, the joint is not
        over x and ry, or the mixed shanks already are the stack's."""
        out = exchange_shanks(frf, [(w, self.of(c)) for w, c in mixed], self.target)
        return (frf, False) if out is None else (out, True)


def shank_inertia(spec) -> ShankInertia | None:
    """The :class:`ShankInertia` of a stack, or None when nothing of the tool lies inside the holder.

    Parameters
    ----------
    spec
        A :class:`jointdb.stack.StackSpec`.

    Returns
    -------
    ShankInertia or None
    """
    pieces = _inserted_shank(spec)
    if not pieces:
        return None
    rho = get_material(spec.tool.material).rho
    target = sum(inserted_shank_mass(d, b - a, rho, a) for a, b, d in pieces if b - a > 0)
    if not isinstance(target, np.ndarray):
        return None
    return ShankInertia(target, float(spec.insertion_length), float(rho))
