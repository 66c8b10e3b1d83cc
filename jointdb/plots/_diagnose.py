"""Before/after figures of a diagnosis (matplotlib, Agg backend).

- ``diagnose-frf.png``: recorded, nominal and augmented FRF magnitude and
  phase for every recorded output (first input; one column per level), with
  the located mode bands shaded by their mismatch;
- ``diagnose-shifts.png``: per-mode frequency shift and damping ratio
  (recorded vs model) before and after the refit.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_diagnosis(result, directory: Path) -> list[str]:
    """Write the figures of a :class:`jointdb.diagnose.Diagnosis`; returns the paths written."""
    plt = _plt()
    obs = result.observation
    f = obs.full_freq
    n_out = obs.full_values.shape[2]
    n_lv = obs.full_values.shape[0]
    fig, axes = plt.subplots(2, n_lv, figsize=(6 * n_lv, 7), squeeze=False, sharex=True)
    worst = max((p.mismatch for p in result.before.pairs), default=1.0) or 1.0
    for lv in range(n_lv):
        ax_m, ax_p = axes[0, lv], axes[1, lv]
        for p in result.before.pairs:
            lo, hi = sorted((p.model.freq_hz, p.recorded.freq_hz))
            for ax in (ax_m, ax_p):
                ax.axvspan(lo * 0.97, hi * 1.03, color="tab:red", alpha=0.08 + 0.3 * min(p.mismatch / worst, 1.0))
        for i in range(n_out):
            w = obs.full_weight[lv, :, i, 0] > 0
            rec = np.where(w, obs.full_values[lv, :, i, 0], np.nan)
            label = f"{obs.out_points[i]}:{obs.out_dirs[i]}/{obs.in_points[0]}:{obs.in_dirs[0]}"
            line, = ax_m.semilogy(f, np.abs(rec), lw=1.0, label=f"recorded {label}")
            ax_m.semilogy(f, np.abs(result.H_before[lv, :, i, 0]), "--", color=line.get_color(), lw=0.8)
            ax_p.plot(f, np.degrees(np.angle(rec)), lw=1.0, color=line.get_color())
            ax_p.plot(f, np.degrees(np.angle(result.H_before[lv, :, i, 0])), "--", color=line.get_color(), lw=0.8)
            if result.H_after is not None:
                ax_m.semilogy(f, np.abs(result.H_after[lv, :, i, 0]), ":", color="k", lw=1.0)
                ax_p.plot(f, np.degrees(np.angle(result.H_after[lv, :, i, 0])), ":", color="k", lw=1.0)
        lvl = obs.levels[lv]
        ax_m.set_title(f"level {lvl:g}" if lvl is not None else "recording")
        ax_m.set_ylabel("|H| [m/N]")
        ax_p.set_ylabel("phase [deg]")
        ax_p.set_xlabel("frequency [Hz]")
    axes[0, 0].plot([], [], "--", color="grey", label="nominal model")
    if result.H_after is not None:
        axes[0, 0].plot([], [], ":", color="k", label="augmented model")
    axes[0, 0].legend(fontsize=7, loc="best")
    fig.suptitle(f"mismatch {100 * result.mismatch_before:.1f} % → {100 * result.mismatch_after:.1f} % "
                 "(shaded: located mode bands, darker = larger mismatch)", fontsize=9)
    fig.tight_layout()
    paths = [str(directory / "diagnose-frf.png")]
    fig.savefig(paths[0], dpi=110)
    plt.close(fig)

    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4))
    modes = [p.mode for p in result.before.pairs]
    x = np.arange(len(modes))
    a1.bar(x - 0.2, [100 * p.shift for p in result.before.pairs], 0.4, label="nominal model")
    a2.bar(x - 0.2, [p.damping_ratio for p in result.before.pairs], 0.4, label="nominal model")
    if result.after is not None:
        after = {p.mode: p for p in result.after.pairs}
        a1.bar(x + 0.2, [100 * after[m].shift if m in after else np.nan for m in modes], 0.4, label="augmented")
        a2.bar(x + 0.2, [after[m].damping_ratio if m in after else np.nan for m in modes], 0.4, label="augmented")
    for a in (a1, a2):
        a.set_xticks(x, [f"mode {m}" for m in modes])
        a.legend(fontsize=8)
    a1.axhline(0, color="k", lw=0.5)
    a2.axhline(1, color="k", lw=0.5)
    a1.set_ylabel("f_recorded / f_model − 1 [%]")
    a2.set_ylabel("ζ_recorded / ζ_model")
    a1.set_title("per-mode frequency shift")
    a2.set_title("per-mode damping ratio")
    fig.tight_layout()
    paths.append(str(directory / "diagnose-shifts.png"))
    fig.savefig(paths[1], dpi=110)
    plt.close(fig)
    return paths
