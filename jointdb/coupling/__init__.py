"""Receptance coupling (RC) and joint identification (IRC).

Forward coupling (theory.md §1):

- :func:`couple` — LM-FBS with rigid, massless (``H_J(ω)``) or inertial joints,
  any number of substructures and interfaces, only the requested outputs.
- :class:`Interface`, :class:`JointSubstructure` — interface descriptions.
- :func:`spring_damper_joint` — diagonal receptance ``1/(k + iωc)``.

Notes on the contract (api-contracts.md): outputs/inputs are
``(substructure name, Dof)`` pairs and the result FRF is labelled with the bare
Dofs, so requested DOF labels must be distinct across substructures. A joint
given as an FRF is matched to the interface by its labels when they equal the
``a_dofs`` or ``b_dofs``; otherwise it is taken in ``a_dofs`` order.
"""

from jointdb.coupling._common import IdentificationResult
from jointdb.coupling._linalg import Regularisation
from jointdb.coupling.irc import identify_planar_joint
from jointdb.coupling.rc import Interface, JointSubstructure, couple, spring_damper_joint

__all__ = [
    "Interface",
    "JointSubstructure",
    "couple",
    "spring_damper_joint",
    "IdentificationResult",
    "Regularisation",
    "identify_planar_joint",
]
