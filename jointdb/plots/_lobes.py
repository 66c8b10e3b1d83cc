"""Figures for stability lobes and modal fits (matplotlib, Agg backend, imported lazily)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from jointdb.plots._axes import phase_deg
from jointdb.plots._frf import _pyplot, save_figure

__all__ = ["plot_lobes", "lobes_figure", "plot_stabilisation", "plot_modal_fit"]


_plt = _pyplot


_UNIT = {"m": 1.0, "mm": 1e3, "um": 1e6}


def plot_lobes(results, path, **kwargs) -> Path:
    """Write :func:`lobes_figure` to a PNG file.

    Parameters
    ----------
    results
        As :func:`lobes_figure`.
    path
        PNG file to write.
    **kwargs
        Keyword arguments of :func:`lobes_figure`.

    Returns
    -------
    Path
    """
    return save_figure(lobes_figure(results, **kwargs), path, dpi=120)


def lobes_figure(
    results, *, title: str | None = None, depth_unit: str = "mm", labels: Sequence[str] | None = None,
    show_lobes: bool = True, depth_max: float | None = None, shade: bool = True, band=None,
):
    """Stability lobe diagram: limiting depth against spindle speed, the stable region shaded.

    ``results`` is one :class:`~jointdb.stability.LobeResult` or a sequence (overlaid,
    e.g. ZOA and SD, or with and without joints); the region below the first
    result's limit is shaded as stable. Flip-type limits are marked. Folds (SD
    boundaries with a real multiplier +1, not chatter limits) and non-finite
    depths are not drawn: the line breaks there and the legend counts them.
    Individual lobes (turning/ZOA) are drawn thin behind the envelope when
    ``show_lobes``.

    Parameters
    ----------
    results
        One :class:`~jointdb.stability.LobeResult` or a sequence of them.
    title
        Figure title.
    depth_unit
        ``"m"``, ``"mm"`` or ``"um"`` on the depth axis.
    labels
        Legend label per result (default: its method).
    show_lobes
        Draw the individual lobes thin behind the envelope.
    depth_max
        Upper limit of the depth axis [m] (default: 1.1 × the largest depth drawn).
    shade
        Shade the stable region below the first result.
    band
        A :class:`jointdb.stability._band.LobeBand` (the 5–95 % limiting depth from the
        joints' parameter covariance), shaded; or None.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from jointdb.stability import plottable_depth

    plt = _plt()
    if not isinstance(results, (list, tuple)):
        results = [results]
    scale = _UNIT[depth_unit]
    fig, ax = plt.subplots(figsize=(8, 4.8))
    colours = ["C0", "C3", "C2", "C1", "C4"]
    top = 0.0
    if band is not None:  # 5–95 % of the limiting depth: measurement noise, joint choice, prediction path
        lo, hi = band.critical_depth_m[0], band.critical_depth_m[2]
        width = (hi - lo) / 2 / band.critical_depth_m[1] if band.critical_depth_m[1] > 0 else 0.0
        ax.fill_between(band.spindle_speed_rpm, band.depth_m[0] * scale, band.depth_m[2] * scale, color="C0",
                        alpha=0.3, lw=0, label=f"5–95 % band ({band.samples} samples), floor ±{width:.1%}")
        if width < 0.01:  # narrower than the line: say so, or it looks like no band
            ax.annotate(f"band ±{width:.2%}: narrower than the line", xy=(0.99, 0.02), xycoords="axes fraction",
                        ha="right", va="bottom", fontsize=8, color="C0")
    for i, res in enumerate(results):
        c = colours[i % len(colours)]
        label = labels[i] if labels else res.method
        d = plottable_depth(res)
        n = res.spindle_speed_rpm
        if shade and i == 0:
            ax.fill_between(n, 0, np.where(np.isfinite(d), d * scale, 0), where=np.isfinite(d), color=c,
                            alpha=0.12, lw=0, label=f"stable ({label})" if len(results) > 1 else "stable")
        if show_lobes and res.lobes:
            for lobe in res.lobes:
                ax.plot(lobe.spindle_speed_rpm, lobe.depth_m * scale, color=c, lw=0.4, alpha=0.25)
        ax.plot(n, d * scale, color=c, lw=1.6, label=label)
        flip = (res.kind == "flip") & np.isfinite(d)
        if np.any(flip):
            ax.plot(n[flip], d[flip] * scale, "v", color=c, ms=3.5, label=f"{label}: flip")
        folds = int(np.sum(res.kind == "fold"))
        if folds:
            ax.plot([], [], " ", label=f"{label}: {folds} fold point{'s' if folds > 1 else ''} (multiplier +1) not drawn")
        if np.any(np.isfinite(d)):
            top = max(top, float(np.nanmax(d)) * scale)
    ax.set_xlim(min(float(r.spindle_speed_rpm.min()) for r in results), max(float(r.spindle_speed_rpm.max()) for r in results))
    ax.set_ylim(0, depth_max * scale if depth_max else top * 1.1 if top > 0 else 1)
    ax.set_xlabel("spindle speed [rpm]")
    ax.set_ylabel(f"limiting depth of cut [{depth_unit}]")
    import textwrap

    ax.set_title("\n".join(textwrap.wrap(title or "Stability lobes", 90)), fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    return fig


def plot_stabilisation(fit, path, *, frf=None, title: str | None = None) -> Path:
    """Stabilisation diagram (poles per model order, by status) over the FRF magnitude sum.

    Parameters
    ----------
    fit
        A :class:`jointdb.modal.ModalFit`.
    path
        PNG file to write.
    frf
        The fitted FRF, whose magnitude sum is drawn behind the poles; or None.
    title
        Figure title.

    Returns
    -------
    Path
    """
    plt = _plt()
    d = fit.diagram
    fig, ax = plt.subplots(figsize=(8, 5))
    styles = {"o": ("x", "0.6", "new"), "f": ("_", "C1", "stable freq."), "d": ("d", "C2", "stable freq.+damping"),
              "s": ("o", "C0", "stable (all)")}
    for code, (marker, colour, name) in styles.items():
        sel = d.status == code
        if np.any(sel):
            ax.plot(d.freq_hz[sel], d.order[sel], marker, color=colour, ms=4, ls="none", label=name, mfc="none")
    for f in fit.model.freq_hz:
        ax.axvline(f, color="k", lw=0.6, ls=":")
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("model order")
    ax.set_xlim(*d.band)
    if frf is not None:
        ax2 = ax.twinx()
        part = frf.band(*d.band)
        ax2.semilogy(part.freq, np.sum(np.abs(part.values), axis=(1, 2)), color="0.3", lw=0.8)
        ax2.set_ylabel(f"Σ|H| ({part.quantity.value})")
    ax.set_title(title or "Stabilisation diagram (pLSCF)")
    ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    return save_figure(fig, path, dpi=120)


def plot_modal_fit(frf, fit, path, *, title: str | None = None, max_entries: int = 6) -> Path:
    """Measured FRF entries against the re-synthesised modal model (magnitude and phase).

    Parameters
    ----------
    frf
        The measured FRF.
    fit
        The :class:`jointdb.modal.ModalFit` of it.
    path
        PNG file to write.
    title
        Figure title.
    max_entries
        At most this many entries are drawn.

    Returns
    -------
    Path
    """
    plt = _plt()
    part = frf.band(*fit.band)
    syn = fit.model.synthesize(part.freq, part.quantity)
    n_o, n_i = part.values.shape[1:]
    pairs = [(i, j) for i in range(n_o) for j in range(n_i)][:max_entries]
    fig, axes = plt.subplots(2, 1, figsize=(8, 6), sharex=True, gridspec_kw={"height_ratios": [3, 1]})
    for k, (i, j) in enumerate(pairs):
        c = f"C{k}"
        lab = f"{part.outputs[i]}/{part.inputs[j]}"
        axes[0].semilogy(part.freq, np.abs(part.values[:, i, j]), color=c, lw=1.0, label=f"{lab} measured")
        axes[0].semilogy(part.freq, np.abs(syn.values[:, i, j]), color=c, lw=1.0, ls="--",
                         label=f"{lab} fit (FRAC {fit.quality.frac[i, j]:.3f})")
        axes[1].plot(*phase_deg(part.freq, part.values[:, i, j]), color=c, lw=0.8)
        axes[1].plot(*phase_deg(part.freq, syn.values[:, i, j]), color=c, lw=0.8, ls="--")
    axes[0].set_ylabel(f"|H| ({part.quantity.value}, SI)")
    axes[1].set_ylabel("phase [deg]")
    axes[1].set_yticks([-180, -90, 0, 90, 180])
    axes[1].set_xlabel("frequency [Hz]")
    axes[0].legend(fontsize=7, ncol=2)
    axes[0].set_title(title or f"Modal fit: {fit.model.n_modes} modes, NMSE {fit.quality.nmse_total:.2e}")
    fig.tight_layout()
    return save_figure(fig, path, dpi=120)
