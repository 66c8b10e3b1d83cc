"""The bare beam matrices ``(K, M)`` of a mesh (Timoshenko or Euler–Bernoulli elements, no
ingredients), and the memo that lets the models of a fit share them.

A fit builds one model per evaluation that differs from the last only in a stiffness, a mass or a
damping; those models share one mesh (:meth:`jointdb.fe.BeamModel.mesh`), whose ``_bare`` token
names the bare matrices they all start from. Assembly then adds the ingredients to a copy.
"""

from __future__ import annotations

import threading
from collections import OrderedDict

import numpy as np

from jointdb.fe._elements import bar_matrices, bending_matrices, section_properties, shear_coefficient
from jointdb.fe._mesh import Mesh

__all__ = ["bare_matrices", "remembered_bare_matrices"]

#: Bare beam matrices (K, M) remembered per shared mesh, sections and theory: at most this many pairs and
#: this many bytes in all (a server runs several diagnoses at once), least recently used dropped.
BARE_CACHE_SIZE = 32
BARE_CACHE_BYTES = 32 * 2**20
_BARE_CACHE: OrderedDict = OrderedDict()
_BARE_BYTES = [0]
_BARE_LOCK = threading.Lock()


def remembered_bare_matrices(mesh: Mesh, segs: tuple, theory: str, kind: str) -> tuple[np.ndarray, np.ndarray]:
    """:func:`bare_matrices`, remembered with the mesh's ``_bare`` token (callers get copies to change).

    Parameters
    ----------
    mesh, segs, theory, kind
        As for :func:`bare_matrices`. A mesh without a ``_bare`` token (not shared) is not remembered.

    Returns
    -------
    (K, M)
        ``(n_dof, n_dof)`` each, the caller's own arrays.
    """
    token = mesh.__dict__.get("_bare")
    if token is None:
        return bare_matrices(mesh, segs, theory, kind)
    key = (id(token), theory, segs)
    with _BARE_LOCK:
        hit = _BARE_CACHE.get(key)
        if hit is not None and hit[0] is token:
            _BARE_CACHE.move_to_end(key)
            return hit[1].copy(), hit[2].copy()
    K, M = bare_matrices(mesh, segs, theory, kind)
    with _BARE_LOCK:
        _BARE_CACHE[key] = (token, K.copy(), M.copy())    # the token is kept: its id is not reused
        _BARE_BYTES[0] += 2 * K.nbytes
        while len(_BARE_CACHE) > 1 and (len(_BARE_CACHE) > BARE_CACHE_SIZE or _BARE_BYTES[0] > BARE_CACHE_BYTES):
            _BARE_BYTES[0] -= 2 * _BARE_CACHE.popitem(last=False)[1][1].nbytes
    return K, M


def bare_matrices(mesh: Mesh, segs: tuple, theory: str, kind: str) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness and mass of the bare beam over every DOF of ``mesh`` (SI).

    Parameters
    ----------
    mesh
        The nodes, elements and DOF numbering.
    segs
        The sections that ``mesh.element_section`` indexes (segments, then inserted parts).
    theory
        ``"timoshenko"`` (shear and rotary inertia) or ``"euler-bernoulli"``.
    kind
        ``"planar"`` (x, ry per node) or ``"frame3d"`` (both bending planes, axial and torsion).

    Returns
    -------
    (K, M)
        ``(n_dof, n_dof)`` each.
    """
    seg = mesh.element_section
    mats = [s.mat for s in segs]
    E = np.array([m.E for m in mats])[seg]
    G = np.array([m.G for m in mats])[seg]
    rho = np.array([m.rho for m in mats])[seg]
    nu = np.array([m.nu for m in mats])[seg]
    do = np.array([s.outer_diameter for s in segs])[seg]
    di = np.array([s.inner_diameter for s in segs])[seg]
    A, I, J = section_properties(do, di)
    kappa = shear_coefficient(nu, do, di)
    en = mesh.element_nodes
    L = mesh.node_positions[en[:, 1]] - mesh.node_positions[en[:, 0]]
    timo = theory == "timoshenko"
    kb, mb = bending_matrices(E, G, rho, A, I, kappa, L, shear=timo, rotary_inertia=timo)
    n = mesh.n_dof
    K = np.zeros((n, n))
    M = np.zeros((n, n))
    gd = np.concatenate([mesh.dof_table[en[:, 0]], mesh.dof_table[en[:, 1]]], axis=1)   # (n_el, 2 n_dir)
    nd = len(mesh.directions)

    def scatter(local_dofs, ke, me, sign=None):
        idx = gd[:, local_dofs]
        if sign is not None:
            ke = ke * np.outer(sign, sign)
            me = me * np.outer(sign, sign)
        ii, jj = idx[:, :, None], idx[:, None, :]
        np.add.at(K, (ii, jj), ke)
        np.add.at(M, (ii, jj), me)

    if kind == "planar":
        scatter([0, 1, nd + 0, nd + 1], kb, mb)
    else:
        # x-z plane: (x, ry) with ry = +dx/dz; y-z plane: (y, rx) with rx = -dy/dz
        scatter([0, 4, nd + 0, nd + 4], kb, mb)
        scatter([1, 3, nd + 1, nd + 3], kb, mb, sign=np.array([1.0, -1.0, 1.0, -1.0]))
        ka, ma = bar_matrices(E * A, rho * A, L)
        scatter([2, nd + 2], ka, ma)
        kt, mt = bar_matrices(G * J, rho * J, L)
        scatter([5, nd + 5], kt, mt)
    return K, M
