"""The benchmark's measurement chain, shared by both truths, and the case records.

A truth supplies noise-free receptances on a fine grid (two sub-lines per
recorded line); :func:`record` turns them into what an analyser would give:
lines averaged over their bin (finite resolution), an optional channel
response (gain, anti-alias filter, skew), seeded complex noise (a proportional
part plus an accelerometer floor that is flat in accelerance) and a
coherence consistent with that noise.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from jointdb.frf import FRF, Dof

__all__ = ["Recording", "BenchCase", "lines", "record"]


@dataclass(frozen=True)
class Recording:
    """One recorded FRF set (outputs x at the recorded points, inputs x at two of them)."""

    frf: FRF
    coherence: np.ndarray          # (n_freq, n_out, n_in), 0..1
    level_n: float | None = None   # excitation force amplitude [N], if known


@dataclass(frozen=True)
class BenchCase:
    """A seeded case: the nominal model (jointdb.fe JSON dict) and its recordings."""

    name: str
    effects: tuple[str, ...]
    seed: int
    truth: dict                    # the hidden parameters, for scoring only
    model: dict                    # jointdb.fe model description (what is diagnosed)
    recordings: tuple[Recording, ...]
    point_map: dict = field(default_factory=dict)   # node -> point name


def lines(f_max: float, df: float):
    """Recorded lines ``df, 2 df, … ≤ f_max`` [Hz] and the fine grid (two sub-lines per bin)."""
    freq = np.arange(1, int(f_max / df) + 1) * df
    sub = np.array([-0.25, 0.25]) * df          # 2-point bin average (finite resolution)
    return freq, (freq[:, None] + sub[None, :]).ravel()


def record(rng, freq, H_fine, out_labels, in_labels, level=None, chain=None):
    """Bin-average ``H_fine`` ``(2 n_freq, n_out, n_in)``, add the channel and seeded noise.

    Returns ``(Recording, relative_noise)``. ``out_labels``/``in_labels`` are
    :class:`jointdb.frf.Dof`; ``chain(freq) -> complex (n_freq,)`` multiplies every FRF.
    """
    n_out, n_in = H_fine.shape[1:]
    H = H_fine.reshape(freq.size, 2, n_out, n_in).mean(axis=1)
    if chain is not None:
        H = H * chain(freq)[:, None, None]
    rel = float(rng.uniform(0.01, 0.02))
    # noise floor of an accelerometer channel: flat in accelerance, so ∝ 1/ω² in receptance
    w2 = (2 * np.pi * freq[:, None, None]) ** 2
    floor = 1e-4 * np.abs(H * w2).max(axis=0, keepdims=True) / w2
    sigma = rel * np.abs(H) + floor
    noise = (rng.standard_normal(H.shape) + 1j * rng.standard_normal(H.shape)) * sigma / np.sqrt(2)
    coh = np.abs(H) ** 2 / (np.abs(H) ** 2 + sigma**2 * (1 + 0.2 * rng.random(H.shape)))
    frf = FRF(freq, H + noise, tuple(out_labels), tuple(in_labels), "receptance")
    return Recording(frf=frf, coherence=coh, level_n=level), rel


def dof_labels(nodes) -> tuple:
    """``Dof(node, "x")`` for each node label."""
    return tuple(Dof(int(n), "x") for n in nodes)
