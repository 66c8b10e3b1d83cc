"""Rigid-body motions of a beam mesh: which remain after supports and constraints, and the
mass-normalised rigid-body modes (exact from geometry, not from an eigen-solve).

The motions of a mesh are remembered by the identity of its DOF labels and node positions: the
models of a fit share one mesh (:mod:`jointdb.fe._model`), so they are computed once per fit.
"""

from __future__ import annotations

import threading
from collections import OrderedDict

import numpy as np

from jointdb.fe._matrices import free_block

__all__ = ["rigid_body_count", "rigid_body_modes"]

#: Rigid-body motions remembered per mesh (its DOF labels and node positions, by identity: a fit's
#: models share one mesh), at most this many.
RIGID_CACHE_SIZE = 64
_RIGID_CACHE: OrderedDict = OrderedDict()
_RIGID_LOCK = threading.Lock()


def _rigid_vectors(matrices, scaled: bool = False) -> np.ndarray:
    """Rigid-body motions of the whole mesh, shape ``(n_dof, r)`` (read-only; shared by the models of a mesh);
    ``scaled``: each divided by its largest entry."""
    labels, z_nodes = matrices.dof_labels, matrices.node_positions
    key = (id(labels), id(z_nodes))
    with _RIGID_LOCK:
        hit = _RIGID_CACHE.get(key)
        if hit is not None and hit[0] is labels and hit[1] is z_nodes:
            _RIGID_CACHE.move_to_end(key)
            return hit[3] if scaled else hit[2]
    R = _rigid_motions(labels, z_nodes)
    scale = np.abs(R).max(axis=0)
    Rs = R / np.where(scale > 0, scale, 1.0)
    R.flags.writeable = Rs.flags.writeable = False
    with _RIGID_LOCK:
        _RIGID_CACHE[key] = (labels, z_nodes, R, Rs)     # the objects are kept: their ids are not reused
        while len(_RIGID_CACHE) > RIGID_CACHE_SIZE:
            _RIGID_CACHE.popitem(last=False)
    return Rs if scaled else R


def _rigid_motions(labels, node_positions) -> np.ndarray:
    """Rigid-body motions of the DOFs ``labels`` of nodes at ``node_positions``, ``(n_dof, r)``."""
    z = node_positions[[d.node for d in labels]]
    dirs = np.array([d.direction for d in labels])
    cols = []
    if set(dirs) <= {"x", "ry"}:
        cols.append(np.where(dirs == "x", 1.0, 0.0))
        cols.append(np.where(dirs == "x", z, np.where(dirs == "ry", 1.0, 0.0)))
    else:
        for t in ("x", "y", "z", "rz"):
            cols.append(np.where(dirs == t, 1.0, 0.0))
        cols.append(np.where(dirs == "x", z, np.where(dirs == "ry", 1.0, 0.0)))  # about y: ry = +dx/dz
        cols.append(np.where(dirs == "y", -z, np.where(dirs == "rx", 1.0, 0.0)))  # about x: rx = -dy/dz
    return np.stack(cols, axis=1)


def _rigid_null_space(matrices) -> np.ndarray:
    """Combinations of rigid motions that strain nothing and move no fixed DOF, ``(n_dof, n_rb)``."""
    R = _rigid_vectors(matrices, scaled=True)
    _, s, vt = np.linalg.svd(_rigid_system(matrices, R), full_matrices=True)
    s = np.concatenate([s, np.zeros(R.shape[1] - s.size)])
    null = vt[s <= 1e-9 * max(1.0, s.max(initial=0.0))]
    return R @ null.T


def _rigid_system(matrices, R: np.ndarray) -> np.ndarray:
    """``[K R / max|K|; R_fixed]``; ``R``: the rigid motions, each scaled to max 1."""
    kscale = float(np.abs(matrices.K).max()) or 1.0
    return np.vstack([matrices.K @ R / kscale, R[matrices.fixed]])


def rigid_body_count(matrices) -> int:
    """Number of rigid-body modes left after constraints and supports.

    A rigid motion ``R a`` is a mode at 0 Hz when it strains nothing
    (``K R a = 0``) and moves no fixed DOF; counted by an SVD of
    ``[K R; R_fixed]`` (small: at most 6 columns).

    Parameters
    ----------
    matrices
        :class:`FEMatrices` with constraints applied.

    Returns
    -------
    int
    """
    R = _rigid_vectors(matrices, scaled=True)
    s = np.linalg.svd(_rigid_system(matrices, R), compute_uv=False)   # the values are all it needs
    s = np.concatenate([s, np.zeros(R.shape[1] - s.size)])
    return int(np.count_nonzero(s <= 1e-9 * max(1.0, s.max(initial=0.0))))


def rigid_body_modes(matrices) -> np.ndarray:
    """Mass-normalised rigid-body modes on the free DOFs, ``(n_free, n_rb)``, exact from geometry."""
    phi = _rigid_null_space(matrices)[~matrices.fixed]
    if phi.shape[1] == 0:
        return phi
    Mf = free_block(matrices.M, matrices.fixed)
    chol = np.linalg.cholesky(phi.T @ Mf @ phi)
    return np.linalg.solve(chol, phi.T).T
