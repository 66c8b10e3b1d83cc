"""Identify jobs: an uploaded campaign unpacked (hardened), identified, and the review data.

The review data is what a test engineer checks before cataloguing: the constant k, c per
DOF with σ (when the identification gives one) and units, the quality verdict, the
conditions the campaign records (with any contradiction of the upload form flagged), and
curves for plots (measured vs re-coupled vs rigid assembly, k(ω) and c(ω) of the joint).
The identified joint is kept as the HDF5 exchange file of ``jointdb identify``; cataloguing
the job (:func:`catalogue_job`) reads that file, exactly as ``jointdb catalogue joint.h5``.
"""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from jointdb.errors import InputError, JointdbError

#: largest number of frequency lines in a plotted curve (thinned evenly)
CURVE_POINTS = 400


def unpack_upload(tmp: Path, filename: str, data: bytes) -> Path:
    """Write an uploaded campaign (.zip) into ``tmp`` and unpack it with the service's checks
    (:func:`jointdb.io._uploads.unpack_campaign`); returns the campaign file."""
    from jointdb.io._uploads import unpack_campaign

    name = filename if filename.lower().endswith(".zip") else "campaign.zip"
    path = tmp / Path(name).name
    path.write_bytes(data)
    return unpack_campaign(path, tmp / "campaign")


def _unit(dof: str, what: str) -> str:
    from jointdb.frf import Dof

    rot = Dof.parse(dof).is_rotation
    return {"k": "N·m/rad" if rot else "N/m", "c": "N·m·s/rad" if rot else "N·s/m"}[what]


def _thin(n: int) -> np.ndarray:
    return np.unique(np.linspace(0, n - 1, min(n, CURVE_POINTS)).round().astype(int))


def _curves(outcome) -> dict[str, Any]:
    """|H| of measured, re-coupled and rigid assembly per entry; k(ω), c(ω) per joint DOF."""
    m, rec, rig = outcome.measured, outcome.reconstructed, outcome.rigid
    idx = _thin(m.n_freq)
    entries = []
    for i, o in enumerate(m.outputs):
        for j, inp in enumerate(m.inputs):
            if o not in rec.outputs or inp not in rec.inputs:
                continue
            ri, rj = rec.outputs.index(o), rec.inputs.index(inp)
            entries.append({"entry": f"{o}/{inp}", "unit": f"{'rad' if o.is_rotation else 'm'}/{'(N·m)' if inp.is_rotation else 'N'}",
                            "measured": np.abs(m.values[idx, i, j]).tolist(),
                            "recoupled": np.abs(rec.values[idx, ri, rj]).tolist(),
                            "rigid": np.abs(rig.values[idx, ri, rj]).tolist() if o in rig.outputs else None})
    joint = outcome.result.joint
    jidx = _thin(joint.n_freq)
    w = 2 * np.pi * joint.freq[jidx]
    dofs = []
    for k, d in enumerate(joint.inputs):
        if d not in joint.outputs:
            continue
        h = joint.values[jidx, joint.outputs.index(d), k]
        with np.errstate(divide="ignore", invalid="ignore"):
            z = 1.0 / h
        dofs.append({"dof": str(d), "k": np.where(np.isfinite(z.real), z.real, np.nan).tolist(),
                     "c": np.where(np.isfinite(z.imag), z.imag / w, np.nan).tolist(),
                     "k_unit": _unit(str(d), "k"), "c_unit": _unit(str(d), "c")})
    clean = lambda rows: [None if not np.isfinite(v) else v for v in rows]  # noqa: E731
    for d in dofs:
        d["k"], d["c"] = clean(d["k"]), clean(d["c"])
    return {"assembly": {"freq_hz": m.freq[idx].tolist(), "entries": entries},
            "joint": {"freq_hz": joint.freq[jidx].tolist(), "dofs": dofs}}


def _parameters(rep: dict) -> list[dict[str, Any]]:
    """k, c per DOF with σ and units: the output-error fit's parameters when there is one, else the
    constant fit of the IRC joint (σ not estimated by IRC: null)."""
    sigma: dict[tuple[str, str], float] = {}
    oe = rep.get("output_error") or {}
    for row in oe.get("parameters", []) or []:
        name = str(row.get("parameter", ""))
        what, _, dof = name.partition(" ")
        if what in ("k", "c") and row.get("std_error") is not None:
            sigma[(what, dof.strip())] = float(row["std_error"])
    out = []
    for row in rep.get("constant_fit", []):
        dof = row["dof"]
        out.append({"dof": dof, "k": row["k"], "k_sigma": sigma.get(("k", dof)), "k_unit": _unit(dof, "k"),
                    "c": row["c"], "c_sigma": sigma.get(("c", dof)), "c_unit": _unit(dof, "c"),
                    "fit_error": row.get("error")})
    return out


def _contradictions(campaign_file: Path, recorded: dict, form: dict | None) -> list[str]:
    """Where the upload form's conditions contradict the campaign's (empty: none or no form)."""
    from jointdb.store import Conditions
    from jointdb.usecases import merge_conditions

    if not form:
        return []
    try:
        merge_conditions(campaign_file, recorded, Conditions.from_dict(form), force=False)
    except InputError as exc:
        return [" ".join(str(exc).replace(str(campaign_file.parent) + "/", "").split())]
    return []


def identify_review(tmp: Path, payload: dict, upload: bytes, progress) -> tuple[dict[str, Any], bytes]:
    """Unpack, identify, and return ``(review, joint file bytes)`` (see the module's docstring)."""
    from jointdb._output import to_jsonable
    from jointdb.campaign import joint_attrs
    from jointdb.io import write_frf_hdf5
    from jointdb.usecases import identify

    progress(0.02, "unpacking the campaign")
    cfile = unpack_upload(tmp, str(payload.get("filename") or "campaign.zip"), upload)
    progress(0.1, "identifying the joint (IRC)")
    try:
        outcome = identify(cfile, root=tmp / "campaign")
    except JointdbError as exc:  # name the upload's own files, never the worker's folder
        raise type(exc)(str(exc).replace(f"{tmp}/campaign/", "").replace(f"{tmp}/", "")) from None
    progress(0.85, "writing the joint file")
    rep = to_jsonable(outcome.report())
    joint_file = tmp / "joint.h5"
    write_frf_hdf5(joint_file, outcome.result.joint, joint_attrs(outcome))
    c = outcome.campaign
    review = {
        "campaign": c.name, "joint_type": c.joint_type, "joint_model": c.joint_model,
        "joint_dofs": rep.get("joint_dofs"), "parameters": _parameters(rep),
        "verdict": rep.get("verdict", []), "quality": {k: v for k, v in rep.items() if k in (
            "reconstruction_error_mean", "rigid_joint_error_mean", "peaks", "validation", "model_adequacy",
            "fit_band_hz")},
        "conditions": to_jsonable(dict(c.conditions)),
        "contradictions": _contradictions(cfile, dict(c.conditions), payload.get("conditions")),
        "suggested_name": c.name, "curves": _curves(outcome),
    }
    return review, joint_file.read_bytes()


def catalogue_job(repo, job_row, overrides: dict, owner: str):
    """Catalogue an identify job's joint as a new version (``POST /api/v1/jobs/{id}/catalogue``).

    ``overrides`` may give ``name``, ``label``, ``conditions`` (completing / overriding the
    campaign's, with ``force`` for a contradiction), ``parent``. Returns the repository's
    catalogue outcome (created or identical).
    """
    import json

    from jointdb.store import Conditions
    from jointdb.store._types import check_label
    from jointdb.usecases import catalogue_inputs

    m = job_row._mapping
    if m["artifact"] is None:
        raise InputError("this job has no identified joint to catalogue")
    review = json.loads(m["result"]) if m["result"] else {}
    name = overrides.get("name") or review.get("suggested_name")
    if not name:
        raise InputError("name: give the joint's name")
    label = check_label(overrides["label"]) if overrides.get("label") else None
    given = Conditions.from_dict(overrides.get("conditions") or {})
    with tempfile.TemporaryDirectory(prefix="jointdb-job-") as tmp:
        path = Path(tmp) / f"{m['id']}.h5"
        path.write_bytes(m["artifact"])
        try:
            args = catalogue_inputs(path, given, author=owner, force=bool(overrides.get("force")))
        except JointdbError as exc:
            raise type(exc)(str(exc).replace(f"{tmp}/", "")) from None
    args["provenance"] = _with_job(args["provenance"], m["id"])
    return repo.catalogue_outcome(name, parent=overrides.get("parent"), author=owner, label=label, **args)


def _with_job(prov, job_id: str):
    import dataclasses

    params = dict(prov.parameters)
    params["job"] = job_id
    return dataclasses.replace(prov, parameters=params)
