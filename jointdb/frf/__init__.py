"""FRF container, DOF labels and exact quantity conversions.

Contract: frequencies in Hz, float64, strictly
increasing; values complex128 of shape ``(n_freq, n_out, n_in)``; outputs and
inputs labelled by :class:`Dof` ``(node, direction)`` with the UFF58 direction
codes ``x y z rx ry rz`` (1..6); the quantity (receptance, mobility,
accelerance) is explicit and converted exactly.

Harmonic convention ``x(t) = X exp(+iωt)`` (docs/theory.md §0), so mobility
``Y = iω H`` and accelerance ``A = −ω² H``.

Labels and quantities
---------------------
DIRECTIONS           -- direction names in UFF58 order (codes 1..6)
Dof                  -- a degree of freedom: node number and direction
dofs                 -- parse an iterable of DOF labels
Quantity             -- receptance, mobility or accelerance

The container
-------------
FRF                  -- values ``(n_freq, n_out, n_in)`` on labelled DOFs, exact conversions
reciprocal_index     -- where a block sits in an FRF's values, directly or by reciprocity
"""

from jointdb.frf._container import FRF
from jointdb.frf._indexing import reciprocal_index
from jointdb.frf._labels import DIRECTIONS, Dof, Quantity, dofs

__all__ = ["DIRECTIONS", "Dof", "Quantity", "FRF", "dofs", "reciprocal_index"]
