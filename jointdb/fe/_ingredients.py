"""Model ingredients: boundary conditions, supports, lumped masses, damping.

Each ingredient is a small frozen dataclass with one step,
``apply(matrices, mesh) -> FEMatrices``, applied in turn to the assembled bare
beam (structural ingredients first, then damping ones, each group in the order
given). Because each is independent, a model can switch any one of them on or
off (``BeamModel.with_ingredient`` / ``BeamModel.without``) — which is what the
diagnosis work does to explain a mismatch.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from jointdb.errors import InputError
from jointdb.fe._fields import FieldError, _number
from jointdb.fe._matrices import free_block
from jointdb.fe._synthesis import eigen_free

if TYPE_CHECKING:  # pragma: no cover
    from jointdb.fe._matrices import FEMatrices
    from jointdb.fe._mesh import Mesh

__all__ = [
    "Ingredient",
    "Clamp",
    "Support",
    "PointMass",
    "ModalDamping",
    "RayleighDamping",
    "HystereticDamping",
]


class Ingredient:
    """Base of all ingredients: ``stage`` orders them, ``positions`` feed the mesh."""

    stage: int = 0

    def positions(self) -> tuple[float, ...]:
        """Axial positions [m] where the mesh needs a node.

        Returns
        -------
        tuple of float
        """
        return ()

    def apply(self, matrices: "FEMatrices", mesh: "Mesh") -> "FEMatrices":  # pragma: no cover
        """The matrices with this ingredient applied (a new :class:`FEMatrices`; the input is unchanged).

        Parameters
        ----------
        matrices
            The assembled matrices so far (:class:`FEMatrices`, ``(n_dof, n_dof)`` each).
        mesh
            The model's :class:`Mesh` (node positions, DOF numbering).

        Returns
        -------
        FEMatrices
        """
        raise NotImplementedError


def _check_directions(directions, mesh: "Mesh", what: str) -> None:
    for d in directions:
        if d not in mesh.directions:
            raise InputError(
                f"{what}: direction {d!r} does not exist in a {mesh.kind} model "
                f"(directions: {', '.join(mesh.directions)})"
            )


class _AtOnePosition(Ingredient):
    """An ingredient acting at one axial ``position`` [m], where the mesh needs a node."""

    position: float

    def positions(self) -> tuple[float, ...]:
        """Axial positions [m] where the mesh needs a node: this ingredient's one ``position``.

        Returns
        -------
        tuple of float
        """
        return (self.position,)


@dataclass(frozen=True)
class Clamp(_AtOnePosition):
    """Fix DOFs at one position (all of them by default: a clamped end).

    Parameters
    ----------
    position
        Axial position [m] from the model's start.
    directions
        Directions to fix (e.g. ``("x",)`` for a pinned support in a planar
        model); ``None`` fixes every DOF of the node.
    """

    position: float
    directions: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        _number(self, "position", minimum=0.0)
        if self.directions is not None:
            object.__setattr__(self, "directions", tuple(str(d).lower() for d in self.directions))

    def apply(self, matrices, mesh):
        node = mesh.node_at(self.position, "clamp")
        dirs = mesh.directions if self.directions is None else self.directions
        _check_directions(dirs, mesh, f"clamp at {self.position:g} m")
        fixed = matrices.fixed.copy()
        fixed[[mesh.dof(node, d) for d in dirs]] = True
        return dataclasses.replace(matrices, fixed=fixed)


@dataclass(frozen=True)
class Support(_AtOnePosition):
    """Elastic support to ground: springs and viscous dampers on chosen DOFs.

    Parameters
    ----------
    position
        Axial position [m].
    stiffness
        ``{direction: k}``, N/m for translations, N·m/rad for rotations.
    damping
        ``{direction: c}``, N·s/m or N·m·s/rad.
    """

    position: float
    stiffness: dict = field(default_factory=dict)
    damping: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        _number(self, "position", minimum=0.0)
        for name in ("stiffness", "damping"):
            raw = getattr(self, name)
            if not isinstance(raw, dict):
                raise FieldError(name, f"must be a mapping of direction to value, got {raw!r}")
            clean = {}
            for key, value in raw.items():
                if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                    raise FieldError(f"{name}.{key}", f"must be a finite number, got {value!r}")
                if value < 0:
                    raise FieldError(f"{name}.{key}", f"must be >= 0, got {value:g}")
                clean[str(key).lower()] = float(value)
            object.__setattr__(self, name, clean)

    def __hash__(self) -> int:
        return hash((self.position, tuple(sorted(self.stiffness.items())), tuple(sorted(self.damping.items()))))

    def apply(self, matrices, mesh):
        node = mesh.node_at(self.position, "support")
        what = f"support at {self.position:g} m"
        _check_directions(self.stiffness, mesh, what)
        _check_directions(self.damping, mesh, what)
        K = matrices.K.copy()
        C = matrices.C.copy()
        for d, k in self.stiffness.items():
            i = mesh.dof(node, d)
            K[i, i] += k
        for d, c in self.damping.items():
            i = mesh.dof(node, d)
            C[i, i] += c
        return dataclasses.replace(matrices, K=K, C=C)


@dataclass(frozen=True)
class PointMass(_AtOnePosition):
    """A lumped mass with rotary inertia (sensor, nut, insert) at one position.

    Parameters
    ----------
    position
        Axial position [m].
    mass
        Mass [kg] on the translational DOFs.
    rotary_inertia
        Inertia [kg·m²] about the bending axes (on ``ry``, and ``rx`` in 3-D).
    polar_inertia
        Inertia [kg·m²] about the beam axis (``rz``, 3-D frame only).
    """

    position: float
    mass: float
    rotary_inertia: float = 0.0
    polar_inertia: float = 0.0

    def __post_init__(self) -> None:
        _number(self, "position", minimum=0.0)
        _number(self, "mass", minimum=0.0)
        _number(self, "rotary_inertia", minimum=0.0)
        _number(self, "polar_inertia", minimum=0.0)

    def apply(self, matrices, mesh):
        node = mesh.node_at(self.position, "point mass")
        M = matrices.M.copy()
        values = {"x": self.mass, "y": self.mass, "z": self.mass,
                  "rx": self.rotary_inertia, "ry": self.rotary_inertia, "rz": self.polar_inertia}
        for d in mesh.directions:
            i = mesh.dof(node, d)
            M[i, i] += values[d]
        return dataclasses.replace(matrices, M=M)


@dataclass(frozen=True)
class RayleighDamping(Ingredient):
    """Proportional viscous damping ``C += α M + β K``.

    Parameters
    ----------
    alpha
        Mass-proportional factor α [1/s], >= 0.
    beta
        Stiffness-proportional factor β [s], >= 0.
    """

    alpha: float = 0.0
    beta: float = 0.0
    stage = 1

    def __post_init__(self) -> None:
        _number(self, "alpha", minimum=0.0)
        _number(self, "beta", minimum=0.0)

    def apply(self, matrices, mesh):
        return dataclasses.replace(matrices, C=matrices.C + self.alpha * matrices.M + self.beta * matrices.K)


@dataclass(frozen=True)
class HystereticDamping(Ingredient):
    """Structural (hysteretic) damping: stiffness ``K → K (1 + iη)``.

    The loss is frequency independent: a mode's loss factor is η whatever its
    frequency. Stored as ``K_loss += η K``.

    Parameters
    ----------
    eta
        Loss factor η (dimensionless), >= 0.
    """

    eta: float
    stage = 1

    def __post_init__(self) -> None:
        _number(self, "eta", minimum=0.0)

    def apply(self, matrices, mesh):
        return dataclasses.replace(matrices, K_loss=matrices.K_loss + self.eta * matrices.K)


@dataclass(frozen=True)
class ModalDamping(Ingredient):
    """Modal viscous damping ratios ζ.

    Parameters
    ----------
    zeta
        One ratio (dimensionless, >= 0) for every elastic mode, or a tuple for the first
        elastic modes in order (the last value applies to all higher modes).

    Notes
    -----
    Realised as the viscous matrix ``C += M Φ diag(2 ζ_r ω_r) Φᵀ M`` over all
    modes of the constrained model (mass-normalised Φ), so the direct solution
    and modal superposition see the same damping; rigid-body modes get none.
    Applied after the structural ingredients so that it uses their modes.
    """

    zeta: float | tuple[float, ...]
    stage = 2

    def __post_init__(self) -> None:
        z = self.zeta
        values = (z,) if not isinstance(z, (tuple, list)) else tuple(z)
        if not values:
            raise FieldError("zeta", "needs at least one damping ratio")
        clean = []
        for i, v in enumerate(values):
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0:
                name = "zeta" if len(values) == 1 else f"zeta[{i}]"
                raise FieldError(name, f"must be a number >= 0, got {v!r}")
            clean.append(float(v))
        object.__setattr__(self, "zeta", clean[0] if not isinstance(z, (tuple, list)) else tuple(clean))

    def ratios(self, n: int) -> np.ndarray:
        """Damping ratios of the first ``n`` elastic modes.

        Parameters
        ----------
        n
            Number of elastic modes.

        Returns
        -------
        ndarray, shape (n,)
        """
        values = np.atleast_1d(np.asarray(self.zeta, dtype=float))
        out = np.full(n, values[-1])
        m = min(n, values.size)
        out[:m] = values[:m]
        return out

    def apply(self, matrices, mesh):
        free = ~matrices.fixed
        lam, phi, n_rb = eigen_free(matrices, None)
        omega = np.sqrt(np.clip(lam, 0.0, None))
        omega[:n_rb] = 0.0
        zeta = np.zeros_like(omega)
        zeta[n_rb:] = self.ratios(omega.size - n_rb)
        Mf = free_block(matrices.M, matrices.fixed)
        mp = Mf @ phi
        Cf = (mp * (2.0 * zeta * omega)) @ mp.T
        C = matrices.C.copy()
        C[np.ix_(free, free)] += 0.5 * (Cf + Cf.T)
        # K and M are unchanged: keep their eigen-solution for the spectral FRF synthesis
        lam.flags.writeable = phi.flags.writeable = False  # shared with every later user
        eigen = (matrices.K, matrices.M, matrices.fixed, lam, phi, n_rb)
        return dataclasses.replace(matrices, C=C, eigen_solution=eigen)
