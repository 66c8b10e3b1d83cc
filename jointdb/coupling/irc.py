"""Inverse receptance coupling (IRC): joint identification (docs/theory.md §2).

The three joint models live in private modules split along their seams:
planar spring–damper (§2a, ``_planar``), n translational joints (§2b,
``_multi``) and the full joint matrix with inertia (§2c, ``_matrix``); the equivalent
stiffness/damping helpers are in ``_kc``.
"""

from jointdb.coupling._common import IdentificationResult
from jointdb.coupling._kc import KCFit, equivalent_stiffness_damping, fit_constant_kc
from jointdb.coupling._linalg import Regularisation
from jointdb.coupling._matrix import identify_joint_matrix
from jointdb.coupling._multi import identify_n_point_joints
from jointdb.coupling._planar import identify_planar_joint

__all__ = [
    "IdentificationResult",
    "Regularisation",
    "identify_planar_joint",
    "identify_n_point_joints",
    "identify_joint_matrix",
    "equivalent_stiffness_damping",
    "fit_constant_kc",
    "KCFit",
]
