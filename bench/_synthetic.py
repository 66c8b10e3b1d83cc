"""Synthetic receptances and the interleaved timing shared by the benchmarks."""

import time

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


def interleaved_timing(contenders: dict, repeat: int, reference: str = "plain"):
    """Run every contender ``repeat`` times, interleaved so that all see the same machine load.

    Returns ``(out, ratio, median)``: each contender's last result, the median of its per-run time
    ratio to ``reference``, and its median time [s].
    """
    times = {k: [] for k in contenders}
    out = {}
    for _ in range(repeat):
        for k, fn in contenders.items():
            t0 = time.perf_counter()
            out[k] = fn()
            times[k].append(time.perf_counter() - t0)
    ratio = {k: float(np.median(np.array(times[k]) / np.array(times[reference]))) for k in contenders}
    med = {k: float(np.median(v)) for k, v in times.items()}
    return out, ratio, med
