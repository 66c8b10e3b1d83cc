"""Diagnose: when a simulated FRF and a recording disagree, locate the mismatch,
name the physics the model left out, add it, refit, and show the fit improve.

Pipeline (see ``docs/validation/diagnose-bench.md`` for the proof on concealed
effects):

1. :func:`prepare` maps recorded DOFs to model points, checks the common band
   and the coherence, and thins the lines (all lines near peaks, a log-spaced
   background).
2. :func:`signature` compares: overall / per-band mismatch, magnitude [dB]
   and phase [deg] errors, FRAC, peak picking and mode pairing, the shift
   pattern across modes, damping and height ratios, a constant offset, a
   phase drift ∝ frequency, extra/missing peaks, level dependence.
3. Every candidate of the physics library (:mod:`jointdb.diagnose.physics`)
   and pairs of the best ones are fitted (``scipy.optimize.least_squares`` on
   the weighted complex log-FRF residual) and ranked by BIC
   (``n ln(RSS/n) + p ln n``). An explanation is accepted only if it lowers the
   BIC by ``BIC_MARGIN`` *and* cuts the mismatch by ``MIN_IMPROVEMENT`` ×
   (the false-alarm threshold); otherwise the verdict says nothing is added.
   A pair (second effect) must in addition beat the best single explanation
   by ``MIN_PAIR_IMPROVEMENT`` × in mismatch and by ``BIC_MARGIN`` per residual
   correlation length, so no surrogate second effect is invented.
4. Uncertainty of the selected explanation: statistical (``χ²_red · τ ·
   (JᵀJ)⁻¹``, τ = correlation length of the residual in lines) combined with a
   model-form spread (delete-one-block jackknife over frequency); both parts
   are reported (``Fit.sigmas_stat``, ``Fit.sigmas_model``).

Mismatch = weighted RMS of ``|log(H_model/H_recorded)|`` (≈ relative error;
weights from coherence with a 2 % model floor).

Entry point
-----------
   diagnose             -- locate the mismatch and explain it with candidate physics (example there)
   Diagnosis            -- its result: signature, ranked fits, verdict, augmented model
   Measurement          -- one recorded FRF set, with coherence and excitation level

Comparison
----------
   prepare              -- map, check and thin the recordings for diagnosis
   Observation          -- recordings aligned with the model on the fit lines
   signature            -- locate and characterise the mismatch
   Signature            -- overall / per-band mismatch, peak pairs, shift pattern
   find_peaks           -- resonance peaks of an FRF set ``(n_freq, n_out, n_in)``
   pair_modes           -- pair model and recorded peaks by log-frequency distance
   Peak, ModePair       -- one peak; one paired mode

Fitting candidates
------------------
   fit_candidate        -- fit one candidate's parameters (bounded least squares) and score it
   jackknife_spread     -- model-form spread of a fit (delete-one-block jackknife)
   Fit                  -- a fitted candidate: values, sigmas, BIC, mismatch
   ModelEvaluator       -- model FRFs at the observation's lines and DOFs
   BIC_MARGIN, MIN_IMPROVEMENT, MIN_PAIR_IMPROVEMENT -- the acceptance thresholds

Physics library
---------------
   Candidate            -- base class of one candidate physics
   Param                -- a fitted parameter: SI unit, bounds, start
   Context              -- what candidates need: nominal model, measured points, levels
   register             -- decorator adding a candidate factory
   candidates_for       -- all candidates the registered factories offer

Excitation levels
-----------------
   track_modes          -- follow each recorded mode across excitation levels
   LevelAnalysis        -- modes tracked across levels
   ModeTrack            -- one mode followed across levels
   local_modal_fit      -- one mode fitted in a band around a recorded resonance
   ModalFit             -- one local modal fit
"""

from jointdb.diagnose._compare import ModePair, Peak, Signature, find_peaks, pair_modes, signature
from jointdb.diagnose._data import Measurement, Observation, prepare
from jointdb.diagnose._diagnose import BIC_MARGIN, MIN_IMPROVEMENT, MIN_PAIR_IMPROVEMENT, Diagnosis, diagnose
from jointdb.diagnose._fit import Fit, ModelEvaluator, fit_candidate
from jointdb.diagnose._uncertainty import jackknife_spread
from jointdb.diagnose._levels import LevelAnalysis, ModeTrack, track_modes
from jointdb.diagnose._modalfit import ModalFit, local_modal_fit
from jointdb.diagnose.physics import Candidate, Context, Param, candidates_for, register

__all__ = [
    "diagnose", "Diagnosis", "Measurement", "Observation", "prepare",
    "signature", "Signature", "ModePair", "Peak", "find_peaks", "pair_modes",
    "Fit", "ModelEvaluator", "fit_candidate", "jackknife_spread",
    "Candidate", "Param", "Context", "register", "candidates_for",
    "BIC_MARGIN", "MIN_IMPROVEMENT", "MIN_PAIR_IMPROVEMENT",
    "track_modes", "LevelAnalysis", "ModeTrack", "local_modal_fit", "ModalFit",
]
