"""Helpers of the optimize tests."""


def fast_equals_brute_force(problem, cands, repo) -> list:
    """Evaluate ``cands`` on the fast path and by brute force (``predict_stack`` + ``stability_lobes`` per
    candidate); assert tips, lobes, best cuts, joints and ranking equal to the last digit; return the fast
    results."""
    import numpy as np

    from jointdb.usecases._optimize import evaluate_brute_force, rank
    from jointdb.usecases._optimize_eval import evaluate_candidates

    fast = evaluate_candidates(problem, cands, repo, keep_tips=True)
    slow = evaluate_brute_force(problem, cands, repo)
    for a, b in zip(fast, slow, strict=True):
        assert np.array_equal(a.tip.values, b.tip.values)
        assert np.array_equal(a.lobes.depth_m, b.lobes.depth_m, equal_nan=True)
        assert a.best == b.best and a.joints == b.joints
    assert [r.candidate for r in rank(fast)] == [r.candidate for r in rank(slow)]
    return fast
