"""Small 3-D frame structures (grillage plates, block frames) for validation cases.

Pure numpy. Euler–Bernoulli frame elements with consistent mass; 6 DOFs per
node in global axes ``x y z rx ry rz``. Used by the thesis ch. 5 (two plates,
four bolts) and ch. 6 (two 3-D bodies, joint with inertia) validation cases,
the fixture generator and the benchmarks. Not a general FE package (that is
:mod:`jointdb.fe`); these bodies need nodes off a single axis.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from jointdb.frf import DIRECTIONS, Dof

__all__ = ["FrameSection", "frame_element", "Frame", "grillage", "block_frame", "merge"]


@dataclass(frozen=True)
class FrameSection:
    """Cross-section and material of a frame member (SI)."""

    E: float
    G: float
    rho: float
    A: float
    Iy: float
    Iz: float
    J: float

    @classmethod
    def rectangle(cls, b: float, h: float, E=200e9, nu=0.3, rho=7850.0) -> "FrameSection":
        a = b * h
        iy, iz = b * h**3 / 12, h * b**3 / 12
        lo, hi = min(b, h), max(b, h)
        j = lo**3 * hi * (1 / 3 - 0.21 * lo / hi * (1 - lo**4 / (12 * hi**4)))
        return cls(E, E / (2 * (1 + nu)), rho, a, iy, iz, j)


def frame_element(p1: np.ndarray, p2: np.ndarray, s: FrameSection) -> tuple[np.ndarray, np.ndarray]:
    """Global 12×12 stiffness and consistent mass of a frame element from ``p1`` to ``p2``."""
    d = np.asarray(p2, float) - np.asarray(p1, float)
    L = float(np.linalg.norm(d))
    e1 = d / L
    ref = np.array([0.0, 0.0, 1.0]) if abs(e1[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    e2 = np.cross(ref, e1)
    e2 /= np.linalg.norm(e2)
    e3 = np.cross(e1, e2)
    R = np.vstack([e1, e2, e3])
    k = np.zeros((12, 12))
    m = np.zeros((12, 12))
    ea, gj = s.E * s.A / L, s.G * s.J / L
    for (i, j), v in {(0, 0): ea, (6, 6): ea, (0, 6): -ea, (3, 3): gj, (9, 9): gj, (3, 9): -gj}.items():
        k[i, j] = v
        k[j, i] = v
    mt = s.rho * s.A * L
    for (i, j), v in {(0, 0): mt / 3, (6, 6): mt / 3, (0, 6): mt / 6}.items():
        m[i, j] = v
        m[j, i] = v
    jp = s.rho * (s.Iy + s.Iz) * L
    for (i, j), v in {(3, 3): jp / 3, (9, 9): jp / 3, (3, 9): jp / 6}.items():
        m[i, j] = v
        m[j, i] = v
    kb = np.array([[12, 6 * L, -12, 6 * L], [6 * L, 4 * L * L, -6 * L, 2 * L * L],
                   [-12, -6 * L, 12, -6 * L], [6 * L, 2 * L * L, -6 * L, 4 * L * L]]) / L**3
    mb = mt / 420 * np.array([[156, 22 * L, 54, -13 * L], [22 * L, 4 * L * L, 13 * L, -3 * L * L],
                              [54, 13 * L, 156, -22 * L], [-13 * L, -3 * L * L, -22 * L, 4 * L * L]])
    # bending in the local x-y plane: (v, θz); in x-z: (w, θy) with θy = −dw/dx
    for idx, ei, sign in (([1, 5, 7, 11], s.E * s.Iz, 1.0), ([2, 4, 8, 10], s.E * s.Iy, -1.0)):
        sgn = np.array([1.0, sign, 1.0, sign])
        ix = np.ix_(idx, idx)
        k[ix] += ei * kb * np.outer(sgn, sgn)
        m[ix] += mb * np.outer(sgn, sgn)
    T = np.kron(np.eye(4), R)
    return T.T @ k @ T, T.T @ m @ T


@dataclass(frozen=True, eq=False)
class Frame:
    """Assembled frame: matrices over 6 DOFs per node, nodes labelled by integers."""

    K: np.ndarray
    M: np.ndarray
    nodes: tuple[int, ...]
    coords: np.ndarray

    @property
    def labels(self) -> tuple[Dof, ...]:
        return tuple(Dof(n, d) for n in self.nodes for d in DIRECTIONS)

    def index(self, dof: "Dof | str") -> int:
        dof = Dof.parse(dof)
        return self.nodes.index(dof.node) * 6 + DIRECTIONS.index(dof.direction)


def _assemble(coords: np.ndarray, nodes: Sequence[int], members: Sequence[tuple[int, int]],
              section: FrameSection) -> Frame:
    n = len(nodes)
    K = np.zeros((6 * n, 6 * n))
    M = np.zeros((6 * n, 6 * n))
    for i, j in members:
        ke, me = frame_element(coords[i], coords[j], section)
        dof = np.r_[6 * i : 6 * i + 6, 6 * j : 6 * j + 6]
        ix = np.ix_(dof, dof)
        K[ix] += ke
        M[ix] += me
    return Frame(K, M, tuple(int(x) for x in nodes), np.asarray(coords, float))


def grillage(lx: float, ly: float, nx: int, ny: int, section: FrameSection, first_node: int,
             z: float = 0.0) -> Frame:
    """A rectangular grillage plate in the x-y plane: (nx+1)×(ny+1) nodes, numbered row by row."""
    xs, ys = np.linspace(0, lx, nx + 1), np.linspace(0, ly, ny + 1)
    coords = np.array([[x, y, z] for y in ys for x in xs])
    members = []
    for r in range(ny + 1):
        for c in range(nx + 1):
            k = r * (nx + 1) + c
            if c < nx:
                members.append((k, k + 1))
            if r < ny:
                members.append((k, k + nx + 1))
    nodes = [first_node + k for k in range(len(coords))]
    return _assemble(coords, nodes, members, section)


def block_frame(size: tuple[float, float, float], section: FrameSection, first_node: int,
                origin=(0.0, 0.0, 0.0)) -> Frame:
    """A 3-D box frame (8 corners, 12 edges, 4 face diagonals on top and bottom, 4 mid-edge nodes of
    the vertical edges), a stiff, three-dimensional body with well-separated modes."""
    a, b, c = size
    o = np.asarray(origin, float)
    corners = [(0, 0, 0), (a, 0, 0), (a, b, 0), (0, b, 0), (0, 0, c), (a, 0, c), (a, b, c), (0, b, c)]
    mids = [(0, 0, c / 2), (a, 0, c / 2), (a, b, c / 2), (0, b, c / 2)]
    coords = np.array(corners + mids, float) + o
    members = [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4), (0, 2), (4, 6),
               (0, 8), (8, 4), (1, 9), (9, 5), (2, 10), (10, 6), (3, 11), (11, 7), (8, 9), (10, 11)]
    nodes = [first_node + k for k in range(len(coords))]
    return _assemble(coords, nodes, members, section)


def merge(*frames: Frame) -> tuple[np.ndarray, np.ndarray, tuple[Dof, ...]]:
    """Block-diagonal K, M and labels of several (uncoupled) frames."""
    n = sum(f.K.shape[0] for f in frames)
    K = np.zeros((n, n))
    M = np.zeros((n, n))
    labels: list[Dof] = []
    o = 0
    for f in frames:
        m = f.K.shape[0]
        K[o : o + m, o : o + m] = f.K
        M[o : o + m, o : o + m] = f.M
        labels += list(f.labels)
        o += m
    return K, M, tuple(labels)
