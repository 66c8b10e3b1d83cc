"""Both bending planes in one coupling chain, for a spindle side whose x and y planes are coupled.

The tool and the holder are axisymmetric beams: their x plane (x, θ_x = ry)
and y plane (y, θ_y = −rx) are independent and equal. A measured spindle
receptance may couple them (cross terms ``H[x, y]``, ``H[x, rx]`` ...,
e.g. from anisotropic or cross-coupled bearings, or a spindle housing that is
not symmetric). Then the two planes cannot be predicted one at a time: each
point carries the four DOFs ``(x, θ_x, y, θ_y)`` and the chain of
:func:`jointdb.stack.attach` runs on 4×4 blocks; the tool tip gets the full
2×2 ``(x, y)`` receptance including ``H[x, y]`` and ``H[y, x]``.

Pure numerics on arrays ``(n_freq, n, n)``.
"""

from __future__ import annotations

import numpy as np

from jointdb.errors import InputError
from jointdb.frf import FRF
from jointdb.stack._chain import attach

__all__ = ["spindle_four", "two_plane_tip"]

#: (x, θ_x, y, θ_y) from the file's (x, ry, y, rx): θ_y = +dy/dz = −rx.
_SIGNS = np.array([1.0, 1.0, 1.0, -1.0])


def spindle_four(frf: FRF, node: int, rel_tol: float = 1e-9) -> np.ndarray | None:
    """The spindle's 4×4 receptance over ``(x, θ_x, y, θ_y)`` at ``node`` if it couples the planes, else None.

    Parameters
    ----------
    frf
        Spindle-side receptance (square after reciprocity completion) with ``x, ry, y, rx`` at ``node``.
    node
        Node number of the connection point.
    rel_tol
        Cross terms smaller than ``rel_tol`` × the largest driving-point term count as absent.

    Returns
    -------
    ndarray ``(n_freq, 4, 4)`` or None
        None when y or rx is missing, or when every x–y cross term is zero (independent planes).

    Raises
    ------
    InputError
        If the FRF cannot be completed by reciprocity.
    """
    outs = {d.direction: d for d in frf.outputs if d.node == node}
    if not all(k in outs for k in ("x", "ry", "y", "rx")):
        return None
    try:
        sq = frf.complete_reciprocal()
    except InputError as exc:
        raise InputError(f"spindle FRF: {exc}") from None
    order = [outs["x"], outs["ry"], outs["y"], outs["rx"]]
    block = sq.block(order, order) * _SIGNS[None, :, None] * _SIGNS[None, None, :]
    cross = np.abs(block[:, :2, 2:]).max(initial=0.0) + np.abs(block[:, 2:, :2]).max(initial=0.0)
    scale = np.abs(block[:, [0, 2], [0, 2]]).max(initial=0.0)
    if scale == 0 or cross <= rel_tol * scale:
        return None
    return block


def _two_planes(part: np.ndarray) -> np.ndarray:
    """An axisymmetric part's (n_freq, 4, 4) planar receptance over (p1 x, p1 θ, p2 x, p2 θ) → (n_freq, 8, 8)
    over (p1: x, θ_x, y, θ_y; p2: x, θ_x, y, θ_y)."""
    nf = part.shape[0]
    out = np.zeros((nf, 8, 8), dtype=complex)
    for plane in (0, 2):  # offset of the plane inside a point's 4 DOFs
        idx = np.array([0 + plane, 1 + plane, 4 + plane, 5 + plane])
        out[:, idx[:, None], idx[None, :]] = part
    return out


def _joint4(planes: dict[str, np.ndarray] | None) -> np.ndarray | None:
    if planes is None:
        return None
    nf = planes["x"].shape[0]
    out = np.zeros((nf, 4, 4), dtype=complex)
    out[:, :2, :2] = planes["x"]
    out[:, 2:, 2:] = planes["y"]
    return out


def two_plane_tip(tool: np.ndarray, holder: np.ndarray, spindle4: np.ndarray,
                  joint_th: dict[str, np.ndarray] | None = None,
                  joint_hs: dict[str, np.ndarray] | None = None) -> np.ndarray:
    """Tool-tip 4×4 receptance over ``(x, θ_x, y, θ_y)`` of tool + holder + a plane-coupling spindle.

    Parameters
    ----------
    tool, holder
        Planar free receptances ``(n_freq, 4, 4)`` over (point 1 x, θ, point 2 x, θ) — the same in both
        planes (axisymmetric parts).
    spindle4
        Spindle receptance ``(n_freq, 4, 4)`` from :func:`spindle_four`.
    joint_th, joint_hs
        Joint receptances per plane ``{"x": (n_freq, 2, 2), "y": ...}`` or None (rigid).

    Returns
    -------
    ndarray ``(n_freq, 4, 4)``

    Raises
    ------
    NumericalError
        Singular interface matrix at some line.
    """
    t, h = _two_planes(np.asarray(tool)), _two_planes(np.asarray(holder))
    g33 = attach(h[:, :4, :4], h[:, :4, 4:], h[:, 4:, :4], h[:, 4:, 4:], spindle4, _joint4(joint_hs))
    return attach(t[:, :4, :4], t[:, :4, 4:], t[:, 4:, :4], t[:, 4:, 4:], g33, _joint4(joint_th))
