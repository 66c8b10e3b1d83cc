"""Concealed-effect benchmark generator for :mod:`jointdb.diagnose`.

Produces "recordings" from richer, independently written truth models together
with the nominal jointdb.fe model that is diagnosed. Neither truth shares code
with :mod:`jointdb.fe` or :mod:`jointdb.diagnose`:

- :mod:`._truth_fe` (end mill on one beam): fine Timoshenko mesh, distributed
  contact bed over the insertion length, finite-size sensor, fluted section
  with its own area and inertia, hysteretic or amplitude-dependent joint;
- :mod:`._truth_stack` (effects ``interface_*``): a tool inside a holder bore
  as two concentric beams tied by a lossy (optionally micro-slip, solved by
  harmonic balance) contact layer over the insertion, the holder on its own
  spindle-face springs.

Both go through one measurement chain (:mod:`._measure`: Bessel anti-alias
filter or gain where hidden, bin-averaged lines, seeded noise, coherence).
Seeds below 1000 are for development, from 1000 up for the reported benchmark.

>>> from jointdb.diagnose_bench import generate_case
>>> case = generate_case("sensor_mass", seed=3)
>>> case.model["segments"][0]["length"], case.recordings[0].frf.shape  # doctest: +SKIP
"""

from jointdb.diagnose_bench._blas import single_blas_thread
from jointdb.diagnose_bench._cases import EFFECTS, BenchCase, Recording, generate_case, generate_suite
from jointdb.diagnose_bench._run import (
    REPORTED_SEEDS_START,
    BenchResult,
    CaseResult,
    diagnose_case,
    expected_families,
    run_benchmark,
    run_case,
)
from jointdb.diagnose_bench._stack_cases import STACK_EFFECTS

__all__ = ["EFFECTS", "STACK_EFFECTS", "BenchCase", "Recording", "generate_case", "generate_suite",
           "BenchResult", "CaseResult", "run_benchmark", "run_case", "diagnose_case", "expected_families",
           "REPORTED_SEEDS_START", "single_blas_thread"]
