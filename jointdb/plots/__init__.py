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
- :func:`save_comparison_plot` — several FRFs of the same entries (measured, coupled, rigid).

Tool-tip prediction
-------------------
- :func:`save_tip_comparison` — predicted tool-tip FRF with catalogued joints against rigid joints.
- :func:`save_joint_distances` — distances of the candidate joints of each queried interface.
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
- :func:`robust_limits` — axis limits from percentiles (single spikes do not set the scale).
"""

from jointdb.plots._axes import phase_deg, robust_limits
from jointdb.plots._coupling import save_comparison_plot, save_kc_plot
from jointdb.plots._diagnose import plot_backbone, plot_diagnosis
from jointdb.plots._frf import bode_figure, nyquist_figure, save_bode, save_figure, save_nyquist
from jointdb.plots._lobes import lobes_figure, plot_lobes, plot_modal_fit, plot_stabilisation
from jointdb.plots._stack import joints_legend, save_joint_distances, save_tip_comparison

__all__ = [
    "bode_figure",
    "nyquist_figure",
    "save_bode",
    "save_nyquist",
    "save_figure",
    "save_kc_plot",
    "save_comparison_plot",
    "save_tip_comparison",
    "save_joint_distances",
    "joints_legend",
    "lobes_figure",
    "plot_lobes",
    "plot_stabilisation",
    "plot_modal_fit",
    "plot_diagnosis",
    "plot_backbone",
    "phase_deg",
    "robust_limits",
]
