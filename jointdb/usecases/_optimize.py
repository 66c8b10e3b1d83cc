"""``jointdb optimize``: the stack and cut with the highest stable removal rate across the catalogue.

A plain function over typed inputs (:func:`optimize_stack`) with a progress callback, so a shell or a
job queue can wrap it. Candidates are every combination of an allowed holder, an overhang on the spec's
grid, a catalogued clamping torque and a catalogued drawbar force inside the spec's ranges. Each is
predicted (both planes) and its zero-order lobes computed; per candidate the best speed and depth
obey stability (less the margin), the flute length, and the spindle's power and torque.

Fast path (:func:`evaluate_candidates`): the substructures are computed once per content — the spindle
once, tool and holder once per (holder, overhang), each joint once per condition — and the receptance
coupling runs over all the candidates of one (holder, overhang) at once (a leading candidate axis
broadcast through :func:`jointdb.stack.tool_tip_chain`). :func:`evaluate_brute_force` is the
straightforward loop (``predict_stack`` + ``stability_lobes`` per candidate), the reference the tests
compare it with.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from jointdb.errors import InputError, NotFoundError
from jointdb.frf import FRF
from jointdb.usecases._optimize_spec import HolderOption, OptimizeProblem, load_problem, problem_from_document

__all__ = ["Candidate", "CandidateResult", "HolderOption", "OptimizeProblem", "load_problem", "problem_from_document",
           "enumerate_candidates", "candidate_stack", "best_cut", "available_power", "evaluate_brute_force",
           "pareto_front", "rank"]

Progress = Callable[[int, int, str], None]


@dataclass(frozen=True)
class Candidate:
    """One stack to evaluate: holder name, overhang (gauge length) [m], clamping torque [N·m], drawbar [N]."""

    holder: str
    overhang_m: float
    torque_nm: float
    drawbar_n: float


@dataclass(frozen=True, eq=False)
class CandidateResult:
    """A candidate's lobes and best cut (``best``: speed, depth, removal rate, binding constraint)."""

    candidate: Candidate
    lobes: Any
    best: dict
    joints: dict = field(default_factory=dict)
    tip: FRF | None = None

    def row(self) -> dict:
        c = self.candidate
        return {"holder": c.holder, "overhang_m": c.overhang_m, "torque_nm": c.torque_nm, "drawbar_n": c.drawbar_n,
                **self.best, **{f"joint_{k}": v for k, v in self.joints.items()}}


def _catalogued(joints, attr: str, lo: float, hi: float, geometry: dict) -> list[float]:
    """Distinct catalogued values of ``attr`` (torque_nm / preload_n) within [lo, hi] among ``joints``
    (the current versions of one joint type, read once per enumeration)."""
    values = set()
    for jv in joints:
        cond = jv.conditions
        if getattr(cond, attr) is None or jv.state != "active":
            continue
        if any(k in cond.geometry and not math.isclose(cond.geometry[k], v, rel_tol=1e-6) for k, v in geometry.items()):
            continue
        value = float(getattr(cond, attr))
        if lo <= value <= hi:
            values.add(value)
    return sorted(values)


def _query_geometry(choice) -> dict:
    return dict((choice.conditions or {}).get("geometry") or {})


def _pinned_condition(tpl, interface: str, attr: str, allowed, repo) -> float | None:
    """The ``attr`` condition (torque_nm / preload_n) of the joint an interface pins (``name@version``), checked
    against the spec's range; None when the interface is a query."""
    choice = tpl.interfaces[interface]
    if choice.kind != "catalogued":
        return None
    v = choice.version
    jv = repo.get(choice.name, version=v) if isinstance(v, int) else repo.get(choice.name, label=str(v))
    value = getattr(jv.conditions, attr)
    what = "torque_nm" if attr == "torque_nm" else "drawbar_n"
    if value is None or not allowed[0] <= float(value) <= allowed[1]:
        raise InputError(f"interfaces.{interface}: the pinned joint {jv.name}@{jv.version} was measured at "
                         f"{attr} {value}, outside the spec's {what} {list(allowed)}")
    return float(value)


def enumerate_candidates(problem: OptimizeProblem, repo) -> list[Candidate]:
    """Every allowed holder × overhang on the grid × catalogued torque × catalogued drawbar force in range
    (an interface pinned to a catalogued joint, ``name@version``, contributes its one measured condition).

    Raises
    ------
    NotFoundError
        No catalogued torque or drawbar force inside the spec's ranges.
    InputError
        More than :data:`jointdb.schemas.optimize.MAX_CANDIDATES` candidates, or candidates × speeds
        above :data:`jointdb.schemas.optimize.MAX_WORK`.
    """
    from jointdb.schemas.optimize import MAX_CANDIDATES, MAX_WORK

    spec, tpl = problem.spec, problem.template
    lo, hi = spec.tool.overhang_m
    n = int(math.floor((hi - lo) / spec.tool.overhang_step_m + 1e-9)) + 1
    overhangs = [round(lo + k * spec.tool.overhang_step_m, 9) for k in range(max(n, 1))]
    pinned_torque = _pinned_condition(tpl, "tool-holder", "torque_nm", spec.torque_nm, repo)
    if pinned_torque is not None:
        torques = [pinned_torque]
    else:
        th_geom = _query_geometry(tpl.interfaces["tool-holder"])
        torques = _catalogued(repo.list_joints("tool-holder", include_deprecated=False), "torque_nm",
                              *spec.torque_nm, th_geom)
    if not torques:
        raise NotFoundError(f"no catalogued tool-holder joint with a torque in {list(spec.torque_nm)} N·m")
    pinned_force = _pinned_condition(tpl, "holder-spindle", "preload_n", spec.drawbar_n, repo)
    out = []
    tapers = repo.list_joints("holder-spindle", include_deprecated=False) if pinned_force is None else []
    for h in problem.holders:
        geom = _query_geometry(tpl.interfaces["holder-spindle"])
        if h.taper_diameter_m is not None:
            geom["taper_diameter_m"] = h.taper_diameter_m
        forces = ([pinned_force] if pinned_force is not None else
                  _catalogued(tapers, "preload_n", *spec.drawbar_n, geom))
        if not forces:
            raise NotFoundError(f"holder {h.name}: no catalogued holder-spindle joint with a drawbar force in "
                                f"{list(spec.drawbar_n)} N (taper {geom.get('taper_diameter_m')})")
        out += [Candidate(h.name, g, t, f) for g in overhangs for t in torques for f in forces]
        if len(out) > MAX_CANDIDATES or len(out) * spec.machine.n_speeds > MAX_WORK:
            raise InputError(f"too many candidates: {len(overhangs)} overhangs × {len(torques)} torques × "
                             f"{len(forces)} drawbar forces per holder, {len(problem.holders)} holders × "
                             f"{spec.machine.n_speeds} speeds exceeds {MAX_CANDIDATES} candidates or {MAX_WORK:.0e} "
                             "candidate-speeds (narrow the ranges or coarsen the grids)")
    return out


def candidate_stack(problem: OptimizeProblem, cand: Candidate):
    """The template stack with the candidate's holder, overhang and interface conditions."""
    from jointdb.stack import JointChoice, stack_from_dict, stack_to_dict

    tpl = problem.template
    try:
        holder = problem.holder(cand.holder)
    except KeyError:
        raise InputError(f"candidate holder {cand.holder!r} is not among the spec's holders") from None
    spec = tpl
    if holder.holder is not None:
        doc = stack_to_dict(tpl)
        doc["holder"] = holder.holder
        spec = stack_from_dict(doc).replace(spindle=tpl.spindle)
    if not 0 < cand.overhang_m < spec.tool.length:
        raise InputError(f"overhang {cand.overhang_m} m: must be inside the tool's length {spec.tool.length} m")
    th, hs = spec.interfaces["tool-holder"], spec.interfaces["holder-spindle"]
    if th.kind not in ("query", "catalogued") or hs.kind not in ("query", "catalogued"):
        raise InputError("the template stack's interfaces must be catalogue queries ({\"query\": {...}}) or "
                         "catalogued joints (name@version)")
    interfaces = dict(spec.interfaces)
    if th.kind == "query":
        th_c = {**dict(th.conditions), "torque_nm": cand.torque_nm}
        interfaces["tool-holder"] = JointChoice(**{**th.__dict__, "conditions": th_c})
    if hs.kind == "query":
        hs_c = {**dict(hs.conditions), "preload_n": cand.drawbar_n}
        if holder.taper_diameter_m is not None:
            hs_c["geometry"] = {**dict(hs_c.get("geometry") or {}), "taper_diameter_m": holder.taper_diameter_m}
        interfaces["holder-spindle"] = JointChoice(**{**hs.__dict__, "conditions": hs_c})
    return spec.replace(gauge_length=cand.overhang_m, interfaces=interfaces)


def available_power(machine, speed_rpm) -> np.ndarray | None:
    """The spindle power available at each speed [W]: the smaller of the flat ``power_w`` and the
    ``power_curve`` (linear between its points); None when the spec gives neither.

    Parameters
    ----------
    machine
        The spec's :class:`jointdb.schemas.optimize.Machine`.
    speed_rpm
        Spindle speeds [rpm], shape ``(n_speeds,)``.

    Returns
    -------
    numpy.ndarray or None
        Shape ``(n_speeds,)`` [W].
    """
    n = np.asarray(speed_rpm, dtype=float)
    out = None if machine.power_w is None else np.full(n.shape, float(machine.power_w))
    if machine.power_curve is not None:
        curve = np.interp(n, [p.speed_rpm for p in machine.power_curve], [p.power_w for p in machine.power_curve])
        out = curve if out is None else np.minimum(out, curve)
    return out


def best_cut(problem: OptimizeProblem, lobes, stability_m=None) -> dict:
    """The speed and depth of highest removal rate under stability (less the margin), flute length,
    spindle power (flat or a curve over speed) and torque; ``binding`` names the constraint that sets the
    depth there.

    Removal rate ``Q = a · a_e · f_z · N · n/60`` [m³/s]; cutting power ``P = K_t Q`` (linear force law,
    no edge forces); spindle torque ``P / ω``.

    Parameters
    ----------
    problem
        The optimize problem (spec, template, cut).
    lobes
        The candidate's :class:`jointdb.stability.LobeResult` (speeds [rpm], limiting depth [m]).
    stability_m
        The stability limit per speed [m] to use instead of ``lobes.depth_m`` (e.g. the band's lower
        edge); the same shape.

    Returns
    -------
    dict
        ``spindle_speed_rpm``, ``depth_m`` [m], ``removal_rate_m3_s``, ``binding``, ``stability_limit_m``
        (of ``lobes`` at that speed), ``power_w`` (cutting power) and ``margin``.
    """
    spec, cut = problem.spec, problem.cut
    n = np.asarray(lobes.spindle_speed_rpm, float)
    diameter = max(s.diameter for s in problem.template.tool.segments)
    rate_per_depth = spec.cut.radial_immersion * diameter * spec.cut.feed_per_tooth_m * cut.n_teeth * n / 60.0
    stab = np.asarray(lobes.depth_m if stability_m is None else stability_m, dtype=float)
    limits = {"stability": np.where(np.isfinite(stab), stab * (1 - spec.objective.margin),
                                    np.where(np.isnan(stab), 0.0, np.inf)),
              "flute length": np.full(n.size, spec.tool.flute_length_m)}
    power = available_power(spec.machine, n)
    if power is not None:
        limits["power"] = power / (cut.kt * rate_per_depth)
    if spec.machine.torque_nm is not None:
        limits["torque"] = spec.machine.torque_nm * 2 * np.pi * n / 60.0 / (cut.kt * rate_per_depth)
    names = list(limits)
    stacked = np.stack([limits[k] for k in names])
    depth = stacked.min(axis=0)
    rate = depth * rate_per_depth
    i = int(np.argmax(rate))
    return {"spindle_speed_rpm": float(n[i]), "depth_m": float(depth[i]), "removal_rate_m3_s": float(rate[i]),
            "binding": names[int(np.argmin(stacked[:, i]))], "stability_limit_m": float(lobes.depth_m[i]),
            "power_w": float(cut.kt * rate[i]), "margin": spec.objective.margin}


def _lobes(problem: OptimizeProblem, tip: FRF):
    from jointdb.usecases._lobes import stability_lobes

    m, c = problem.spec.machine, problem.cut
    return stability_lobes(tip, "milling", rpm_min=m.speed_rpm[0], rpm_max=m.speed_rpm[1], n_speeds=m.n_speeds,
                           teeth=c.n_teeth, kt=c.kt, kr=c.kr, immersion=c.radial_immersion, up=not c.down_milling)


def _joint_names(joints) -> dict:
    return {k: (f"{r.name}@{r.version}" if r.name else r.description) for k, r in joints.items()}


def evaluate_brute_force(problem: OptimizeProblem, candidates: Sequence[Candidate], repo,
                         progress: Progress | None = None) -> list[CandidateResult]:
    """The straightforward loop: ``predict_stack`` + ``stability_lobes`` per candidate (the reference)."""
    from jointdb.usecases._stack import predict_stack

    out = []
    for k, cand in enumerate(candidates):
        pred = predict_stack(candidate_stack(problem, cand), repo)
        lobes = _lobes(problem, pred.prediction.tip)
        out.append(CandidateResult(cand, lobes, best_cut(problem, lobes), _joint_names(pred.joints), pred.prediction.tip))
        if progress:
            progress(k + 1, len(candidates), "brute force")
    return out


def pareto_front(problem: OptimizeProblem, results: Sequence[CandidateResult], margins=None):
    """``(margins, rates)``: the highest removal rate [m³/s] of any candidate when a fraction ``margin`` of
    the limiting depth is held back (default margins 0–50 %), from each candidate's zero-order lobes."""
    from dataclasses import replace

    margins = np.linspace(0, 0.5, 11) if margins is None else np.asarray(margins, dtype=float)
    rates = []
    for m in margins:
        objective = problem.spec.objective.model_copy(update={"margin": float(m)})
        prob = replace(problem, spec=problem.spec.model_copy(update={"objective": objective}))
        rates.append(max(best_cut(prob, r.lobes)["removal_rate_m3_s"] for r in results))
    return margins, np.array(rates)


def rank(results: Sequence[CandidateResult]) -> list[CandidateResult]:
    """Highest removal rate first (stable sort: ties keep the enumeration order)."""
    return sorted(results, key=lambda r: -r.best["removal_rate_m3_s"])
