"""Synthetic receptances shared by the coupling and identification benchmarks."""

import numpy as np


def modal_receptance(freq, n, seed):
    """Receptance (n_freq, n, n) of a random damped n-DOF modal model (symmetric, passive)."""
    rng = np.random.default_rng(seed)
    fn = np.sort(rng.uniform(50, 5000, n))
    zeta = rng.uniform(0.005, 0.03, n)
    phi = rng.standard_normal((n, n)) / np.sqrt(n)
    w, wn = 2 * np.pi * freq[:, None], 2 * np.pi * fn[None, :]
    d = 1.0 / (wn**2 - w**2 + 2j * zeta * wn * w)  # unit modal masses
    return np.einsum("im,fm,jm->fij", phi, d, phi, optimize=True)
