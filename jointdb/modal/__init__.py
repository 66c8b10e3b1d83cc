"""Modal parameter estimation and modal models (numpy/scipy only).

Public API
----------
``fit_modes(frf, n_modes=None, band=None, *, max_order=30, residuals=True,
criteria=StabilisationCriteria(), min_count=3) -> ModalFit``
    pLSCF (PolyMAX) poles over model orders 1..max_order, a stabilisation
    diagram, automatic pole selection, LSFD residues with upper/lower residuals
    and quality (NMSE, FRAC per entry).
``ModalModel(freq_hz, zeta, residues, outputs, inputs, upper=None, lower=None)``
    ``.synthesize(freq, quantity)`` -> FRF, ``.poles``, ``.state_space()``,
    ``.modal_mass_stiffness(dof)``, ``.select()``, ``ModalModel.from_modal_parameters``,
    ``ModalModel.block_diagonal([mx, my])``.
``fit_tool_tip(frf, frf_y=None, n_modes=None, band=None, *, max_order=30) -> (ModalModel, fits)``
    x/y driving points fitted separately, combined block-diagonally (input to
    ``jointdb.stability.milling_lobes_sd``).
``stabilisation_diagram``, ``select_poles``, ``fit_residues``, ``fit_quality``,
``StabilisationCriteria``, ``StabilisationDiagram``, ``FitQuality``, ``ModalFit``,
``single_dof_residue``.

Deviation from api-contracts.md: ``ModalFit`` carries the model in ``.model``
(with ``.freq_hz``, ``.zeta``, ``.residues`` shortcuts) and the quality in ``.quality``.
"""

from jointdb.modal._lscf import (
    StabilisationCriteria,
    StabilisationDiagram,
    lscf_poles,
    select_poles,
    stabilisation_diagram,
)
from jointdb.modal._lsfd import FitQuality, ModalFit, fit_modes, fit_quality, fit_residues
from jointdb.modal._model import ModalModel, single_dof_residue
from jointdb.modal._tooltip import fit_tool_tip

__all__ = [
    "FitQuality",
    "ModalFit",
    "ModalModel",
    "StabilisationCriteria",
    "StabilisationDiagram",
    "fit_modes",
    "fit_quality",
    "fit_residues",
    "fit_tool_tip",
    "lscf_poles",
    "select_poles",
    "single_dof_residue",
    "stabilisation_diagram",
]
