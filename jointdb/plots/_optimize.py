"""Figures of ``jointdb optimize``: removal rate against overhang per holder, Pareto front of rate vs margin."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from jointdb.plots._frf import _pyplot, save_figure

__all__ = ["plot_rate_vs_overhang", "plot_pareto"]


def plot_rate_vs_overhang(results, path) -> Path:
    """Best removal rate [cm³/min] against overhang [mm], one line per holder (best over torques and forces)."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7, 4.5))
    holders = sorted({r.candidate.holder for r in results})
    for h in holders:
        best: dict = {}
        for r in results:
            if r.candidate.holder == h:
                g = r.candidate.overhang_m
                best[g] = max(best.get(g, 0.0), r.best["removal_rate_m3_s"])
        g = np.array(sorted(best))
        ax.plot(g * 1e3, [best[x] * 6e7 for x in g], "o-", label=h)
    ax.set_xlabel("overhang (gauge length) [mm]")
    ax.set_ylabel("best stable removal rate [cm³/min]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return save_figure(fig, path)


def plot_pareto(problem, results, path, margins=None) -> Path:
    """Pareto front: the highest removal rate any candidate reaches when a fraction ``margin`` of the
    limiting depth is held back, for margins 0–50 %."""
    from dataclasses import replace

    from jointdb.usecases._optimize import best_cut

    margins = np.linspace(0, 0.5, 11) if margins is None else np.asarray(margins)
    front = []
    for m in margins:
        spec = problem.spec.model_copy(update={"objective": problem.spec.objective.model_copy(update={"margin": float(m)})})
        prob = replace(problem, spec=spec)
        front.append(max(best_cut(prob, r.lobes)["removal_rate_m3_s"] for r in results))
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7, 4.5))
    ax.plot(margins * 100, np.array(front) * 6e7, "o-")
    ax.set_xlabel("stability margin held back [% of the limiting depth]")
    ax.set_ylabel("best removal rate [cm³/min]")
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    return save_figure(fig, path)
