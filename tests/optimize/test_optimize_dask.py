"""The candidates evaluated on a Dask local cluster give exactly the in-process results — for a spec file
with its stack beside it, and for a spec whose spindle and holders come from the parts catalogue (the
workers load the pinned document: every choice as name@version)."""

from pathlib import Path

import numpy as np
import pytest

from jointdb.usecases._optimize import enumerate_candidates, load_problem
from jointdb.usecases._optimize_eval import evaluate_candidates

pytest.importorskip("distributed")

SPECS = Path(__file__).resolve().parents[2] / "fixtures" / "optimize"


@pytest.mark.parametrize("spec", ["optimize-spec.json", "optimize-catalogue.json"])
def test_local_cluster_equals_in_process(catalogue, spec):
    repo, _ = catalogue
    problem = load_problem(SPECS / spec, repo)
    cands = enumerate_candidates(problem, repo)
    seen = []
    here = evaluate_candidates(problem, cands, repo)
    there = evaluate_candidates(problem, cands, repo, lambda d, t, m: seen.append((d, t)), scheduler="local",
                                n_workers=2, chunk_size=9)  # four tasks
    assert len(seen) == 4 and seen[-1] == (36, 36)
    for a, b in zip(here, there):
        assert a.candidate == b.candidate and a.best == b.best and a.joints == b.joints
        assert np.array_equal(a.lobes.depth_m, b.lobes.depth_m, equal_nan=True)
