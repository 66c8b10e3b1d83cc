"""The inserted tool shank's inertia inside a tool–holder joint (issue 22; docs/stacks.md, *The shank inside the
holder*; docs/theory.md §4).

A tool–holder joint is identified with substructure B = the tool's overhang (tip to holder face) and A = the
holder with the shank stub bonded in (Schmitz & Duncan 2005). On a holder much stiffer than the contact, the
equivalent joint at the holder face is then the contact layer *and* the part of the tool inside the holder
moving on it:

    Z_J(ω) ≈ K_c + iω C_c − ω² M_s,

``M_s`` the rigid inserted shank's mass matrix about the holder face. ``K_c + iω C_c`` varies smoothly with
the conditions (torque, diameter); ``M_s`` grows with the diameter squared and the insertion, and above the
shank's own resonance on its contact layer (``ω² ≈ k′ / ρA``) it dominates ``Re Z_J`` and flips its sign there.
A joint catalogued for one shank therefore carries that shank's mass; used for another, it puts the layer
resonance at the wrong frequency. :func:`move_shank_inertia` exchanges the catalogued shanks' inertia for the
requested one's.

Sign convention: planar (x, ry) DOFs of the jointdb stack models, z from the tool tip towards the spindle, the
shank on the +z side of the holder face (``w(s) = u + θ s`` over depth ``s``).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from jointdb.errors import InputError
from jointdb.frf import FRF

__all__ = ["inserted_shank_mass", "move_shank_inertia", "exchange_shanks", "planar_x_ry"]


def inserted_shank_mass(diameter: float, length: float, density: float, start: float = 0.0) -> np.ndarray:
    """Rigid-body mass matrix of a solid cylindrical shank piece about the holder face, over (x, ry).

    For the piece from depth ``a = start`` to ``b = start + length``: ``m = ρ π d² L / 4``,
    ``M = [[m, m (a + b) / 2], [m (a + b) / 2, m (a² + ab + b²) / 3 + m d² / 16]]`` (translation, first moment
    about the face, moment of inertia about the face plus the section's rotary inertia ``ρ I L``,
    ``I = π d⁴ / 64``); a stepped shank is the sum of its pieces.

    Parameters
    ----------
    diameter
        Shank diameter [m], > 0.
    length
        Insertion depth [m] from the holder face, > 0.
    density
        [kg/m³], > 0.
    start
        Depth [m] of the piece's face-side end (0: at the holder face), ≥ 0.

    Returns
    -------
    ndarray ``(2, 2)``
        [kg, kg·m; kg·m, kg·m²].

    Raises
    ------
    InputError
        A value that is not a positive finite number, or a shank so large its mass overflows.

    Examples
    --------
    A Ø10 mm carbide shank 40 mm deep (15 630 kg/m³): 49 g.

    >>> m = inserted_shank_mass(0.010, 0.040, 15630.0)
    >>> round(float(m[0, 0]) * 1e3, 2), round(float(m[0, 1] / m[0, 0]) * 1e3, 1)
    (49.1, 20.0)
    """
    for name, v in (("diameter", diameter), ("length", length), ("density", density)):
        if isinstance(v, bool) or not isinstance(v, (int, float, np.floating)) or not np.isfinite(v) or v <= 0:
            raise InputError(f"inserted shank: {name} must be a positive number, got {v!r}")
    if isinstance(start, bool) or not isinstance(start, (int, float, np.floating)) or not np.isfinite(start) \
            or start < 0:
        raise InputError(f"inserted shank: start must be a depth ≥ 0, got {start!r}")
    a, b = np.float64(start), np.float64(start) + np.float64(length)
    d = np.float64(diameter)
    with np.errstate(over="ignore", invalid="ignore"):
        m = np.float64(density) * np.pi * d ** 2 * np.float64(length) / 4.0
        first = m * (a + b) / 2.0
        out = np.array([[m, first], [first, m * (a * a + a * b + b * b) / 3.0 + m * d ** 2 / 16.0]])
    if not np.isfinite(out).all():
        raise InputError(f"inserted shank: a Ø{diameter!r} m shank {length!r} m deep has no finite mass")
    return out


def planar_x_ry(frf: FRF) -> bool:
    """Whether ``frf`` is a square joint over one x and one ry DOF (the joints :func:`move_shank_inertia` takes)."""
    dirs = [d.direction for d in frf.outputs]
    return sorted(dirs) == ["ry", "x"] and [d.direction for d in frf.inputs] == dirs


def move_shank_inertia(frf: FRF, weighted: Sequence[tuple[float, np.ndarray]], target: np.ndarray) -> FRF:
    """A joint receptance with its catalogued shanks' inertia exchanged for the requested shank's.

    ``Z' = Z + ω² (Σ wᵢ Mᵢ − M)``: the joint ``Z = H⁻¹`` mixed from catalogued joints with weights ``wᵢ``
    (Σ wᵢ = 1; one joint with weight 1 for a nearest joint) carries ``−ω² Σ wᵢ Mᵢ``; the requested shank's
    ``−ω² M`` replaces it. Exact for a catalogue whose joints are ``K(c) + iωC(c) − ω² Mᵢ`` with ``K, C``
    mixed exactly by the weights (the mass is real: the loss, and the interpolation's passivity rule on it,
    are unchanged).

    Parameters
    ----------
    frf
        Joint receptance ``(n_freq, 2, 2)`` over (x, ry) in either order [m/N, rad/N·m].
    weighted
        ``(wᵢ, Mᵢ)`` of the catalogued joints mixed: weight and their shank's ``(2, 2)`` mass matrix over (x, ry)
        (:func:`inserted_shank_mass`).
    target
        The requested shank's ``(2, 2)`` mass matrix over (x, ry).

    Returns
    -------
    FRF
        The same DOFs and lines.

    Raises
    ------
    InputError
        A joint that is not over one x and one ry DOF, or weights that do not sum to 1.
    """
    dirs = [d.direction for d in frf.outputs]
    if not planar_x_ry(frf):
        raise InputError(f"the shank's inertia is moved on a planar (x, ry) joint only, not over {dirs}")
    w = np.array([wi for wi, _ in weighted], float)
    if w.size == 0 or abs(w.sum() - 1.0) > 1e-9:
        raise InputError(f"the mixed joints' weights must sum to 1, got {w.sum() if w.size else 0.0!r}")
    delta = sum(wi * np.asarray(mi, float) for wi, mi in weighted) - np.asarray(target, float)
    order = [dirs.index("x"), dirs.index("ry")]
    d = np.empty((2, 2))
    d[np.ix_(order, order)] = delta
    z = np.linalg.inv(frf.values) + ((2 * np.pi * frf.freq) ** 2)[:, None, None] * d
    return frf.replace(values=np.linalg.inv(z))


def exchange_shanks(frf: FRF, weighted: Sequence[tuple[float, np.ndarray | None]],
                    target: np.ndarray | None) -> FRF | None:
    """:func:`move_shank_inertia` where there is something to exchange, else None.

    Parameters
    ----------
    frf, weighted, target
        As :func:`move_shank_inertia`, but a mass matrix (or ``target``) may be None: a shank its conditions do
        not give.

    Returns
    -------
    FRF or None
        None when the joint is not over x and ry, a shank is unknown, or the mixed shanks already are the
        target's (``Σ wᵢ Mᵢ`` equal to ``M`` within 1e-9 of its largest entry): nothing to exchange.
    """
    if target is None or not planar_x_ry(frf) or any(m is None for _, m in weighted):
        return None
    delta = sum(w * np.asarray(m, float) for w, m in weighted) - np.asarray(target, float)
    if np.max(np.abs(delta)) <= 1e-9 * np.max(np.abs(target)):
        return None
    return move_shank_inertia(frf, weighted, target)
