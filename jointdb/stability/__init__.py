"""Chatter stability lobes: turning, milling ZOA and milling semi-discretization (numpy/scipy only).

Depths are in metres, spindle speeds in rpm, chatter frequencies in Hz, cutting
coefficients in N/m² (docs/theory.md §5).

Lobes
-----
   turning_lobes                 -- turning lobes (Tlusty) from a tool-tip FRF
   tlusty_limit                  -- absolute (speed-independent) turning limit
   milling_lobes_zoa             -- milling lobes by the zero-order approximation (Altintas & Budak)
   milling_lobes_sd              -- milling lobes by semi-discretization on a modal model
   milling_lobes_sd_grid         -- SD reference on a dense (speed × depth) grid
   refine_lobes                  -- adaptive speeds near the envelope's turning points
   MillingCut                    -- teeth, cutting coefficients, immersion, up/down milling

Results
-------
   LobeResult                    -- limiting depth over spindle speed (the envelope) and its lobes
   Lobe                          -- one lobe curve: depth and chatter frequency against speed
   envelope                      -- lowest lobe at each spindle speed
   merge_lobe_results            -- rows of two results of the same computation, sorted by speed
   plottable_depth               -- limiting depth with folds and non-finite values as NaN

Building blocks
---------------
   oriented_frf                  -- oriented receptance ``Σ μ_ij H_ij(ω)``
   tool_tip_matrix               -- tool-tip receptance matrix Φ (n_freq, 2, 2) in (x, y)
   lobes_from_transfer           -- lobes from an oriented transfer function ``g(ω)``
   mean_directional_matrix       -- tooth-period mean of the directional matrix (ZOA)
   interval_directional_matrices -- averages of the directional matrix over SD sub-intervals
   sd_system                     -- the SD system of a tool-tip modal model
   monodromy                     -- Floquet transition matrix over one tooth period
   spectral_radius               -- largest |Floquet multiplier| (stable when < 1)
   critical_depth                -- smallest depth with spectral radius 1 at one speed

Time domain
-----------
   simulate_milling              -- regenerative milling of a tip modal model in time: tool leaving the cut,
                                    runout, once-per-period chatter statistic, forces, SLE
   SimulationResult              -- one simulated cut (chatter verdict, chatter frequency, forces, vibration)
   CHATTER_THRESHOLD             -- the sampling statistic above which a cut is called chatter
   SUSTAINED_GROWTH              -- growth of the sampled vibration that marks chatter
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
