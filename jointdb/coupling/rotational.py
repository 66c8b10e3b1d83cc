"""Rotational receptances at a contact point from translational measurements (docs/theory.md §3).

Two estimates of the 2×2 block ``H_33 = [[h, l], [n, p]]`` of substructure A
at point 3 (``h = x/f``, ``l = x/M``, ``n = θ/f``, ``p = θ/M``):

* :func:`rotations_by_extension` — attach a known extension E (a modelled
  cylinder, free-free) rigidly at point 3, measure the translational FRFs
  ``G_11, G_12, G_22`` at two points on E, and invert the rigid RC equations
  (Park, Altintas & Movahhedy 2003; thesis §4.4). With
  ``R = H^E_00 + H_33`` and ``e_i = H^E_0i`` (E's joint-point response to a
  force at i), ``H^E_ij − G_ij = e_iᵀ R⁻¹ e_j``: linear in the symmetric
  ``S = R⁻¹``, so ``S = E⁻ᵀ M E⁻¹`` and ``H_33 = S⁻¹ − H^E_00``.
* :func:`rotations_by_finite_difference` — first-order difference over a
  short distance s: ``n ≈ (h_33 − h_43)/s``; ``p ≈ n²/h`` (theory) or the
  second-order ``p ≈ (h_33 − h_34 − h_43 + h_44)/s²``. Noise sensitive.
"""

from __future__ import annotations

import numpy as np

from jointdb.coupling._common import as_receptance, fetch, same_grid
from jointdb.coupling._linalg import condition
from jointdb.errors import InputError, NumericalError
from jointdb.frf import FRF, Dof, Quantity

__all__ = ["rotations_by_extension", "rotations_by_finite_difference"]


def rotations_by_extension(
    assembly: FRF,
    extension: FRF,
    e_joint: int,
    e_points: tuple[int, int],
    a_point: int,
    *,
    translation: str = "x",
    rotation: str = "ry",
) -> tuple[FRF, np.ndarray]:
    """Full 2×2 receptance of A at its contact point by the extension method (docs/theory.md §3).

    Parameters
    ----------
    assembly
        Measured A+E translational receptances among ``e_points`` (G_11, G_12,
        G_22; missing entries by reciprocity).
    extension
        E's free receptance (model) over ``e_joint`` (translation and rotation)
        and ``e_points`` (translation).
    e_joint
        E's node rigidly attached to A's point.
    e_points
        Two measured nodes on E (distinct distances from the joint).
    a_point
        Node label of A's contact point in the returned FRF.
    translation, rotation
        Directions of the bending plane (default ``x`` and ``ry``).

    Returns
    -------
    (FRF, ndarray)
        ``H_33`` labelled ``(a_point, translation), (a_point, rotation)``
        (symmetric, ``l = n``), and the condition number of ``E = [e_1 e_2]``
        per line.

    Raises
    ------
    InputError
        Missing DOFs, grid mismatch, equal points.
    NumericalError
        If ``E`` is singular at every line.
    """
    p1, p2 = e_points
    if p1 == p2:
        raise InputError("the two measured points on the extension must differ")
    G = as_receptance("assembly", assembly)
    E = as_receptance("extension", extension)
    freq = same_grid({"assembly": G, "extension": E})
    t, r = translation, rotation
    j = [Dof(e_joint, t), Dof(e_joint, r)]
    pts = [Dof(p1, t), Dof(p2, t)]
    h00 = fetch("extension", E, j, j, "the joint point incl. rotation")
    e = fetch("extension", E, j, pts)  # (nf, 2 [x0, θ0], 2 [force at 1, 2])
    he = fetch("extension", E, pts, pts)
    g = fetch("assembly", G, pts, pts)
    cond = condition(e)
    if np.all(~np.isfinite(cond)):
        raise NumericalError("the extension's joint-to-point receptances are singular at every line")
    try:
        h33 = extension_receptance(h00, e, he, g)
    except np.linalg.LinAlgError:
        bad = np.flatnonzero(~np.isfinite(cond))
        where = f" (e.g. {freq[bad[0]]:g} Hz)" if bad.size else ""
        raise NumericalError(
            f"the extension equations are singular at some line{where}; choose measured points at "
            "other distances from the joint, or drop that line"
        ) from None
    a = [Dof(a_point, t), Dof(a_point, r)]
    return FRF(freq, h33, a, a, Quantity.RECEPTANCE), cond


def extension_receptance(h00: np.ndarray, e: np.ndarray, he: np.ndarray, g: np.ndarray) -> np.ndarray:
    """The algebra of :func:`rotations_by_extension` on arrays, batched over any leading axes.

    Parameters
    ----------
    h00
        E's receptance at its joint point over (x, θ), ``(..., 2, 2)``.
    e
        E's joint-point response to forces at the two measured points, ``(..., 2, 2)``.
    he, g
        E's free and the assembly's measured translational receptances among the two points, ``(..., 2, 2)``.

    Returns
    -------
    ndarray ``(..., 2, 2)``
        A's symmetric 2×2 receptance at the contact point.

    Raises
    ------
    numpy.linalg.LinAlgError
        A singular system at some line.
    """
    m = he - g
    m = 0.5 * (m + np.swapaxes(m, -1, -2))
    einv = np.linalg.inv(e)
    h33 = np.linalg.inv(np.swapaxes(einv, -1, -2) @ m @ einv) - h00
    return 0.5 * (h33 + np.swapaxes(h33, -1, -2))


def rotations_by_finite_difference(
    frf_a: FRF,
    point: int,
    inner: int,
    spacing: float,
    *,
    method: str = "first-order",
    translation: str = "x",
    rotation: str = "ry",
) -> FRF:
    """2×2 receptance at ``point`` from translations at ``point`` and ``inner`` (docs/theory.md §3).

    Parameters
    ----------
    frf_a
        A's measured translational receptances: ``h_33``, ``h_43`` (and
        ``h_44`` for the second-order ``p``), by reciprocity if needed.
    point, inner
        The contact point and a point at distance ``spacing`` from it, on the
        side opposite to the rotation's positive direction (i.e. at
        ``z_point − spacing`` for ``ry = +dx/dz``).
    spacing
        Distance s [m] > 0.
    method
        ``"first-order"``: ``n = (h_33 − h_43)/s``, ``p = n²/h_33``;
        ``"second-order"``: same ``n``, ``p = (h_33 − h_34 − h_43 + h_44)/s²``.
    translation, rotation
        Directions of the bending plane (default ``x`` and ``ry``).

    Returns
    -------
    FRF
        ``H_33`` labelled ``(point, translation), (point, rotation)``.

    Raises
    ------
    InputError
        Non-positive spacing, ``point == inner``, unknown method, missing FRFs.
    NumericalError
        First-order ``p`` where ``h_33`` is zero.
    """
    if not (np.isfinite(spacing) and spacing > 0):
        raise InputError(f"spacing must be > 0 m, got {spacing!r}")
    if point == inner:
        raise InputError(f"point and inner are both node {point}; the inner point must be another node")
    if method not in ("first-order", "second-order"):
        raise InputError(f"method {method!r}: expected first-order or second-order")
    H = as_receptance("substructure A", frf_a)
    t = translation
    d3, d4 = Dof(point, t), Dof(inner, t)
    h33 = fetch("substructure A", H, [d3], [d3])[:, 0, 0]
    h43 = fetch("substructure A", H, [d4], [d3])[:, 0, 0]
    n = (h33 - h43) / spacing
    if method == "first-order":
        with np.errstate(divide="ignore", invalid="ignore"):
            p = n * n / h33
        if not np.all(np.isfinite(p)):
            raise NumericalError("h_33 is zero at some line; p = n²/h is undefined there")
    else:
        h34 = fetch("substructure A", H, [d3], [d4])[:, 0, 0]
        h44 = fetch("substructure A", H, [d4], [d4], "h_44 is needed for the second-order estimate")[:, 0, 0]
        p = (h33 - h34 - h43 + h44) / spacing**2
    vals = np.empty((H.n_freq, 2, 2), dtype=complex)
    vals[:, 0, 0], vals[:, 0, 1], vals[:, 1, 0], vals[:, 1, 1] = h33, n, n, p
    a = [d3, Dof(point, rotation)]
    return FRF(H.freq, vals, a, a, Quantity.RECEPTANCE)
