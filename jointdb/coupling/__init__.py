"""Receptance coupling (RC) and joint identification (IRC).

Forward coupling (docs/theory.md §1):

- :func:`couple` — LM-FBS with rigid, massless (``H_J(ω)``) or inertial joints,
  any number of substructures and interfaces, only the requested outputs.
- :class:`Interface`, :class:`JointSubstructure` — interface descriptions.
- :func:`spring_damper_joint` — diagonal receptance ``1/(k + iωc)``.

Identification (IRC, docs/theory.md §2), each returning an :class:`IdentificationResult`
(joint FRF + residual, condition number per line, flags):

- :func:`identify_planar_joint` — planar spring–damper from two translational FRFs (§2a).
- :func:`identify_n_point_joints` — n translational joints between two bodies (§2b).
- :func:`identify_joint_matrix` — full joint matrix with inertia (§2c).
- :class:`Regularisation` — truncated-SVD / Tikhonov pseudo-inverses.
- :func:`equivalent_stiffness_damping`, :func:`fit_constant_kc` — k(ω), c(ω), constant (k, c)
  (a :class:`KCFit`).

Output-error identification (all lines at once, weighted by the measurement's
uncertainty, started from the IRC estimate; parameters with standard errors and
correlation, an :class:`OutputErrorResult`): :func:`fit_planar_joint`,
:func:`fit_n_point_joints`, :func:`fit_joint_matrix`; weights from
:func:`sigma_from_coherence` or :func:`mean_and_sigma_of_repeats`.

Rotational receptances at a contact point (docs/theory.md §3):
:func:`rotations_by_extension`, :func:`rotations_by_finite_difference`.

Labels: outputs/inputs are
``(substructure name, Dof)`` pairs and the result FRF is labelled with the bare
Dofs, so requested DOF labels must be distinct across substructures. A joint
given as an FRF is matched to the interface by its labels when they equal the
``a_dofs`` or ``b_dofs``; otherwise it is taken in ``a_dofs`` order.
"""

from jointdb.coupling.irc import (
    IdentificationResult,
    KCFit,
    Regularisation,
    equivalent_stiffness_damping,
    fit_constant_kc,
    identify_joint_matrix,
    identify_n_point_joints,
    identify_planar_joint,
)
from jointdb.coupling._output_error import (
    OutputErrorResult,
    fit_joint_matrix,
    fit_n_point_joints,
    fit_planar_joint,
    mean_and_sigma_of_repeats,
    sigma_from_coherence,
)
from jointdb.coupling.rc import Interface, JointSubstructure, couple, spring_damper_joint
from jointdb.coupling.rotational import rotations_by_extension, rotations_by_finite_difference

from jointdb.coupling import _output_error, irc, rc, rotational

#: The public names: those of the submodules, forward coupling first.
__all__: list[str] = []
__all__ += rc.__all__
__all__ += irc.__all__
__all__ += _output_error.__all__
__all__ += rotational.__all__
