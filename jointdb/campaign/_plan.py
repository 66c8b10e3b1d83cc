"""``jointdb plan CAMPAIGN``: rank candidate tap points for a campaign's joint (issue 13, item 4)."""

from __future__ import annotations

import numpy as np

from jointdb.campaign._file import Campaign, _err, load_substructure, merge_measurements
from jointdb.coupling._oe_core import SpringDamperModel, coupled_blocks
from jointdb.coupling._plan import MeasurementPlan, plan_measurements
from jointdb.errors import InputError
from jointdb.frf import Dof


def candidate_dofs(c: Campaign, subs) -> list[tuple[str, Dof]]:
    """Every translational DOF of the interface's direction(s) that a substructure FRF holds (tap/response points)."""
    directions = {d.direction for d in c.interface["a_dofs"] if not d.is_rotation}
    out, seen = [], set()
    for name, frf in subs.items():
        for d in dict.fromkeys(list(frf.outputs) + list(frf.inputs)):
            if not d.is_rotation and d.direction in directions and d not in seen:
                out.append((name, d))
                seen.add(d)
    return out


def plan_campaign(c: Campaign, *, n_measurements: int = 2, noise: float = 0.01, target: float = 0.05,
                  criterion: str = "A", targets: list[str] | None = None) -> tuple[MeasurementPlan, dict]:
    """Plan for a planar or n-point campaign at its current output-error estimate.

    Returns the plan and the information of the campaign's own measurements (``"current"``:
    labels, std_rel, averages).

    Raises
    ------
    InputError
        Matrix campaigns, too few candidates.
    """
    from jointdb.campaign import identify_campaign

    if c.joint_model == "matrix":
        raise _err(c.path, "joint_model", "plan supports the planar and n-point models (spring–dampers)")
    outcome = identify_campaign(c)
    measured = merge_measurements(c.path, "measurements", c.measurements, c.band)
    subs = {n: load_substructure(c.path, f"substructures.{n}", s, measured.freq) for n, s in c.substructures.items()}
    cands = candidate_dofs(c, subs)
    if len(cands) < 2:
        raise InputError(f"campaign {c.path.name}: fewer than 2 candidate translational DOFs in its substructures")
    i = c.interface
    blocks = coupled_blocks(subs, i["a"], i["a_dofs"], i["b"], i["b_dofs"], cands, cands)
    fit = outcome.output_error
    if fit is not None and fit.log_parameters:
        model, theta = fit.model, fit.theta
    else:
        model = SpringDamperModel(tuple(i["a_dofs"]))
        theta = model.start(np.abs(outcome.kc.k), np.abs(outcome.kc.c))
    if targets is None and c.joint_model == "planar":
        targets = [n for n in model.names if Dof.parse(n.split()[1]).is_rotation]  # the weakly determined ones
    plan = plan_measurements(model, theta, blocks, n_measurements=n_measurements, noise=noise, target=target,
                             criterion=criterion, targets=targets, top=10)
    index = {d: k for k, (_, d) in enumerate(cands)}
    own = []
    for o in measured.outputs:
        for inp in measured.inputs:
            if o in index and inp in index:
                pair = tuple(sorted((index[o], index[inp])))
                if pair not in own:
                    own.append(pair)
    current = {}
    if own:
        cur = plan_measurements(model, theta, blocks, n_measurements=len(own), noise=noise, target=target,
                                criterion=criterion, targets=targets, must_include=own, top=1)
        if cur.rows:
            current = cur.rows[0]
    return plan, current
