"""The candidates evaluated on a Dask local cluster give exactly the in-process results."""

from pathlib import Path

import numpy as np
import pytest

from jointdb.usecases._demo import run_main_job
from jointdb.store import Repository
from jointdb.usecases._optimize import enumerate_candidates, load_problem
from jointdb.usecases._optimize_eval import evaluate_candidates

pytest.importorskip("distributed")

SPEC = Path(__file__).resolve().parents[2] / "fixtures" / "optimize" / "optimize-spec.json"


def test_local_cluster_equals_in_process(tmp_path):
    run_main_job(tmp_path / "out", f"sqlite:///{tmp_path / 'joints.sqlite'}", say=lambda _: None, n_speeds=40)
    repo = Repository(f"sqlite:///{tmp_path / 'joints.sqlite'}")
    try:
        problem = load_problem(SPEC)
        cands = enumerate_candidates(problem, repo)
        seen = []
        here = evaluate_candidates(problem, cands, repo)
        there = evaluate_candidates(problem, cands, repo, lambda d, t, m: seen.append((d, t)), scheduler="local",
                                    n_workers=2, chunk_size=9)  # four tasks
    finally:
        repo.close()
    assert len(seen) == 4 and seen[-1] == (36, 36)
    for a, b in zip(here, there):
        assert a.candidate == b.candidate and a.best == b.best and a.joints == b.joints
        assert np.array_equal(a.lobes.depth_m, b.lobes.depth_m, equal_nan=True)
