"""Beam element matrices: Timoshenko / Euler–Bernoulli bending, axial bar, torsion.

All functions are vectorised over elements: inputs are arrays of shape
``(n_el,)`` and the matrices come back as ``(n_el, 4, 4)`` (bending) or
``(n_el, 2, 2)`` (axial, torsion). SI units.

Bending element DOFs are ``(v1, θ1, v2, θ2)`` with ``θ = +dv/dz`` (for
Timoshenko, θ is the cross-section rotation). Matrices after Przemieniecki,
*Theory of Matrix Structural Analysis* (1968), and Friedman & Kosmatka,
Comput. Struct. 47 (1993): the interdependent interpolation with
``Φ = 12 E I / (κ G A L²)``, consistent translational and rotary inertia.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "section_properties",
    "shear_coefficient",
    "bending_matrices",
    "bar_matrices",
]


def section_properties(outer_diameter, inner_diameter):
    """Area, second moment of area and polar moment of a (hollow) circle.

    Parameters
    ----------
    outer_diameter, inner_diameter
        Diameters D and d [m] (0 for a solid section); scalars or arrays.

    Returns
    -------
    A, I, J : ndarray
        ``A = π(D² − d²)/4`` [m²], ``I = π(D⁴ − d⁴)/64`` [m⁴] (about either
        bending axis) and ``J = 2 I`` [m⁴] (torsion constant of a circular section).
    """
    do = np.asarray(outer_diameter, dtype=float)
    di = np.asarray(inner_diameter, dtype=float)
    area = np.pi * (do**2 - di**2) / 4.0
    second = np.pi * (do**4 - di**4) / 64.0
    return area, second, 2.0 * second


def shear_coefficient(nu, outer_diameter, inner_diameter=0.0):
    """Timoshenko shear coefficient κ of a solid or hollow circular section.

    Cowper (1966), J. Appl. Mech. 33, 335–340: with ``m = d/D``,
    ``κ = 6(1+ν)(1+m²)² / ((7+6ν)(1+m²)² + (20+12ν)m²)``; for a solid
    circle (m = 0) ``κ = 6(1+ν)/(7+6ν)`` (0.886 for ν = 0.3).

    Parameters
    ----------
    nu
        Poisson's ratio ν.
    outer_diameter, inner_diameter
        Diameters D and d [m] (d = 0: solid); scalars or arrays.

    Returns
    -------
    ndarray
        κ (dimensionless).
    """
    nu = np.asarray(nu, dtype=float)
    m2 = (np.asarray(inner_diameter, dtype=float) / np.asarray(outer_diameter, dtype=float)) ** 2
    a = (1.0 + m2) ** 2
    return 6.0 * (1.0 + nu) * a / ((7.0 + 6.0 * nu) * a + (20.0 + 12.0 * nu) * m2)


def bending_matrices(E, G, rho, A, I, kappa, L, *, shear: bool = True, rotary_inertia: bool = True):
    """Stiffness and consistent mass of planar beam elements.

    Parameters
    ----------
    E, G, rho, A, I, kappa, L
        Arrays ``(n_el,)``: moduli [Pa], density [kg/m³], area [m²], second
        moment [m⁴], shear coefficient [-], element length [m].
    shear
        Include shear deformation (Timoshenko); ``False`` gives Φ = 0.
    rotary_inertia
        Include the rotary inertia ``ρ I`` of the cross-sections.

    Returns
    -------
    K, M : ndarray, shape ``(n_el, 4, 4)``
        DOF order ``(v1, θ1, v2, θ2)``, ``θ = +dv/dz``.
    """
    E, G, rho, A, I, kappa, L = (np.asarray(v, dtype=float) for v in (E, G, rho, A, I, kappa, L))
    phi = 12.0 * E * I / (kappa * G * A * L**2) if shear else np.zeros_like(L)
    n = L.size
    K = np.empty((n, 4, 4))
    c = E * I / (L**3 * (1.0 + phi))
    L2 = L**2
    K[:, 0] = np.stack([12 + 0 * L, 6 * L, -12 + 0 * L, 6 * L], axis=-1)
    K[:, 1] = np.stack([6 * L, (4 + phi) * L2, -6 * L, (2 - phi) * L2], axis=-1)
    K[:, 2] = np.stack([-12 + 0 * L, -6 * L, 12 + 0 * L, -6 * L], axis=-1)
    K[:, 3] = np.stack([6 * L, (2 - phi) * L2, -6 * L, (4 + phi) * L2], axis=-1)
    K *= c[:, None, None]

    p2 = phi**2
    m1 = 13 / 35 + 7 * phi / 10 + p2 / 3
    m2 = (11 / 210 + 11 * phi / 120 + p2 / 24) * L
    m3 = 9 / 70 + 3 * phi / 10 + p2 / 6
    m4 = -(13 / 420 + 3 * phi / 40 + p2 / 24) * L
    m5 = (1 / 105 + phi / 60 + p2 / 120) * L2
    m6 = -(1 / 140 + phi / 60 + p2 / 120) * L2
    Mt = np.stack(
        [
            np.stack([m1, m2, m3, m4], -1),
            np.stack([m2, m5, -m4, m6], -1),
            np.stack([m3, -m4, m1, -m2], -1),
            np.stack([m4, m6, -m2, m5], -1),
        ],
        axis=1,
    )
    Mt *= (rho * A * L / (1.0 + phi) ** 2)[:, None, None]
    if rotary_inertia:
        r1 = 6 / 5 + 0 * L
        r2 = (1 / 10 - phi / 2) * L
        r3 = (2 / 15 + phi / 6 + p2 / 3) * L2
        r4 = (-1 / 30 - phi / 6 + p2 / 6) * L2
        Mr = np.stack(
            [
                np.stack([r1, r2, -r1, r2], -1),
                np.stack([r2, r3, -r2, r4], -1),
                np.stack([-r1, -r2, r1, -r2], -1),
                np.stack([r2, r4, -r2, r3], -1),
            ],
            axis=1,
        )
        Mt = Mt + Mr * (rho * I / (L * (1.0 + phi) ** 2))[:, None, None]
    return K, Mt


def bar_matrices(stiffness, inertia, L):
    """Two-node bar (axial or torsion) elements with consistent mass.

    Parameters
    ----------
    stiffness
        ``E A`` (axial) or ``G J`` (torsion), shape ``(n_el,)``.
    inertia
        ``ρ A`` (axial) or ``ρ J`` (torsion), per unit length.
    L
        Element lengths [m].

    Returns
    -------
    K, M : ndarray, shape ``(n_el, 2, 2)``
        ``K = (s/L)[[1, −1], [−1, 1]]``, ``M = (μL/6)[[2, 1], [1, 2]]``.
    """
    s = np.asarray(stiffness, dtype=float) / np.asarray(L, dtype=float)
    m = np.asarray(inertia, dtype=float) * np.asarray(L, dtype=float) / 6.0
    base_k = np.array([[1.0, -1.0], [-1.0, 1.0]])
    base_m = np.array([[2.0, 1.0], [1.0, 2.0]])
    return s[:, None, None] * base_k, m[:, None, None] * base_m
