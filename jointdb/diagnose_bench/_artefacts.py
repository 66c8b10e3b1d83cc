"""Measured-looking artefacts on a generated case (no openly licensed multi-level recording of a bolted
or clamped joint was found: the Brake–Reuss beam data carry no licence, the UNESP bolted-beam set is
behind a sign-up form; see docs/validation/diagnose-bench.md).

:func:`with_artefacts` turns a case's clean-chain recordings into what a hurried tap or shaker test
gives, on top of the chain's own noise:

- **leakage** of an under-windowed decaying response: each FRF smoothed along frequency by the
  three-line kernel of a Hann window in the frequency domain, ``(¼, ½, ¼)`` (peaks lose height and
  widen, as a too-short record does);
- **coherence dips** at antiresonances: where ``|H|`` is below its 10th percentile the coherence falls
  to 0.5–0.7 and the noise there grows to match (``σ_log = √((1−γ²)/(2 n_avg γ²))``, 10 averages);
- **mass loading** that differs by level: a roving sensor remounted between levels, modelled as a
  frequency-axis scaling by ``1 − ε_l`` with ``ε_l`` 0.05–0.15 % (about a 1–3 g sensor on a small
  beam);
- **one faulty level**: one interior level's peak region smeared twice more (a double hit).

Seeded; returns a new :class:`BenchCase` whose name ends in ``+artefacts``.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from jointdb.diagnose_bench._measure import BenchCase, Recording
from jointdb.frf import FRF

__all__ = ["with_artefacts"]

_HANN = np.array([0.25, 0.5, 0.25])
N_AVERAGES = 10


def _smear(values: np.ndarray) -> np.ndarray:
    """Hann leakage along frequency (axis 0), ends kept."""
    out = values.copy()
    out[1:-1] = _HANN[0] * values[:-2] + _HANN[1] * values[1:-1] + _HANN[2] * values[2:]
    return out


def with_artefacts(case: BenchCase, seed: int = 0) -> BenchCase:
    """The case's recordings with leakage, coherence dips, level-dependent mass loading and one faulty
    level (see the module docstring)."""
    rng = np.random.default_rng(seed)
    recs = []
    n = len(case.recordings)
    faulty = n // 2 if n >= 3 else None
    for k, r in enumerate(case.recordings):
        f = r.frf.freq
        v = _smear(np.asarray(r.frf.values))
        eps = rng.uniform(5e-4, 1.5e-3)
        # mass loading: the response at f is the unloaded one at f (1 + eps) (resonances move down by eps)
        v = np.stack([np.stack([np.interp(f * (1 + eps), f, v[:, o, i].real)
                                + 1j * np.interp(f * (1 + eps), f, v[:, o, i].imag)
                                for i in range(v.shape[2])], axis=-1) for o in range(v.shape[1])], axis=1)
        if k == faulty:
            v = _smear(_smear(v))
        mag = np.abs(v)
        low = mag < np.percentile(mag, 10, axis=0, keepdims=True)
        coh = np.where(low, rng.uniform(0.5, 0.7, size=v.shape), np.asarray(r.coherence))
        sig = np.sqrt((1 - coh) / (2 * N_AVERAGES * coh))
        noise = sig * (rng.standard_normal(v.shape) + 1j * rng.standard_normal(v.shape)) / np.sqrt(2)
        v = np.where(low, v * np.exp(noise), v)
        recs.append(Recording(FRF(f, v, r.frf.outputs, r.frf.inputs, r.frf.quantity), coh, r.level_n))
    return dataclasses.replace(case, name=case.name + "+artefacts", recordings=tuple(recs))
