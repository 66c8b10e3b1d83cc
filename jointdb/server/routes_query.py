"""Computing routes (reader): nearest query, interpolation, stack prediction, stability lobes."""

from __future__ import annotations

import warnings
from typing import Any

from fastapi import APIRouter, Depends
from fastapi.responses import JSONResponse

from jointdb.errors import InputError
from jointdb.io import frf_json
from jointdb.server._deps import reader, repo, version_json
from jointdb.server._schemas import LobesJobIn, NearestIn, PredictIn

router = APIRouter(tags=["query"])


def run_nearest(r, body: NearestIn):
    """Matches and warnings of :meth:`Repository.nearest` (shared by the API and the web form)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        matches = r.nearest(body.joint_type, body.conditions.to_conditions(), k=body.k, at=body.at, label=body.label,
                            all_versions=body.all_versions, include_deprecated=body.include_deprecated)
    return matches, [" ".join(str(w.message).split()) for w in caught]


def match_json(m) -> dict[str, Any]:
    return {"name": m.version.name, "version": m.version.version, "distance": m.distance,
            "per_condition": dict(m.per_condition), "extrapolating": m.extrapolating,
            "outside_range": list(m.outside_range), "joint": version_json(m.version)}


@router.post("/query/nearest", summary="The k catalogued versions nearest to given conditions")
def nearest(body: NearestIn, r=Depends(repo), _who=reader) -> JSONResponse:
    """Ranked by distance = sqrt(sum of the per-condition terms squared); the first is the
    answer, the others are the runners-up."""
    matches, notes = run_nearest(r, body)
    return JSONResponse({"matches": [match_json(m) for m in matches], "warnings": notes})


@router.post("/query/interpolate", summary="A joint FRF interpolated between the nearest versions")
def interpolate(body: NearestIn, r=Depends(repo), _who=reader) -> dict[str, Any]:
    """The neighbours' dynamic stiffness weighted by the joints bracketing the request along the condition
    axes, among the k nearest (NOT a catalogued joint)."""
    matches, notes = run_nearest(r, body)
    ij = r.interpolate(matches, body.conditions.to_conditions())
    return {"label": ij.label, "description": ij.describe(), "joint_type": ij.joint_type,
            "neighbours": [{"name": n, "version": v, "weight": w} for n, v, w in ij.neighbours],
            "passivity_moved": [{"name": n, "version": v, "lines": k} for n, v, k in ij.passivity_moved],
            "warnings": notes, "frf": frf_json(ij.frf)}


@router.post("/predict", summary="Tool-tip FRF of a stack (with band and joint-choice sensitivity)")
def predict(body: PredictIn, r=Depends(repo), _who=reader) -> dict[str, Any]:
    """As ``jointdb predict --json``: joints from the catalogue (pinned, nearest or explicit), the
    tip FRF and the rigid-joint tip, the 5–95 % band from the joints' covariance, the change with
    the next-nearest joints. The stack must carry its spindle model inline (a server reads no client
    files) or name catalogued parts (``{"part": "name@version"}`` for tool, holder, spindle; listed in
    ``parts``). Takes seconds to a minute: prefer ``POST /api/v1/jobs/predict``."""
    from jointdb.jobs._run import run_predict

    # the stack as sent (not model_dump: pydantic refuses to serialise a hostile 300-deep stack with a 500;
    # stack_from_document answers it with a 422 naming the field)
    result, _ = run_predict({"stack": body.stack}, r, lambda fraction, message: None)
    return result


@router.post("/lobes", summary="Stability lobes from a tool-tip FRF (milling ZOA or SD, or turning)")
def lobes(body: LobesJobIn, _who=reader) -> dict[str, Any]:
    """As ``jointdb lobes --json``: method, summary (floor, deepest pocket), rows (depth in m), best
    speeds and notes — a kt/kr/kf given in N/mm² (e.g. ``kt: 796``) is recognised, converted to N/m²
    and said so in ``notes``. Refinement (``refine`` rounds) as the CLI. SD can take minutes: prefer
    ``POST /api/v1/jobs/lobes``."""
    from jointdb.jobs._run import run_lobes

    result, _ = run_lobes(check_lobes(body), None, lambda fraction, message: None)
    return result


def check_lobes(body: LobesJobIn) -> dict[str, Any]:
    """The checks a lobes request gets before any work (field-named 422s)."""
    from jointdb.jobs._run import tip_frf_input

    payload = body.model_dump(mode="json")
    if body.joint is not None or body.frf is None:
        raise InputError("joint: a catalogued joint FRF describes an interface, not a tool tip; lobes need the "
                         "tool-tip FRF of a stack as frf (run a predict job and send its tip_frf)"
                         if body.joint is not None else "frf: give the tool-tip FRF (JSON)")
    tip_frf_input(payload.get("frf"))
    if not body.rpm_min < body.rpm_max:
        raise InputError("rpm_min must be < rpm_max")
    if body.op == "milling" and (body.kt is None or body.kr is None):
        raise InputError("kt, kr: milling needs both cutting coefficients (N/m²)")
    if body.op == "turning" and body.kf is None:
        raise InputError("kf: turning needs the cutting coefficient (N/m²)")
    return payload
