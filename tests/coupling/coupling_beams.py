"""Small planar Euler–Bernoulli beam matrices for coupling tests (independent of jointdb.fe).

DOFs per node: x (bending translation) and ry = +dx/dz.
"""

import numpy as np

from jointdb.coupling._matrices import receptance_from_matrices

E_STEEL, RHO_STEEL = 200e9, 7850.0


def beam(length, diameter, n_el, E=E_STEEL, rho=RHO_STEEL, eta=0.0):
    """K (complex if eta>0), M of a free-free planar beam; DOF order node0 x, node0 ry, node1 x, ..."""
    A = np.pi * diameter**2 / 4
    I = np.pi * diameter**4 / 64
    L = length / n_el
    ke = E * I / L**3 * np.array(
        [[12, 6 * L, -12, 6 * L], [6 * L, 4 * L * L, -6 * L, 2 * L * L],
         [-12, -6 * L, 12, -6 * L], [6 * L, 2 * L * L, -6 * L, 4 * L * L]])
    me = rho * A * L / 420 * np.array(
        [[156, 22 * L, 54, -13 * L], [22 * L, 4 * L * L, 13 * L, -3 * L * L],
         [54, 13 * L, 156, -22 * L], [-13 * L, -3 * L * L, -22 * L, 4 * L * L]])
    n = 2 * (n_el + 1)
    K = np.zeros((n, n))
    M = np.zeros((n, n))
    for e in range(n_el):
        s = slice(2 * e, 2 * e + 4)
        K[s, s] += ke
        M[s, s] += me
    return K * (1 + 1j * eta), M


def labels_for(nodes):
    out = []
    for nd in nodes:
        out += [f"{nd}x", f"{nd}ry"]
    return out


def clamp_first(K, M, labels):
    """Remove node 0's DOFs (clamped start)."""
    return K[2:, 2:], M[2:, 2:], labels[2:]


def frf(freq, K, M, labels, keep=None, C=None):
    full = receptance_from_matrices(freq, K, M, labels, C)
    if keep is None:
        return full
    return full.select(keep, keep)
