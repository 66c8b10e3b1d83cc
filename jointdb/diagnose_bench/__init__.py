"""Concealed-effect benchmark generator for :mod:`jointdb.diagnose`.

Produces "recordings" from a richer, independently written truth model
(:mod:`jointdb.diagnose_bench._truth_fe`: fine Timoshenko mesh, distributed
contact bed over the insertion length, finite-size sensor, fluted section with
its own area and inertia, hysteretic or amplitude-dependent joint, Bessel
anti-alias filter, calibration gain, bin-averaged lines, seeded noise) together
with the nominal jointdb.fe model that is diagnosed. It shares no code with
:mod:`jointdb.diagnose` that injects an effect.

>>> from jointdb.diagnose_bench import generate_case
>>> case = generate_case("sensor_mass", seed=3)
>>> case.model["segments"][0]["length"], case.recordings[0].frf.shape  # doctest: +SKIP
"""

from jointdb.diagnose_bench._blas import single_blas_thread
from jointdb.diagnose_bench._cases import EFFECTS, BenchCase, Recording, generate_case, generate_suite
from jointdb.diagnose_bench._run import BenchResult, CaseResult, run_benchmark, run_case

__all__ = ["EFFECTS", "BenchCase", "Recording", "generate_case", "generate_suite",
           "BenchResult", "CaseResult", "run_benchmark", "run_case", "single_blas_thread"]
