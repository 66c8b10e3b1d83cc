"""The semi-discretization's step integrals Φ0 = e^{AΔt}, Φ1 = ∫₀^Δt e^{As} ds, Φ2 = (1/Δt)∫₀^Δt e^{A(Δt−s)} s ds
(jointdb/stability/_sd.py, ``_exp_integrals``) against quadrature, on the eigen path and on the defective
(Jordan block) matrices that take the Van Loan block exponential instead."""

from __future__ import annotations

import numpy as np
from scipy.integrate import quad_vec
from scipy.linalg import expm

from jointdb.stability._sd import _exp_integrals


def _reference(a: np.ndarray, dt: float):
    phi1 = quad_vec(lambda s: expm(a * s), 0.0, dt, epsabs=0.0, epsrel=1e-12)[0]
    phi2 = quad_vec(lambda s: expm(a * (dt - s)) * s, 0.0, dt, epsabs=0.0, epsrel=1e-12)[0] / dt
    return expm(a * dt), phi1, phi2


def _sdof(wn: float, zeta: float) -> np.ndarray:
    return np.array([[0.0, 1.0], [-wn**2, -2 * zeta * wn]])


def test_step_integrals_equal_quadrature_for_diagonalisable_and_defective_matrices():
    wn, dt = 2 * np.pi * 800.0, 1.0 / 20000.0
    rng = np.random.default_rng(3)
    generic = rng.normal(size=(3, 4, 4)) * 3000.0
    batch = np.concatenate([
        np.stack([_sdof(wn, 0.03), _sdof(wn, 0.2)]),
        # overdamped: one pole at -2.5 1/s, |λΔt| = 1.25e-4, where (e^x - 1 - x)/x² cancels to 1e-8
        np.stack([np.array([[0.0, 1.0], [-wn**2, -4e3 * wn]]), np.array([[-1e-3, 0.0], [0.0, -0.3]])]),
        np.stack([np.array([[-wn, 1.0], [0.0, -wn]]), np.array([[0.0, 1.0], [-wn**2, -2 * wn]])]),  # defective
    ])
    for a in (batch, generic):
        got = _exp_integrals(a, dt)
        for k, m in enumerate(a):
            for g, r in zip(got, _reference(m, dt)):
                np.testing.assert_allclose(g[k], r, rtol=1e-9, atol=1e-9 * np.abs(r).max())
