"""The assembled system of a beam model: its matrices and its natural modes.

What assembly produces and synthesis consumes; below both, so the model, its
ingredients and the FRF synthesis all read it without importing each other.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from jointdb.frf import Dof

__all__ = ["FEMatrices", "Modes", "free_block"]


@dataclass(frozen=True, eq=False)
class FEMatrices:
    """Assembled matrices over all mesh DOFs (SI).

    The dynamic stiffness is ``K + i K_loss + iωC − ω²M``.

    Attributes
    ----------
    K
        Stiffness ``(n_dof, n_dof)`` [N/m, N, N·m/rad].
    M
        Mass ``(n_dof, n_dof)`` [kg, kg·m²].
    C
        Viscous damping ``(n_dof, n_dof)`` [N·s/m, ...].
    K_loss
        Hysteretic part of the stiffness ``(n_dof, n_dof)``.
    dof_labels
        ``Dof(mesh node index, direction)`` of each DOF.
    node_positions
        Axial node positions [m], ``(n_nodes,)``.
    fixed
        Bool ``(n_dof,)``: the constrained DOFs.
    eigen_solution
        The eigen-solution of the constrained (K, M) problem when an ingredient already
        computed it (modal damping does); reused only while K, M and ``fixed`` are unchanged.
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

    Attributes
    ----------
    freq_hz
        Natural frequencies [Hz], ascending, ``(n,)``.
    shapes
        Mass-normalised mode shapes, ``(n_dof, n)``.
    dof_labels
        ``Dof`` of each row of ``shapes``.
    n_rigid
        How many of the modes are rigid-body modes (the first ones).
    """

    freq_hz: np.ndarray
    shapes: np.ndarray
    dof_labels: tuple[Dof, ...]
    n_rigid: int = 0


def free_block(a: np.ndarray, fixed: np.ndarray) -> np.ndarray:
    """``a[np.ix_(free, free)]`` over the free DOFs (``free = ~fixed``), by two ``take`` s (the same
    values, a few times cheaper than the 2-D fancy index for these sizes).

    Parameters
    ----------
    a
        A matrix over all DOFs, ``(n_dof, n_dof)``.
    fixed
        Boolean mask of the fixed DOFs, ``(n_dof,)``.

    Returns
    -------
    ndarray, ``(n_free, n_free)``
    """
    idx = np.flatnonzero(~fixed)
    return a.take(idx, axis=0).take(idx, axis=1)
