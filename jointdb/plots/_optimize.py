"""Figures of ``jointdb optimize``: removal rate against overhang per holder, Pareto front of rate vs margin."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from jointdb.plots._frf import _pyplot, save_figure

__all__ = ["plot_rate_vs_overhang", "plot_pareto"]


def plot_rate_vs_overhang(by_holder, path) -> Path:
    """Best removal rate [cm³/min] against overhang [mm], one line per holder.

    Parameters
    ----------
    by_holder
        ``holder -> (overhangs [m], rates [m³/s])``
        (:func:`jointdb.usecases._optimize_run.rate_by_overhang`).
    path
        The PNG to write.

    Returns
    -------
    Path
        ``path``, one line per holder.
    """
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for h, (g, q) in by_holder.items():
        ax.plot(np.asarray(g) * 1e3, np.asarray(q) * 6e7, "o-", label=h)
    ax.set_xlabel("overhang (gauge length) [mm]")
    ax.set_ylabel("best stable removal rate [cm³/min]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return save_figure(fig, path)


def plot_pareto(margins, rates, path, point=None, point_label: str = "recommendation") -> Path:
    """Pareto front: the highest removal rate any candidate reaches against the fraction of the limiting
    depth held back.

    Parameters
    ----------
    margins, rates
        Fractions held back and the best removal rate [m³/s] at each
        (:func:`jointdb.usecases._optimize.pareto_front`).
    path
        The PNG to write.
    point
        ``(margin, rate)`` of the confirmed recommendation, its margin as the fraction of its zero-order
        limit held back (by the margin, the band's lower edge and semi-discretization); drawn as a marker
        labelled ``point_label``.

    Returns
    -------
    Path
        ``path``.
    """
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7, 4.5))
    ax.plot(np.asarray(margins) * 100, np.asarray(rates) * 6e7, "o-",
            label="best of all candidates, zero-order lobes less the margin")
    if point is not None:
        ax.plot([point[0] * 100], [point[1] * 6e7], "r*", markersize=12, label=point_label)
    ax.set_xlabel("stability margin held back [% of the limiting depth]")
    ax.set_ylabel("best removal rate [cm³/min]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return save_figure(fig, path)
