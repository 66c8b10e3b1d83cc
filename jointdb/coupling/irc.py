"""Inverse receptance coupling (IRC): joint identification (theory.md §2).

The three joint models live in private modules split along their seams:
planar spring–damper (§2a, :mod:`._planar`), n translational joints (§2b) and
the full joint matrix with inertia (§2c) (:mod:`._multi`); the equivalent
stiffness/damping helpers are in :mod:`._kc`.
"""

from jointdb.coupling._planar import identify_planar_joint

__all__ = ["identify_planar_joint"]
