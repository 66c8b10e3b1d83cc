"""Measurement planning: which assembly FRFs determine the joint best (issue 13, item 4).

For a joint model at a current estimate θ (log k, log c per DOF), each candidate assembly
FRF ``G_oi`` (response o, excitation i) has a sensitivity ``J_oi(ω) = ∂G_oi/∂θ`` from the
substructure models alone (:class:`~jointdb.coupling._oe_core.CoupledBlocks`). With
complex noise of standard deviation ``σ = r |G|`` per line (r: relative noise of one
average), its Fisher information is ``F_oi = Σ_ω 2 Re(J^H J) / σ²``. A set of measured
FRFs adds its informations; ``F⁻¹`` is the covariance of θ an efficient fit reaches
(the output-error fit is one). Sets are ranked by the A-criterion on the target
parameters (sum of their relative variances) or by the D-criterion (−log det F).
Averages divide the variance: ``n_avg = ⌈(σ_θ(1) / target)²⌉``.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from jointdb.coupling._oe_core import CoupledBlocks, SpringDamperModel
from jointdb.errors import InputError

__all__ = ["MeasurementPlan", "plan_measurements"]


@dataclass(frozen=True, eq=False)
class MeasurementPlan:
    """Candidate measurement sets ranked best first.

    ``rows``: per set, ``measurements`` (list of ``"o/i"``), ``criterion`` value, ``std_rel``
    (relative standard error per parameter with one average), and ``averages`` needed for
    ``target`` on every target parameter.
    """

    parameters: list[str]
    targets: list[str]
    criterion: str
    noise: float
    target: float
    rows: list[dict]


def _pair_information(model: SpringDamperModel, theta: np.ndarray, blocks: CoupledBlocks, noise: float,
                      band_mask: np.ndarray) -> tuple[np.ndarray, list[tuple[int, int]]]:
    g, jac = model.evaluate(theta, blocks, jac=True)  # (nf, n, n), (nf, n, n, p)
    n = g.shape[1]
    pairs = [(o, i) for o in range(n) for i in range(o, n)]  # reciprocity: G_oi = G_io
    sig2 = (noise * np.abs(g[band_mask])) ** 2
    j = jac[band_mask]
    info = np.empty((len(pairs), jac.shape[-1], jac.shape[-1]))
    for k, (o, i) in enumerate(pairs):  # loops over DOF pairs; each is batched over lines
        jj = j[:, o, i, :] / np.sqrt(sig2[:, o, i])[:, None]
        info[k] = 2 * np.real(jj.conj().T @ jj)
    return info, pairs


def plan_measurements(model: SpringDamperModel, theta: np.ndarray, blocks: CoupledBlocks, *,
                      n_measurements: int = 2, noise: float = 0.01, targets: Sequence[str] | None = None,
                      criterion: str = "A", target: float = 0.05, band: "tuple[float, float] | None" = None,
                      must_include: Sequence[tuple[int, int]] = (), top: int = 10) -> MeasurementPlan:
    """Rank every set of ``n_measurements`` candidate FRFs by the expected joint-parameter variance.

    Parameters
    ----------
    model, theta
        Joint model and the current estimate (e.g. an output-error fit's ``theta``).
    blocks
        Coupled blocks with outputs = inputs = the candidate DOFs.
    n_measurements
        FRFs per set (each a response/excitation pair; a driving point counts as one).
    noise
        Relative noise of one averaged FRF (0.01 = 1 %).
    targets
        Parameter names whose precision matters (default: all).
    criterion
        ``"A"``: sum of the targets' relative variances; ``"D"``: −log det of the information.
    target
        Wanted relative standard error of every target parameter (for ``averages``).
    must_include
        Candidate index pairs every set must contain.

    Raises
    ------
    InputError
        Unknown target names or criterion, fewer candidates than ``n_measurements``.
    """
    if criterion not in ("A", "D"):
        raise InputError(f"criterion must be A or D, got {criterion!r}")
    names = model.names
    tg = list(names) if targets is None else list(targets)
    bad = [t for t in tg if t not in names]
    if bad:
        raise InputError(f"unknown target parameter(s) {bad}; the model has {names}")
    ti = [names.index(t) for t in tg]
    use = np.ones(blocks.freq.size, bool) if band is None else (blocks.freq >= band[0]) & (blocks.freq <= band[1])
    info, pairs = _pair_information(model, np.asarray(theta, float), blocks, float(noise), use)
    if len(pairs) < n_measurements:
        raise InputError(f"{len(pairs)} candidate FRFs, {n_measurements} asked")
    fixed = [pairs.index(tuple(sorted(p))) for p in must_include]
    labels = [f"{blocks.outputs[o]}/{blocks.inputs[i]}" for o, i in pairs]
    rows = []
    others = [k for k in range(len(pairs)) if k not in fixed]
    for combo in itertools.combinations(others, max(n_measurements - len(fixed), 0)):
        sel = list(fixed) + list(combo)
        f = info[sel].sum(axis=0)
        try:
            cov = np.linalg.inv(f)
        except np.linalg.LinAlgError:
            continue
        var = np.diag(cov)
        if np.any(~np.isfinite(var)) or np.any(var <= 0):
            continue
        if criterion == "A":
            crit = float(np.sum(var[ti]))
        else:
            sign, logdet = np.linalg.slogdet(f)
            crit = float(-logdet) if sign > 0 else np.inf
        sd = np.sqrt(var)
        rows.append({"measurements": [labels[k] for k in sel], "criterion": crit,
                     "std_rel": {n: float(s) for n, s in zip(names, sd)},
                     "averages": int(np.ceil(np.max((sd[ti] / target) ** 2)))})
    rows.sort(key=lambda r: r["criterion"])
    return MeasurementPlan(list(names), tg, criterion, float(noise), float(target), rows[:top])
