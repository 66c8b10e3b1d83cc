"""What each kind of job does: the use cases, run with progress and cancellation.

A runner gets the job's JSON input (``payload``), the uploaded bytes (identify), an open
repository and a :class:`Progress`; it returns ``(result, artifact)``: the JSON result the
API shows and, for identify, the identified joint file (HDF5 bytes) that ``catalogue``
stores later. A runner calls ``progress(fraction, message)`` between steps; that call
raises :class:`Cancelled` once a cancel was asked for, so a job stops at its next step.
"""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Any, Callable

import numpy as np

from jointdb.errors import InputError

KINDS = ("predict", "lobes", "diagnose", "identify", "optimize")
#: Most ranking rows an optimize job returns.
MAX_OPTIMIZE_ROWS = 1000


class Cancelled(Exception):
    """A cancel was asked for; the job stops at its next step."""


class Progress:
    """``progress(fraction, message)``: records progress through ``record`` (which returns whether a
    cancel was asked for) and raises :class:`Cancelled` when one was."""

    def __init__(self, record: Callable[[float, str], bool]):
        self._record = record

    def __call__(self, fraction: float, message: str) -> None:
        if self._record(fraction, message):
            raise Cancelled("cancelled while running")


def tip_frf_input(data, field: str = "frf"):
    """An FRF sent as JSON (``data``, the request's ``field``), with a field-named error for any shape
    problem (never a numpy message)."""
    from jointdb.io import frf_from_json

    if not isinstance(data, dict):
        raise InputError(f"{field}: an FRF object (freq_hz, outputs, inputs, real, imag) is needed")
    for part in ("real", "imag"):
        try:
            np.asarray(data.get(part), dtype=float)
        except (ValueError, TypeError):
            raise InputError(f"{field}.{part}: must be a full (n_freq, n_outputs, n_inputs) array of numbers "
                             "(rows of unequal length were given)") from None
    try:
        return frf_from_json(data)
    except InputError as exc:  # io names the field "frf"; the request may have called it otherwise
        text = str(exc)
        raise InputError(field + text[3:] if text.startswith("frf") and field != "frf" else text) from None


def run_lobes(payload: dict, repo, progress: Progress) -> tuple[dict, None]:
    from jointdb.usecases import lobes_report

    if payload.get("joint") is not None:
        raise InputError("joint: a catalogued joint FRF describes an interface, not a tool tip; lobes need the "
                         "tool-tip FRF of a stack (run a predict job and send its tip_frf as frf)")
    frf = tip_frf_input(payload.get("frf"))
    keys = ("op", "method", "teeth", "kt", "kr", "kf", "immersion", "up", "rpm_min", "rpm_max", "n_speeds",
            "refine", "intervals", "modes", "band", "max_order", "cross_terms")
    args = {k: payload[k] for k in keys if payload.get(k) is not None}
    if "band" in args:
        args["band"] = tuple(args["band"])
    return lobes_report(frf, progress=progress, **args), None


def run_predict(payload: dict, repo, progress: Progress) -> tuple[dict, None]:
    from jointdb import usecases
    from jointdb.io import frf_json
    from jointdb.stack import MeasuredSpindle, ModelledSpindle

    spec = usecases.stack_from_document(payload.get("stack"), repo)  # catalogued parts resolved
    sp = spec.spindle
    if (isinstance(sp, MeasuredSpindle) and sp.frf is None) or (isinstance(sp, ModelledSpindle)
                                                                 and isinstance(sp.model, str)):
        raise InputError("stack.spindle: refers to a file; send the spindle model inline or name a catalogued "
                         "part (the server reads no client files)")
    from jointdb.usecases._tip_band import choice_sensitivity, tip_band_of

    progress(0.05, "choosing the joints")
    joints = usecases.resolve_joints(spec, repo)
    progress(0.3, "coupling the stack")
    result = usecases.predict_with_joints(spec, joints)
    pred = result.prediction
    progress(0.5, "the band from the joints' covariance")
    band, terms, band_notes = tip_band_of(result)
    progress(0.8, "the next-nearest joints")
    sensitivity, choice_notes = choice_sensitivity(result, repo, pred.tip.freq)
    progress(0.95, "writing the result")
    return {"stack": spec.name, "parts": list(spec.parts), "joints": [j.row() for j in joints.values()],
            "prediction": pred.summary(),
            "notes": [*pred.notes, *band_notes, *choice_notes], "tip_frf": frf_json(pred.tip),
            "rigid_tip_frf": frf_json(pred.rigid),
            "band": None if band is None else {**band.to_json(), **terms.to_json()},
            "joint_choice_sensitivity": sensitivity}, None


def run_diagnose(payload: dict, repo, progress: Progress) -> tuple[dict, None]:
    """``jointdb diagnose`` on a model (JSON) and recorded FRFs (JSON), levels and a point map."""
    import dataclasses

    from jointdb.diagnose import Measurement, diagnose
    from jointdb.fe import model_from_dict

    model = model_from_dict(payload.get("model"))
    recs = payload.get("recordings") or []
    if not isinstance(recs, list) or not recs:
        raise InputError("recordings: give one or more recorded FRFs (JSON), one per excitation level")
    ms = [Measurement(tip_frf_input(r, f"recordings[{i}]")) for i, r in enumerate(recs)]
    levels = payload.get("levels") or []
    if levels and len(levels) != len(ms):
        raise InputError(f"levels: {len(levels)} values for {len(ms)} recordings")
    if not levels and len(ms) > 1:
        levels = [float(i + 1) for i in range(len(ms))]
    ms = [dataclasses.replace(m, level=float(v)) for m, v in zip(ms, levels)] if levels else ms
    mapping = {int(k): str(v) for k, v in (payload.get("map") or {}).items()}
    band = tuple(payload.get("band") or (None, None))
    progress(0.05, "diagnosing")
    result = diagnose(model, ms, mapping=mapping, band=band, combinations=bool(payload.get("combinations", True)))
    from jointdb.io._jsonable import to_jsonable

    return to_jsonable(result.to_dict() | {"input_notes": list(result.observation.notes)}), None


def optimize_options(payload: dict) -> tuple[int, bool]:
    """``(top, simulate)`` of an optimize job's payload, checked (InputError naming the field)."""
    top, simulate = payload.get("top", 20), payload.get("simulate", True)
    if isinstance(top, bool) or not isinstance(top, int) or not 1 <= top <= MAX_OPTIMIZE_ROWS:
        raise InputError(f"top: a whole number of ranking rows in 1-{MAX_OPTIMIZE_ROWS}, got {str(top)[:40]}")
    if not isinstance(simulate, bool):
        raise InputError(f"simulate: true or false, got {str(simulate)[:40]}")
    return top, simulate


def run_optimize(payload: dict, repo, progress: Progress) -> tuple[dict, None]:
    """``jointdb optimize`` on a spec sent inline (parts and joints from the catalogue, no server files).

    The candidates are evaluated in the worker's process, or on the Dask scheduler the deployment names
    in ``JOINTDB_DASK_SCHEDULER`` (never one the request names); the result is
    :func:`jointdb.usecases._optimize_run.outcome_json`, as ``jointdb optimize --json`` prints it.
    """
    import os

    from jointdb.usecases import optimize_stack
    from jointdb.usecases._optimize import problem_from_document
    from jointdb.usecases._optimize_run import outcome_json

    top, simulate = optimize_options(payload)
    progress(0.02, "reading the spec and the parts")
    problem = problem_from_document(payload.get("spec"), repo, where="spec", allow_files=False)

    def report(done: int, total: int, message: str) -> None:
        progress(0.05 + 0.8 * done / max(total, 1), f"{done}/{total} candidates ({message})")

    scheduler = os.environ.get("JOINTDB_DASK_SCHEDULER") or "in-process"
    outcome = optimize_stack(problem, repo, progress=report, simulate=simulate, scheduler=scheduler)
    progress(0.95, "writing the result")
    return outcome_json(problem, outcome, top), None


def run_identify(payload: dict, upload: bytes | None, progress: Progress) -> tuple[dict, bytes]:
    """Unpack the uploaded campaign (hardened: :func:`jointdb.jobs._review.unpack_upload`), identify it
    and return the review data with the joint file (HDF5 bytes) to catalogue."""
    from jointdb.jobs._review import identify_review

    if not upload:
        raise InputError("identify: the job has no uploaded campaign")
    with tempfile.TemporaryDirectory(prefix="jointdb-job-") as tmp:
        return identify_review(Path(tmp), payload, upload, progress)


def run(kind: str, payload: dict, upload: bytes | None, repo, progress: Progress) -> tuple[dict[str, Any], bytes | None]:
    """Run one job of ``kind``; returns ``(result, artifact)``."""
    if kind == "lobes":
        return run_lobes(payload, repo, progress)
    if kind == "predict":
        return run_predict(payload, repo, progress)
    if kind == "diagnose":
        return run_diagnose(payload, repo, progress)
    if kind == "identify":
        return run_identify(payload, upload, progress)
    if kind == "optimize":
        return run_optimize(payload, repo, progress)
    raise InputError(f"kind must be one of {', '.join(KINDS)}, got {kind!r}")
