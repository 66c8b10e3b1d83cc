"""Before/after figures of a diagnosis (matplotlib, Agg backend).

- ``diagnose-frf.png``: recorded, nominal and augmented FRF magnitude and
  phase for every recorded output (first input; one column per level), with
  the located mode bands shaded by their mismatch;
- ``diagnose-shifts.png``: per-mode frequency shift and damping ratio
  (recorded vs model) before and after the refit;
- ``backbone.png`` (:func:`plot_backbone`, with recordings at several
  excitation levels): per mode, the local-fit frequency and damping ratio
  against the response amplitude of each level, with 1-σ error bars, and
  optionally the augmented model's values at the same levels.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from jointdb.errors import InputError
from jointdb.plots._axes import phase_deg
from jointdb.plots._frf import save_figure


def _plt():
    from jointdb.plots._frf import _pyplot

    return _pyplot()


def plot_diagnosis(result, directory: Path) -> list[str]:
    """Write the figures of a :class:`jointdb.diagnose.Diagnosis`.

    Parameters
    ----------
    result
        The :class:`jointdb.diagnose.Diagnosis`.
    directory
        Existing directory the PNG files go to.

    Returns
    -------
    list of str
        The paths written.
    """
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
            ax_p.plot(*phase_deg(f, rec), lw=1.0, color=line.get_color())
            ax_p.plot(*phase_deg(f, result.H_before[lv, :, i, 0]), "--", color=line.get_color(), lw=0.8)
            if result.H_after is not None:
                ax_m.semilogy(f, np.abs(result.H_after[lv, :, i, 0]), ":", color="k", lw=1.0)
                ax_p.plot(*phase_deg(f, result.H_after[lv, :, i, 0]), ":", color="k", lw=1.0)
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
    paths = [str(save_figure(fig, directory / "diagnose-frf.png", dpi=110))]

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
    paths.append(str(save_figure(fig, directory / "diagnose-shifts.png", dpi=110)))
    return paths


def plot_backbone(analysis, path, model_analysis=None) -> Path:
    """Backbone figure: frequency and damping ratio of each mode against the response amplitude per level.

    Parameters
    ----------
    analysis
        :class:`jointdb.diagnose._levels.LevelAnalysis` of the recordings
        (one row of panels per tracked mode; error bars are the 1-σ of the
        local fits).
    path
        Image file to write (``.png``; ``.pdf``/``.svg`` also work).
    model_analysis
        Optional ``LevelAnalysis`` of the augmented model's per-level FRFs,
        drawn dashed over the recorded points (matched by mode number).

    Returns
    -------
    pathlib.Path
        The file written (atomically).

    Raises
    ------
    InputError
        No tracked mode, or an unknown image suffix.
    """
    if not analysis.tracks:
        raise InputError("backbone plot: no mode could be followed across the levels")
    plt = _plt()
    order = list(analysis.order)
    model = {t.mode: t for t in (model_analysis.tracks if model_analysis is not None else ())}
    n = len(analysis.tracks)
    fig, axes = plt.subplots(n, 2, figsize=(10, 2.8 * n + 0.6), squeeze=False)
    for row, t in zip(axes, analysis.tracks):
        ax_f, ax_z = row
        x = t.amplitude[order]
        label = "recorded (local modal fit)" + (" — changes with level" if t.differs else "")
        ax_f.errorbar(x, t.freq_hz[order], yerr=t.sigma_freq_hz[order], fmt="o-", capsize=3, label=label)
        ax_z.errorbar(x, 100 * t.zeta[order], yerr=100 * t.sigma_zeta[order], fmt="o-", capsize=3)
        m = model.get(t.mode)
        if m is not None and len(m.freq_hz) == len(t.freq_hz):
            o = list(model_analysis.order)
            ax_f.plot(m.amplitude[o], m.freq_hz[o], "s--", color="k", mfc="none", label="augmented model")
            ax_z.plot(m.amplitude[o], 100 * m.zeta[o], "s--", color="k", mfc="none")
        for ax in (ax_f, ax_z):
            ax.ticklabel_format(axis="y", useOffset=False, style="plain")
            if np.all(x > 0) and x.max() > 3 * x.min():
                from matplotlib.ticker import NullFormatter

                ax.set_xscale("log")
                ax.xaxis.set_minor_formatter(NullFormatter())
            ax.grid(True, alpha=0.3)
            ax.set_xlabel(f"response amplitude at the peak [{t.amplitude_unit}]")
        for k, lv in zip(order, x):
            level = analysis.levels[k]
            if level is not None:
                ax_f.annotate(f"{level:g}", (lv, t.freq_hz[k]), textcoords="offset points", xytext=(4, 4),
                              fontsize=7, color="0.35")
        ax_f.set_ylabel(f"mode {t.mode}: frequency [Hz]")
        ax_z.set_ylabel(f"mode {t.mode}: damping ratio ζ [%]")
        ax_f.legend(fontsize=7, loc="best")
    fig.suptitle("backbone: each mode's frequency and damping per excitation level (labels: level; "
                 "bars: ±1σ)", fontsize=9)
    fig.tight_layout()
    return save_figure(fig, path, dpi=110)
