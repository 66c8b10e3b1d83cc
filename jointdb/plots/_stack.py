"""Figures of a stack prediction: tool-tip FRF with the database joints against rigid joints.

matplotlib (Agg), imported lazily by the CLI and the main job only.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from jointdb.plots._frf import _pyplot, save_figure

__all__ = ["save_tip_comparison", "save_joint_distances", "joints_legend"]


def joints_legend(resolutions) -> str:
    """Short legend text naming the joints used: ``"tool-holder: th-er32-carbide-120nm v1"``, or for an
    interpolated joint its neighbours and weights (``"… v1 (w=0.550), … v1 (w=0.450)"``); rigid joints omitted.

    Parameters
    ----------
    resolutions
        Interface name → :class:`jointdb.usecases.JointResolution`.

    Returns
    -------
    str
        ``"rigid"`` when every joint is rigid.
    """
    parts = []
    for name, res in resolutions.items():
        method = getattr(res, "method", "") or ""
        used = getattr(res, "neighbours", ()) or ()
        if res.kind == "interpolated" and used:
            text = ", ".join(f"{n} v{v} (w={w:.3f})" for n, v, w, _ in used)
            parts.append(f"{name}: {method or 'interpolated'} {text}")
        elif res.kind == "interpolated":
            text = res.description.split(" from ", 1)[-1]
            parts.append(f"{name}: interpolated {text}")
        elif res.name:
            parts.append(f"{name}: {res.name} v{res.version}" + (f" ({method})" if method in ("nearest", "edge")
                                                                  else ""))
        elif res.kind == "explicit":
            parts.append(f"{name}: explicit k, c")
    return "; ".join(parts) or "rigid"


def save_tip_comparison(path, prediction, *, title: str | None = None,
                        extra: Sequence[tuple[str, object]] = (), label: str = "with catalogued joints",
                        band=None) -> Path:
    """Tool-tip receptance magnitude, real and imaginary parts: with joints vs rigid joints.

    Parameters
    ----------
    path
        PNG file to write.
    prediction
        :class:`jointdb.stack.Prediction`.
    title
        Figure title.
    extra
        Further ``(label, FRF)`` curves on the same tip DOFs (e.g. a measurement).
    label
        Legend of the prediction: name the joint versions (and interpolation
        weights), e.g. with :func:`joints_legend`.
    band
        Optional :class:`jointdb.stack._band.TipBand`: its 5–95 % |H| band is shaded.

    Returns
    -------
    Path
    """
    plt = _pyplot()
    tip, rigid = prediction.tip, prediction.rigid
    directions = ["x"]
    if not np.allclose(tip.entry("1y", "1y"), tip.entry("1x", "1x")):
        directions.append("y")
    fig, axes = plt.subplots(2, len(directions), figsize=(7.5 * len(directions), 7.5), sharex=True, squeeze=False)
    for col, d in enumerate(directions):
        dof = f"1{d}"
        curves = [(label, tip, "C0", "-"), ("rigid joints", rigid, "C3", "--")]
        curves += [(name, frf, f"C{2 + i}", ":") for i, (name, frf) in enumerate(extra)]
        ax_m, ax_c = axes[0, col], axes[1, col]
        for name, frf, colour, style in curves:
            h = frf.entry(dof, dof)
            ax_m.semilogy(frf.freq, np.abs(h) * 1e6, style, color=colour, lw=1.3, label=name)
            ax_c.plot(frf.freq, h.real * 1e6, style, color=colour, lw=1.0, label=f"Re, {name}")
            ax_c.plot(frf.freq, h.imag * 1e6, style, color=colour, lw=1.0, alpha=0.5)
        if band is not None and d in band.magnitude:  # 5–95 %: measurement noise, joint choice, prediction path
            p05, p50, p95 = band.peak[d]
            width = (p95 - p05) / 2 / p50 if p50 > 0 else 0.0
            ax_m.fill_between(band.freq, band.magnitude[d][0] * 1e6, band.magnitude[d][2] * 1e6, color="C0", alpha=0.3,
                              lw=0, label=f"5–95 % band ({band.samples} samples), peak ±{width:.1%}"
                              + (" (narrower than the line)" if width < 0.01 else ""))
        ax_m.set_ylabel(f"|H_{d}{d}| [µm/N]")  # one unit per figure: the panel below is in µm/N too
        ax_m.set_title(f"tool tip, {d} direction")
        ax_m.grid(True, which="both", alpha=0.3)
        ax_c.set_ylabel("Re (dark), Im (light) [µm/N]")
        ax_c.set_xlabel("frequency [Hz]")
        ax_c.grid(True, alpha=0.3)
    # one legend for all panels, below them: its labels name joint versions and weights and are long
    import textwrap

    handles, names = axes[0, 0].get_legend_handles_labels()
    names = ["\n".join(textwrap.wrap(n, 110)) for n in names]
    leg = fig.legend(handles, names, loc="lower center", fontsize=7.5, ncol=1, frameon=False)
    fig.suptitle("\n".join(textwrap.wrap(title or "Predicted tool-tip FRF", 100)))
    fig.canvas.draw()
    legend_h = leg.get_window_extent().height / fig.dpi / fig.get_figheight()
    fig.tight_layout(rect=(0, min(0.45, legend_h + 0.02), 1, 1))
    return save_figure(fig, path, dpi=120)


def save_joint_distances(path, resolutions, *, title: str | None = None) -> Path:
    """Bar chart of the candidate joints' distances for each queried interface (chosen one highlighted).

    Parameters
    ----------
    path
        PNG file to write.
    resolutions
        Interface name → :class:`jointdb.usecases.JointResolution`.
    title
        Figure title.

    Returns
    -------
    Path
    """
    plt = _pyplot()
    queried = [r for r in resolutions.values() if r.candidates]
    fig, axes = plt.subplots(1, max(1, len(queried)), figsize=(6.5 * max(1, len(queried)), 3.6), squeeze=False)
    for ax, res in zip(axes[0], queried):
        names = [f"{n}@{v}" for n, v, _ in res.candidates]
        dist = [d for _, _, d in res.candidates]
        colours = ["C0" if (n, v) == (res.name, res.version) else "0.7" for n, v, _ in res.candidates]
        ax.barh(names[::-1], dist[::-1], color=colours[::-1])
        ax.set_xlabel("condition distance [-]")
        ax.set_title(f"{res.interface}: nearest catalogued joints")
        ax.grid(True, axis="x", alpha=0.3)
    if not queried:
        axes[0, 0].text(0.5, 0.5, "no interface was queried", ha="center", va="center")
        axes[0, 0].set_axis_off()
    fig.suptitle(title or "Joint choice")
    fig.tight_layout()
    return save_figure(fig, path, dpi=120)
