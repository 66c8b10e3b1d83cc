"""Figures of a time-domain milling simulation (matplotlib, Agg backend, imported lazily)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from jointdb.plots._frf import _pyplot, save_figure

__all__ = ["plot_simulation"]


def plot_simulation(sim, path, *, title: str | None = None) -> Path:
    """Tip vibration with the once-per-period samples, cutting force, and the vibration spectrum.

    Parameters
    ----------
    sim
        A :class:`jointdb.stability.SimulationResult`.
    path
        PNG to write.

    Returns
    -------
    Path
        The file written.
    """
    plt = _pyplot()
    fig, axes = plt.subplots(3, 1, figsize=(8, 8.5))
    t, q, f = sim.time_s, sim.displacement_m, sim.force_n
    for k, name in enumerate("xy"):
        axes[0].plot(t, q[:, k] * 1e6, lw=0.6, label=f"{name}")
    idx = sim.once_per_period
    axes[0].plot(t[idx], q[idx, 0] * 1e6, ".", ms=3, color="k", label="x once per period")
    axes[0].set_ylabel("tip displacement [µm]")
    axes[0].legend(loc="upper left", fontsize=8)
    verdict = "chatter" if sim.chatter else "stable"
    axes[0].set_title(title or f"{sim.spindle_speed_rpm:.0f} rpm, a = {sim.depth_m * 1e3:.3g} mm: {verdict} "
                      f"(statistic {sim.statistic:.3g})", fontsize=10)
    for k, name in enumerate("xy"):
        axes[1].plot(t, f[:, k], lw=0.6, label=f"F{name}")
    axes[1].set_ylabel("cutting force on tool [N]")
    axes[1].set_xlabel("time [s]")
    axes[1].legend(loc="upper left", fontsize=8)
    half = q[q.shape[0] // 2:] - q[q.shape[0] // 2:].mean(axis=0)
    dt = t[1] - t[0]
    freq = np.fft.rfftfreq(half.shape[0], dt)
    amp = np.sqrt(np.sum(np.abs(np.fft.rfft(half * np.hanning(half.shape[0])[:, None], axis=0)) ** 2, axis=1))
    axes[2].semilogy(freq[1:], amp[1:] + 1e-300, lw=0.7)
    if np.isfinite(sim.chatter_freq_hz):
        axes[2].axvline(sim.chatter_freq_hz, color="r", ls="--", lw=0.8, label=f"chatter {sim.chatter_freq_hz:.1f} Hz")
        axes[2].legend(fontsize=8)
    axes[2].set_xlim(0, min(freq[-1], 4 * max(sim.chatter_freq_hz if np.isfinite(sim.chatter_freq_hz) else 0, 1000)))
    axes[2].set_xlabel("frequency [Hz]")
    axes[2].set_ylabel("|X| (last half)")
    fig.tight_layout()
    return save_figure(fig, path, dpi=110)
