"""Three-component receptance coupling chain (docs/theory.md §4, §1a).

Each step joins a substructure A (internal point i, contact point c) to the
driving-point receptance ``G_cc`` of everything behind it, through a massless
joint ``H_J``::

    G_ii = H_ii − H_ic (H_cc + G_cc^B + H_J)⁻¹ H_ci

All blocks are planar 2×2 (x, θ) per point, arrays ``(n_freq, 2, 2)``; one
batched solve per step. Chaining spindle → holder → tool gives the tool tip.
"""

from __future__ import annotations

import numpy as np

from jointdb.errors import NumericalError

__all__ = ["attach", "tool_tip_chain"]


def attach(h_ii, h_ic, h_ci, h_cc, g_cc_behind, h_joint=None) -> np.ndarray:
    """Driving-point receptance at point i of substructure A joined at c to what is behind it.

    Parameters
    ----------
    h_ii, h_ic, h_ci, h_cc
        Free receptance blocks of A, each ``(n_freq, n, n)``.
    g_cc_behind
        Receptance of the rest of the assembly at its contact point, ``(n_freq, n, n)``.
    h_joint
        Joint receptance ``(n_freq, n, n)`` (``u_A − u_B = H_J λ``), ``None`` for rigid.

    Returns
    -------
    ndarray ``(n_freq, n, n)``
        ``G_ii = H_ii − H_ic (H_cc + G_cc + H_J)⁻¹ H_ci`` (docs/theory.md §1a, §4).

    Raises
    ------
    NumericalError
        If the interface matrix is singular at some line.
    """
    b = np.asarray(h_cc) + np.asarray(g_cc_behind)
    if h_joint is not None:
        b = b + np.asarray(h_joint)
    try:
        x = np.linalg.solve(b, h_ci)
    except np.linalg.LinAlgError:
        raise NumericalError("the interface matrix H_cc + G_cc + H_J is singular at some frequency line") from None
    g = h_ii - h_ic @ x
    if not np.all(np.isfinite(g)):
        raise NumericalError("receptance coupling produced NaN/inf (singular interface matrix)")
    return g


def tool_tip_chain(tool, holder, spindle, joint_th=None, joint_hs=None) -> np.ndarray:
    """Tool-tip 2×2 receptance of tool + holder + spindle (docs/theory.md §4).

    Any leading axes before ``n_freq`` broadcast (e.g. a candidate axis: many stacks coupled at
    once).

    Parameters
    ----------
    tool
        Tool overhang free receptance over (tip x, tip θ, base x, base θ),
        ``(n_freq, 4, 4)``.
    holder
        Holder (with clamped shank) free receptance over (nose x, nose θ,
        base x, base θ), ``(n_freq, 4, 4)``.
    spindle
        Spindle-side receptance at its nose (x, θ), ``(n_freq, 2, 2)``.
    joint_th, joint_hs
        Tool–holder and holder–spindle joint receptances ``(n_freq, 2, 2)`` or
        ``None`` (rigid).

    Returns
    -------
    ndarray ``(..., n_freq, 2, 2)``
        ``G_11`` at the tip (x, θ):
        ``G_33 = H_33 − H_34 (H_44 + S_55 + J_hs)⁻¹ H_43`` then
        ``G_11 = h_11 − h_12 (h_22 + G_33 + J_th)⁻¹ h_21``.
    """
    t, h = np.asarray(tool), np.asarray(holder)
    g33 = attach(h[..., :2, :2], h[..., :2, 2:], h[..., 2:, :2], h[..., 2:, 2:], spindle, joint_hs)
    return attach(t[..., :2, :2], t[..., :2, 2:], t[..., 2:, :2], t[..., 2:, 2:], g33, joint_th)
