"""Figures for stability lobes and modal fits (matplotlib, Agg backend, imported lazily)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from jointdb.plots._axes import percent, phase_deg
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
    show_lobes: bool = False, depth_max: float | None = None, shade: bool = True, band=None,
    flute_length_m: float | None = None, joints: str | None = None,
):
    """Stability lobe diagram: limiting depth against spindle speed, the stable region shaded.

    ``results`` is one :class:`~jointdb.stability.LobeResult` or a sequence (overlaid, e.g. ZOA
    and SD, or with and without joints); the region below the first result's limit is shaded as
    stable, without gaps (:func:`jointdb.plots._envelope.shade_depth`). Frequency-domain envelopes
    are drawn between the FRF lines on fine speeds (:func:`jointdb.plots._envelope.drawn_envelope`),
    so no lobe is a straight segment. Flip-type limits are marked; folds (SD boundaries with a real
    multiplier +1, not chatter limits) and non-finite depths break the line and are counted in the
    legend. The depth axis stops at the flute length, or without one at
    :data:`~jointdb.plots._envelope.FLOOR_MULTIPLE` × the floor; the title's second line gives the
    cutting parameters (from the results' ``info``), the third the joints.

    Parameters
    ----------
    results
        One :class:`~jointdb.stability.LobeResult` or a sequence of them.
    title
        Figure title (first line).
    depth_unit
        ``"m"``, ``"mm"`` or ``"um"`` on the depth axis.
    labels
        Legend label per result (default: its method).
    show_lobes
        Also draw the individual lobes, thin, behind the envelope.
    depth_max
        Upper limit of the depth axis [m]; default: see above.
    shade
        Shade the stable region below the first result.
    band
        A :class:`jointdb.stability._band.LobeBand` (5–95 % of the limiting depth), shaded, and
        annotated when narrower than the envelope's line; or None.
    flute_length_m
        The tool's flute length [m]: the depth axis never goes above it. None: unknown.
    joints
        The joints used (e.g. :func:`jointdb.plots.joints_legend`), put under the title; or None.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import textwrap

    from jointdb.plots._envelope import cut_caption, depth_cap, drawn_envelope

    plt = _plt()
    results = list(results) if isinstance(results, (list, tuple)) else [results]
    scale = _UNIT[depth_unit]
    drawn = [drawn_envelope(res) for res in results]
    floors = [np.nanmin(d) for _, d in drawn if np.any(np.isfinite(d))]
    flute = None if flute_length_m is None else flute_length_m * scale
    top, cap_note = depth_cap(np.concatenate([d for _, d in drawn]) * scale, max(floors, default=np.nan) * scale, flute)
    if depth_max:
        top, cap_note = depth_max * scale, ""
    if cap_note:
        cap_note += f" ({top:.3g} {depth_unit})"
    fig, ax = plt.subplots(figsize=(8, 6))
    colours = ["C0", "C3", "C2", "C1", "C4"]
    for i, (res, (speed, depth)) in enumerate(zip(results, drawn)):
        _draw_result(ax, res, speed, depth * scale, top, colours[i % len(colours)],
                     labels[i] if labels else res.method, shade=shade and i == 0, show_lobes=show_lobes,
                     scale=scale, unit=depth_unit, several=len(results) > 1)
    if flute is not None and top >= flute:  # the flutes end there: deeper is no cut at all
        ax.axhspan(flute, 1.08 * flute, color="0.85", lw=0, zorder=3)
        ax.axhline(flute, color="k", lw=1.0, ls="--", zorder=3, label=f"flute length {flute:.3g} {depth_unit}")
        top = 1.08 * flute
    band_width = _draw_band(ax, band, scale, depth_unit) if band is not None else None
    ax.set_xlim(min(float(r.spindle_speed_rpm.min()) for r in results),
                max(float(r.spindle_speed_rpm.max()) for r in results))
    ax.set_ylim(0, top)
    ax.set_xlabel("spindle speed [rpm]")
    ax.set_ylabel(f"limiting depth of cut [{depth_unit}]")
    lines = ["\n".join(textwrap.wrap(title or "Stability lobes", 90))]
    lines.append(cut_caption(results[0].info, results[0].method) + (f"; {cap_note}" if cap_note else ""))
    if joints:
        lines += textwrap.wrap(f"joints: {joints}", 110)
    ax.set_title(lines[0], fontsize=10, loc="center", pad=6 + 11 * (len(lines) - 1))
    ax.text(0.5, 1.01, "\n".join(lines[1:]), transform=ax.transAxes, ha="center", va="bottom", fontsize=7.5)
    ax.grid(True, alpha=0.3)
    # below the axes: inside, it hides the lobes (or the shading) of some speed range
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.11), fontsize=7.5, ncol=2, frameon=False)
    fig.tight_layout()
    if band_width is not None:
        _note_thin_band(ax, *band_width)
    return fig


def _draw_result(ax, res, speed, depth, top, colour, label, *, shade, show_lobes, scale, unit, several) -> None:
    """One result: shading (gap-free), envelope, flips, the count of folds and clipped pockets."""
    from jointdb.plots._envelope import shade_depth

    if shade:
        ax.fill_between(speed, 0, np.minimum(shade_depth(depth, top), top), color=colour, alpha=0.12, lw=0,
                        label=f"stable ({label})" if several else "stable")
    if show_lobes and res.lobes:
        for lobe in res.lobes:
            ax.plot(lobe.spindle_speed_rpm, lobe.depth_m * scale, color=colour, lw=0.4, alpha=0.25)
    ax.plot(speed, depth, color=colour, lw=1.6, label=label)
    d = res.depth_m
    flip = (res.kind == "flip") & np.isfinite(d)
    if np.any(flip):
        ax.plot(res.spindle_speed_rpm[flip], d[flip] * scale, "v", color=colour, ms=3.5, label=f"{label}: flip")
    folds = int(np.sum(res.kind == "fold"))
    if folds:
        ax.plot([], [], " ", label=f"{label}: {folds} fold point{'s' if folds > 1 else ''} (multiplier +1) not drawn")
    if np.nanmax(np.where(np.isfinite(depth), depth, -np.inf), initial=-np.inf) > top:
        k = int(np.nanargmax(np.where(np.isfinite(depth), depth, -np.inf)))
        ax.plot([speed[k]], [top], "^", color=colour, ms=5, clip_on=False,
                label=f"{label}: highest pocket {depth[k]:.3g} {unit} at {speed[k]:.0f} rpm (above the axis)")


def _draw_band(ax, band, scale, depth_unit) -> tuple[float, float]:
    """The 5–95 % band of the limiting depth in its own colour; returns (median width in axis units,
    half-width of the floor band relative to its median)."""
    lo, mid, hi = band.critical_depth_m
    width = (hi - lo) / 2 / mid if mid > 0 else 0.0
    d05, d95 = band.depth_m[0] * scale, band.depth_m[2] * scale
    ax.fill_between(band.spindle_speed_rpm, d05, d95, color="tab:orange", alpha=0.45, lw=0, zorder=1.5,
                    label=f"5–95 % band ({band.samples} samples), floor {lo * scale:#.3g}–{hi * scale:#.3g} "
                          f"{depth_unit} (±{percent(width)})")
    return float(np.nanmedian(d95 - d05)), width


def _note_thin_band(ax, median_width: float, relative: float) -> None:
    """Say so when the band, on this axis, is thinner than two widths of the envelope's line (1.6 pt):
    else it looks like no band at all."""
    px_per_unit = ax.get_window_extent().height / (ax.get_ylim()[1] - ax.get_ylim()[0])
    points = median_width * px_per_unit * 72.0 / ax.figure.dpi
    if not np.isfinite(points) or points < 2 * 1.6:
        ax.annotate(f"band ±{percent(relative)} of the floor: narrower than the line", xy=(0.99, 0.02),
                    xycoords="axes fraction", ha="right", va="bottom", fontsize=8, color="tab:orange")


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
