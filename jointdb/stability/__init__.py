"""Chatter stability lobes: turning, milling ZOA and milling semi-discretization (numpy/scipy only).

Public API
----------
``turning_lobes(frf, kf, orientation=None, spindle_speed_rpm=None, max_lobes=30) -> LobeResult``
``tlusty_limit(frf, kf, orientation=None) -> (depth_m, chatter_freq_hz)``
``oriented_frf(frf, orientation=None) -> ndarray``
``MillingCut(n_teeth, kt, kr, radial_immersion=1.0, down_milling=True)``  (kt, kr in N/m²)
``milling_lobes_zoa(frf, cut, frf_y=None, *, cross_terms=False, spindle_speed_rpm=None, max_lobes=30) -> LobeResult``
``milling_lobes_sd(model, cut, spindle_speed_rpm, *, n_intervals=40, rtol=1e-4, depth_max=None) -> LobeResult``
``milling_lobes_sd_grid(model, cut, speeds, depths, *, n_intervals=40)`` (dense-grid reference)
``sd_system``, ``monodromy``, ``spectral_radius``, ``critical_depth`` (SD building blocks)
``refine_lobes(compute, speeds, *, rounds=3) -> LobeResult`` (adaptive speeds near the envelope's turning points;
equal to the plain computation at the shared speeds), ``plottable_depth(result)`` (folds and non-finite as NaN)
``simulate_milling(model, cut, speeds, depths, *, feed_per_tooth_m, revolutions, steps_per_tooth, runout_m)
-> [SimulationResult]`` (time domain: tool leaving the cut, runout, once-per-period chatter statistic)
``LobeResult`` (frozen: spindle_speed_rpm, depth_m, chatter_freq_hz, lobe, kind, lobes, info;
``.table()``, ``.min_depth_m``), ``Lobe``, ``mean_directional_matrix``, ``tool_tip_matrix``.
"""

from jointdb.stability._adaptive import merge_lobe_results, plottable_depth, refine_lobes
from jointdb.stability._cutting import MillingCut, interval_directional_matrices, mean_directional_matrix
from jointdb.stability._frequency import milling_lobes_zoa, oriented_frf, tlusty_limit, tool_tip_matrix, turning_lobes
from jointdb.stability._results import Lobe, LobeResult, envelope, lobes_from_transfer
from jointdb.stability._timedomain import CHATTER_THRESHOLD, SUSTAINED_GROWTH, SimulationResult, simulate_milling
from jointdb.stability._sd import (
    critical_depth,
    milling_lobes_sd,
    milling_lobes_sd_grid,
    monodromy,
    sd_system,
    spectral_radius,
)

__all__ = [
    "CHATTER_THRESHOLD",
    "SUSTAINED_GROWTH",
    "SimulationResult",
    "simulate_milling",
    "Lobe",
    "LobeResult",
    "MillingCut",
    "critical_depth",
    "envelope",
    "interval_directional_matrices",
    "lobes_from_transfer",
    "mean_directional_matrix",
    "merge_lobe_results",
    "milling_lobes_sd",
    "milling_lobes_sd_grid",
    "milling_lobes_zoa",
    "monodromy",
    "oriented_frf",
    "plottable_depth",
    "refine_lobes",
    "sd_system",
    "spectral_radius",
    "tlusty_limit",
    "tool_tip_matrix",
    "turning_lobes",
]
