"""Figures (PNG, matplotlib's Agg backend): FRFs, joints, tool-tip predictions, lobes, diagnoses.

matplotlib is imported on the first figure drawn, not by ``import jointdb.plots``; every
``save_*`` / ``plot_*`` function writes its file atomically and returns its path.

FRFs
----
- :func:`bode_figure` — magnitude (log) and phase of FRF entries, as a matplotlib figure.
- :func:`nyquist_figure` — real against imaginary part of FRF entries.
- :func:`save_bode`, :func:`save_nyquist` — the same, written to a PNG file.
- :func:`save_figure` — write any figure atomically and close it.

Joints and coupling
-------------------
- :func:`save_kc_plot` — equivalent stiffness k(ω) and damping c(ω) of a joint FRF.
- :func:`comparison_figure`, :func:`save_comparison_plot` — several FRFs of the same entries (measured,
  coupled, rigid), the phase unwrapped on the first one's branch.

Tool-tip prediction
-------------------
- :func:`tip_comparison_figure`, :func:`save_tip_comparison` — predicted tool-tip FRF in µm/N with its
  band; rigid joints in a panel of their own, with :func:`rigid_reason`.
- :func:`joint_choice_figure`, :func:`save_joint_distances` — distances of the candidate joints of each
  queried interface on one scale, the joints used, the request.
- :func:`joints_legend` — legend text naming the joints a prediction used.

Stability and modal fits
------------------------
- :func:`lobes_figure`, :func:`plot_lobes` — stability lobes (stable region shaded, band).
- :func:`plot_stabilisation` — stabilisation diagram of a modal fit.
- :func:`plot_modal_fit` — measured FRF entries against the re-synthesised modal model.

Diagnosis
---------
- :func:`plot_diagnosis` — the figures of a :class:`jointdb.diagnose.Diagnosis`.
- :func:`plot_backbone` — modal frequency and damping against response amplitude per level.

Axis helpers
------------
- :func:`phase_deg` — phase in degrees, the line broken where it wraps.
- :func:`phase_unwrapped` — phase in degrees, continuous, on a reference curve's branch.
- :func:`robust_limits` — axis limits from percentiles (single spikes do not set the scale).
"""

from jointdb.plots._axes import phase_deg, phase_unwrapped, robust_limits
from jointdb.plots._coupling import comparison_figure, save_comparison_plot, save_kc_plot
from jointdb.plots._diagnose import plot_backbone, plot_diagnosis
from jointdb.plots._frf import bode_figure, nyquist_figure, save_bode, save_figure, save_nyquist
from jointdb.plots._lobes import lobes_figure, plot_lobes, plot_modal_fit, plot_stabilisation
from jointdb.plots._stack import (
    joint_choice_figure,
    joints_legend,
    rigid_reason,
    save_joint_distances,
    save_tip_comparison,
    tip_comparison_figure,
)

__all__ = [
    "bode_figure",
    "nyquist_figure",
    "save_bode",
    "save_nyquist",
    "save_figure",
    "save_kc_plot",
    "save_comparison_plot",
    "comparison_figure",
    "save_tip_comparison",
    "tip_comparison_figure",
    "rigid_reason",
    "save_joint_distances",
    "joint_choice_figure",
    "joints_legend",
    "lobes_figure",
    "plot_lobes",
    "plot_stabilisation",
    "plot_modal_fit",
    "plot_diagnosis",
    "plot_backbone",
    "phase_deg",
    "phase_unwrapped",
    "robust_limits",
]
