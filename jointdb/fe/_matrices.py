"""The assembled system of a beam model: its matrices and its natural modes.

What assembly produces and synthesis consumes; below both, so the model, its
ingredients and the FRF synthesis all read it without importing each other.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from jointdb.frf import Dof

__all__ = ["FEMatrices", "Modes"]


@dataclass(frozen=True, eq=False)
class FEMatrices:
    """Assembled matrices over all mesh DOFs (SI).

    ``K`` stiffness, ``M`` mass, ``C`` viscous damping, ``K_loss`` the
    hysteretic part (dynamic stiffness ``K + i K_loss + iωC − ω²M``), all
    ``(n_dof, n_dof)``; ``fixed`` marks constrained DOFs; ``dof_labels`` are
    ``Dof(mesh node index, direction)``; ``node_positions`` in metres.
    """

    K: np.ndarray
    M: np.ndarray
    C: np.ndarray
    K_loss: np.ndarray
    dof_labels: tuple[Dof, ...]
    node_positions: np.ndarray
    fixed: np.ndarray
    #: the full eigen-solution of the constrained (K, M) problem when an ingredient already
    #: computed it (modal damping does), with the arrays it belongs to; reused only while
    #: ``K``, ``M`` and ``fixed`` are those very arrays (see ``jointdb.fe._synthesis.eigen_free``)
    eigen_solution: tuple | None = field(default=None, repr=False)

    @property
    def free(self) -> np.ndarray:
        return ~self.fixed


@dataclass(frozen=True, eq=False)
class Modes:
    """Undamped natural frequencies [Hz] ``(n,)`` and mass-normalised shapes ``(n_dof, n)``.

    Rigid-body modes have frequency 0 exactly; shapes are zero on fixed DOFs.
    """

    freq_hz: np.ndarray
    shapes: np.ndarray
    dof_labels: tuple[Dof, ...]
    n_rigid: int = 0
