"""Coupling figures: identified k(ω), c(ω); measured vs reconstructed vs rigid-joint FRF (PNG, Agg).

Imported lazily by the CLI and the validation script; the numerical core never imports matplotlib.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from jointdb.frf import FRF, Dof
from jointdb.plots._axes import phase_unwrapped, plot_clipped, robust_limits
from jointdb.plots._frf import _pyplot, _unit, save_figure

__all__ = ["save_kc_plot", "save_comparison_plot", "comparison_figure"]


def save_kc_plot(path: "str | Path", joint: FRF, kc_fit=None, title: str | None = None,
                 flagged: np.ndarray | None = None) -> Path:
    """Equivalent stiffness and damping of each diagonal joint term vs frequency (one row per DOF).

    Parameters
    ----------
    path
        Image file to write (``.png``, ``.pdf``, ``.svg``).
    joint
        The joint receptance (square FRF).
    kc_fit
        A :class:`jointdb.coupling.KCFit` drawn as horizontal lines, or None.
    title
        Figure title.
    flagged
        Bool ``(n_freq,)``: lines to mark as unreliable, or None.

    Returns
    -------
    Path
    """
    from jointdb.coupling import equivalent_stiffness_damping

    plt = _pyplot()
    k, c = equivalent_stiffness_damping(joint)
    n = k.shape[1]
    fig, axes = plt.subplots(n, 2, figsize=(10, 2.6 * n + 0.6), squeeze=False, sharex=True)
    for i, dof in enumerate(joint.inputs):
        unit_k = "N·m/rad" if dof.is_rotation else "N/m"
        unit_c = "N·m·s/rad" if dof.is_rotation else "N·s/m"
        fits = (kc_fit.k[i], kc_fit.c[i]) if kc_fit is not None else (None, None)
        for ax, y, lab, fit in ((axes[i, 0], k[:, i], f"k {dof} [{unit_k}]", fits[0]),
                                (axes[i, 1], c[:, i], f"c {dof} [{unit_c}]", fits[1])):
            # scaled by the 2nd-98th percentile (and the constant fit), not by single spikes
            lim = robust_limits(y)
            if lim is not None and fit is not None and np.isfinite(fit):
                pad = 0.1 * (lim[1] - lim[0])
                lim = (min(lim[0], fit - pad), max(lim[1], fit + pad))
            plot_clipped(ax, joint.freq, y, lim, lw=1.2, label="identified")
            if flagged is not None and flagged.any():
                yf = np.clip(y[flagged], *lim) if lim is not None else y[flagged]
                ax.plot(joint.freq[flagged], yf, "x", ms=3, color="tab:red", label="flagged line")
            ax.set_ylabel(lab)
            ax.grid(True, alpha=0.3)
        if kc_fit is not None:
            axes[i, 0].axhline(kc_fit.k[i], color="k", ls="--", lw=1, label=f"constant fit {kc_fit.k[i]:.4g}")
            axes[i, 1].axhline(kc_fit.c[i], color="k", ls="--", lw=1, label=f"constant fit {kc_fit.c[i]:.4g}")
        axes[i, 0].legend(fontsize=7)
        axes[i, 1].legend(fontsize=7)
    for ax in axes[-1]:
        ax.set_xlabel("frequency [Hz]")
    fig.suptitle(title or "identified joint: equivalent stiffness and damping")
    fig.tight_layout()
    return save_figure(fig, path, dpi=110)


def save_comparison_plot(path: "str | Path", curves: Sequence[tuple[str, FRF]], **kwargs) -> Path:
    """Write :func:`comparison_figure` of ``curves`` to the image file ``path`` (110 dpi).

    Parameters
    ----------
    path
        Image file to write (``.png``, ``.pdf``, ``.svg``).
    curves, **kwargs
        As :func:`comparison_figure` (``pairs``, ``title``).

    Returns
    -------
    Path
    """
    return save_figure(comparison_figure(curves, **kwargs), path, dpi=110)


def comparison_figure(curves: Sequence[tuple[str, FRF]], pairs=None, title: str | None = None):
    """Magnitude (log) and unwrapped phase of several FRFs of the same entries (measured / fitted / rigid).

    The phase is continuous along frequency and every curve is put on the first one's branch
    (:func:`jointdb.plots._axes.phase_unwrapped`): noise near ±180° draws no wrap artefacts.

    Parameters
    ----------
    curves
        ``[(label, FRF), ...]`` with the same DOFs; the first is the reference (e.g. the measurement).
    pairs
        ``[(output, input), ...]`` entries to draw (default: the first four of the first FRF).
    title
        Figure title; default ``"assembly FRF"``.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.ticker import MultipleLocator

    ref = curves[0][1]
    if pairs is None:
        pairs = [(o, i) for o in ref.outputs for i in ref.inputs][:4]
    fig, axes = _pyplot().subplots(2, len(pairs), figsize=(5 * len(pairs), 6), squeeze=False, sharex=True)
    styles = ["-", "--", ":", "-."]
    for j, (o, i) in enumerate(pairs):
        first = None
        for k, (label, frf) in enumerate(curves):
            h = frf.entry(o, i)
            axes[0, j].semilogy(frf.freq, np.abs(h), styles[k % 4], lw=1.3, label=label)
            phase = phase_unwrapped(frf.freq, h, first)
            first = first or (frf.freq, phase)
            axes[1, j].plot(frf.freq, phase, styles[k % 4], lw=1.1)
        axes[0, j].set_title(f"H({o}, {i})")
        axes[0, j].grid(True, which="both", alpha=0.3)
        axes[1, j].yaxis.set_major_locator(MultipleLocator(90))
        axes[1, j].grid(True, alpha=0.3)
        axes[1, j].set_xlabel("frequency [Hz]")
    axes[0, 0].set_ylabel(f"|H| [{_unit(ref, *map(Dof.parse, pairs[0]))}]")
    axes[1, 0].set_ylabel("phase [°], unwrapped")
    axes[0, 0].legend(fontsize=8)
    fig.suptitle(title or "assembly FRF")
    fig.tight_layout()
    return fig
