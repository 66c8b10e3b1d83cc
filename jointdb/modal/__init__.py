"""Modal parameter estimation and modal models (numpy/scipy only).

Fitting
-------
   fit_modes               -- pLSCF poles, stabilisation diagram, automatic selection, LSFD residues
   fit_tool_tip            -- x and y tool-tip driving points fitted separately, combined block-diagonally
   ModalFit                -- result of :func:`fit_modes`: model, stabilisation diagram, quality

Building blocks
---------------
   lscf_poles              -- poles and participation vectors of one pLSCF model order
   stabilisation_diagram   -- pLSCF poles over model orders and their stability status
   StabilisationDiagram    -- all physical poles per model order, with their status
   StabilisationCriteria   -- tolerances for calling a pole stable between orders
   select_poles            -- cluster the stable poles by frequency, keep the best clusters
   fit_residues            -- LSFD residues and residual terms for fixed poles
   fit_quality             -- NMSE and FRAC per entry of two FRF arrays
   FitQuality              -- how well a modal model reproduces the FRF it was fitted to

Modal models
------------
   ModalModel              -- poles and residues on labelled DOFs; ``.synthesize(freq)`` -> FRF
   single_dof_residue      -- residue of a driving-point mode of given stiffness and damping

``fit_tool_tip`` gives the input of :func:`jointdb.stability.milling_lobes_sd`.
``ModalFit`` carries the model in ``.model`` (with ``.freq_hz``, ``.zeta``, ``.residues``
shortcuts) and the quality in ``.quality``.
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
