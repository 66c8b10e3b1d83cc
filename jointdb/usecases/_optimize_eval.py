"""Evaluate optimize candidates fast, in-process or on Dask (local cluster or a scheduler address).

Substructures are computed once per content (:class:`SubstructureCache`: the spindle once, tool and
holder per (holder, overhang), each joint per (interface, conditions)); the coupling runs over a
leading candidate axis (:func:`jointdb.stack.tool_tip_chain` broadcasts), and the zero-order lobes of
all candidates of a chunk at once (:func:`jointdb.stability._batch.zoa_envelope_batch`). The result
equals :func:`jointdb.usecases._optimize.evaluate_brute_force` to the last digit (tests/optimize).

Scale-out: the candidates are split into chunks (whole (holder, overhang) groups) and each chunk is one
Dask task running :func:`evaluate_chunk` — the very function the in-process path calls — on a worker
that loads the spec (its pinned document: every catalogue choice as ``name@version``) and opens the
database itself (cached per worker process). ``scheduler``:
``None``/``"in-process"``, ``"local"`` (a ``distributed.LocalCluster`` of ``n_workers`` processes, one
thread each) or a scheduler address (``tcp://host:8786``, workers started with ``dask worker`` on hosts
with jointdb installed and the database reachable).
"""

from __future__ import annotations

import functools
from collections.abc import Sequence

import numpy as np

from jointdb.errors import InputError
from jointdb.frf import FRF, Dof, Quantity
from jointdb.usecases._optimize import (
    Candidate,
    CandidateResult,
    OptimizeProblem,
    Progress,
    _joint_names,
    best_cut,
    candidate_stack,
    evaluate_brute_force,
    problem_from_document,
)

INTERFACES = ("tool-holder", "holder-spindle")
#: Candidates per Dask task (whole (holder, overhang) groups are kept together).
CHUNK = 250


def _freeze(mapping) -> tuple:
    return tuple(sorted((k, _freeze(v) if isinstance(v, dict) else tuple(v) if isinstance(v, list) else v)
                        for k, v in dict(mapping).items()))


class SubstructureCache:
    """Substructure receptances computed once per content: the spindle, tool/holder per (holder, overhang),
    each interface's joint per (interface, conditions)."""

    def __init__(self, problem: OptimizeProblem, repo):
        from jointdb.stack import NODES, MeasuredSpindle, prediction_grid, stack_parts
        from jointdb.stack._predict import _planes
        from jointdb.stack._twoplane import spindle_four

        self.problem, self.repo = problem, repo
        tpl = problem.template
        self.freq = prediction_grid(tpl)
        sp = stack_parts(tpl, self.freq)["spindle"]
        node = tpl.spindle.node if isinstance(tpl.spindle, MeasuredSpindle) else NODES["spindle_nose"]
        self.spindle, has_y = _planes(sp, "spindle FRF", node)
        self.coupled_planes = has_y and spindle_four(sp, node) is not None
        self.parts: dict = {}
        self.joints: dict = {}

    def tool_holder(self, spec, cand: Candidate):
        from jointdb.stack import holder_model, tool_model

        key = (cand.holder, cand.overhang_m)
        if key not in self.parts:
            self.parts[key] = (tool_model(spec).frf(self.freq, ["tip", "base"]).values,
                               holder_model(spec).frf(self.freq, ["nose", "base"]).values)
        return self.parts[key]

    def joint(self, spec, name: str):
        """(planes dict or None, resolution) of one interface of ``spec``."""
        from jointdb.stack._predict import _joint_planes
        from jointdb.usecases._stack import resolve_joints

        key = (name, _freeze(spec.interfaces[name].conditions or {}))
        if key not in self.joints:
            for other, res in resolve_joints(spec, self.repo).items():
                okey = (other, _freeze(spec.interfaces[other].conditions or {}))
                planes, _ = _joint_planes(other, spec, {other: res.frf} if res.frf is not None else {}, self.freq)
                self.joints.setdefault(okey, (planes, res))
        return self.joints[key]


def _group_tips(cache: SubstructureCache, group: list, specs: list) -> np.ndarray:
    """Tool-tip receptances (C, F, 2, 2) of candidates sharing tool and holder, coupled over a candidate axis."""
    from jointdb.stack import tool_tip_chain

    tool, holder = cache.tool_holder(specs[0], group[0])
    joints = [[cache.joint(s, n)[0] for n in INTERFACES] for s in specs]
    v = np.zeros((len(group), cache.freq.size, 2, 2), dtype=complex)
    for k, plane in enumerate(("x", "y")):
        stacked = []
        for j in range(2):
            col = [jj[j] for jj in joints]
            if all(c is None for c in col):
                stacked.append(None)
            elif any(c is None for c in col):
                raise InputError("candidates mix rigid and catalogued joints at one interface")
            else:
                stacked.append(np.stack([c[plane] for c in col]))
        tip = tool_tip_chain(tool[None], holder[None], cache.spindle[plane][None], stacked[0], stacked[1])
        v[:, :, k, k] = tip[:, :, 0, 0]
    return v


def _lobe_result(problem: OptimizeProblem, speeds, depth, fc, lobe):
    from jointdb.stability import LobeResult

    cut = problem.cut
    kind = np.where(np.isfinite(depth), "hopf", "")
    return LobeResult("milling-zoa", speeds, depth, fc, lobe, kind, (), {
        "n_teeth": cut.n_teeth, "kt": cut.kt, "kr": cut.kr, "radial_immersion": cut.radial_immersion,
        "down_milling": cut.down_milling, "cross_terms": False})


def evaluate_chunk(problem: OptimizeProblem, candidates: Sequence[Candidate], cache: SubstructureCache,
                   keep_tips: bool = False) -> list[CandidateResult]:
    """Predict every candidate of a chunk (coupling over a candidate axis), then their lobes at once."""
    from jointdb.stack import TIP_NODE
    from jointdb.stability._batch import zoa_envelope_batch

    m = problem.spec.machine
    speeds = np.linspace(m.speed_rpm[0], m.speed_rpm[1], m.n_speeds)
    groups: dict = {}
    for i, c in enumerate(candidates):
        groups.setdefault((c.holder, c.overhang_m), []).append(i)
    order, specs, tips = [], [], []
    for idx in groups.values():
        group = [candidates[i] for i in idx]
        group_specs = [candidate_stack(problem, c) for c in group]
        tips.append(_group_tips(cache, group, group_specs))
        order += idx
        specs += group_specs
    phi = np.concatenate(tips)
    depth, fc, lobe = zoa_envelope_batch(cache.freq, phi, problem.cut, speeds)
    out = (Dof(TIP_NODE, "x"), Dof(TIP_NODE, "y"))
    results: list = [None] * len(candidates)
    for row, (i, spec) in enumerate(zip(order, specs)):
        lobes = _lobe_result(problem, speeds, depth[row], fc[row], lobe[row])
        names = _joint_names({n: cache.joint(spec, n)[1] for n in INTERFACES})
        tip = FRF(cache.freq, phi[row], out, out, Quantity.RECEPTANCE) if keep_tips else None
        results[i] = CandidateResult(candidates[i], lobes, best_cut(problem, lobes), names, tip)
    return results


def _blobs_of(repo) -> str | None:
    """Where ``repo`` keeps its blobs, for a worker to open the same store: a directory, ``"database"``, or
    None (the worker's default)."""
    store = getattr(repo, "blobs", None)
    if type(store).__name__ == "DatabaseBlobStore":  # the frf_blobs table (JOINTDB_BLOBS=database)
        return "database"
    root = getattr(store, "root", None)
    return None if root is None else str(root)


@functools.lru_cache(maxsize=None)
def _worker_repo(db_url: str, blobs: str | None):
    """One open store per database of a worker process, for its life (a spec's state below may be
    evicted; the store it used is not dropped with it, so no connection pool is left open behind)."""
    from jointdb.store import Repository

    return Repository(db_url, blobs=blobs)


@functools.lru_cache(maxsize=4)
def _worker_state(pinned: str, base: str | None, db_url: str, blobs: str | None = None):
    """The problem and the substructure cache of one spec on a worker process (kept between tasks)."""
    import json

    repo = _worker_repo(db_url, blobs)
    problem = problem_from_document(json.loads(pinned), repo, base=base)
    return problem, SubstructureCache(problem, repo)


def evaluate_chunk_by_reference(pinned: str, base: str | None, db_url: str, candidates: Sequence[Candidate],
                                blobs: str | None = None) -> list[CandidateResult]:
    """:func:`evaluate_chunk` on a Dask worker: the pinned spec document, the database and its blob store
    named, the substructures computed there."""
    problem, cache = _worker_state(pinned, base, db_url, blobs)
    return evaluate_chunk(problem, candidates, cache)


def chunks(candidates: Sequence[Candidate], size: int = CHUNK) -> list[list[int]]:
    """Indices of the candidates in chunks of about ``size``, whole (holder, overhang) groups each."""
    groups: dict = {}
    for i, c in enumerate(candidates):
        groups.setdefault((c.holder, c.overhang_m), []).append(i)
    out: list[list[int]] = [[]]
    for idx in groups.values():
        if out[-1] and len(out[-1]) + len(idx) > size:
            out.append([])
        out[-1].extend(idx)
    return [c for c in out if c]


def _client(scheduler: str, n_workers: int | None):
    """``(client, cluster)`` for ``"local"`` or a scheduler address; the caller closes both."""
    try:
        from distributed import Client, LocalCluster
    except ImportError:  # a declared dependency; a broken install says so
        raise InputError("Dask's distributed package is not installed (pip install 'distributed>=2026.8')") from None
    if scheduler == "local":
        import logging

        # the workers' own shutdown chatter (heartbeats to a scheduler that has closed) is not the user's concern;
        # a task's error still reaches the caller through its future
        cluster = LocalCluster(n_workers=n_workers or 2, threads_per_worker=1, processes=True,
                               dashboard_address=None, silence_logs=logging.CRITICAL)
        return Client(cluster), cluster
    return Client(scheduler), None


def evaluate_candidates(problem: OptimizeProblem, candidates: Sequence[Candidate], repo,
                        progress: Progress | None = None, *, keep_tips: bool = False,
                        scheduler: str | None = None, n_workers: int | None = None,
                        chunk_size: int = CHUNK) -> list[CandidateResult]:
    """Predict and rate every candidate (the fast path; equal to :func:`evaluate_brute_force`).

    Parameters
    ----------
    problem
        From :func:`jointdb.usecases._optimize.load_problem`.
    candidates
        From :func:`jointdb.usecases._optimize.enumerate_candidates` (any subset, any order).
    repo
        The joint store (a :class:`jointdb.store.Repository`).
    progress
        Called as ``progress(done, total, message)`` after each chunk.
    keep_tips
        Keep each candidate's tip FRF in its result (in-process only).
    scheduler
        ``None`` / ``"in-process"``: this process; ``"local"``: a Dask local cluster of ``n_workers``
        processes (default 2); otherwise a Dask scheduler address. The same :func:`evaluate_chunk` runs
        either way; a cluster needs a spec file and a database URL the workers can open.
    chunk_size
        Candidates per task.

    Returns
    -------
    list of CandidateResult
        In the order of ``candidates``.
    """
    parts = chunks(candidates, chunk_size)
    total = len(candidates)
    results: list = [None] * total
    if scheduler in (None, "in-process") or keep_tips:
        cache = SubstructureCache(problem, repo)
        if cache.coupled_planes:  # the two-plane chain over cross terms: no batched path, use the reference
            return evaluate_brute_force(problem, candidates, repo, progress)
        done = 0
        for idx in parts:
            for i, r in zip(idx, evaluate_chunk(problem, [candidates[i] for i in idx], cache, keep_tips)):
                results[i] = r
            done += len(idx)
            if progress:
                progress(done, total, "in-process")
        return results
    if not problem.pinned:
        raise InputError("a Dask cluster loads the spec from its document: build the problem with load_problem "
                         "or problem_from_document")
    from distributed import as_completed

    client, cluster = _client(scheduler, n_workers)
    try:
        futures = {client.submit(evaluate_chunk_by_reference, problem.pinned, problem.base, str(repo.url),
                                 [candidates[i] for i in idx], _blobs_of(repo), pure=False): idx for idx in parts}
        done = 0
        for fut in as_completed(futures):
            idx = futures[fut]
            for i, r in zip(idx, fut.result()):
                results[i] = r
            done += len(idx)
            if progress:
                progress(done, total, f"Dask, {len(client.scheduler_info()['workers'])} workers")
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    return results
