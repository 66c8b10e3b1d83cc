"""Use cases that span layers: files → numerics → database, called by the CLI (and any other front end).

- :func:`load_stack` — read a stack file, load a referenced spindle FRF / model file.
- :func:`resolve_joints` — fetch each interface's joint from the database
  (pinned ``name@version`` or the nearest to the requested conditions),
  reporting the chosen version, its distance and extrapolation warnings.
- :func:`predict_stack` — resolve, then :func:`jointdb.stack.predict_tool_tip`.
- :func:`catalogue_campaign` — identify a joint from a measurement campaign
  (IRC, docs/theory.md §2; the project's ``jointdb-campaign/1`` file, read by
  :mod:`jointdb.campaign._file`) and catalogue it.

"""

from __future__ import annotations

import os
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from jointdb._jsonfile import read_json_file
from jointdb.errors import InputError, NotFoundError
from jointdb.frf import FRF
from jointdb.stack import (
    INTERFACE_NAMES,
    MeasuredSpindle,
    ModelledSpindle,
    Prediction,
    StackSpec,
    predict_tool_tip,
    prediction_grid,
    stack_from_dict,
)

__all__ = [
    "JointResolution",
    "StackPrediction",
    "CatalogueOutcome",
    "read_frf_file",
    "write_frf_file",
    "load_stack",
    "resolve_joints",
    "predict_stack",
    "catalogue_campaign",
]

# ------------------------------------------------------------------ files


#: How many nearest catalogued joints a stack's interpolated query ranks before the interpolation picks the
#: ones that bracket the request along the condition axes (jointdb.store._interp).
INTERPOLATION_POOL = 64

#: FRF file formats by suffix (reading and writing).
FRF_SUFFIXES = {".uff": "uff58", ".unv": "uff58", ".uff58": "uff58", ".uf": "uff58", ".58": "uff58",
                ".h5": "hdf5", ".hdf5": "hdf5", ".hdf": "hdf5", ".csv": "csv"}


def frf_format(path: Path | str, option: str = "") -> str:
    """``"uff58"``, ``"hdf5"`` or ``"csv"`` from the suffix; InputError naming the option otherwise."""
    p = Path(path)
    fmt = FRF_SUFFIXES.get(p.suffix.lower())
    if fmt is None:
        where = f"{option} {str(p)!r}" if option else str(p)
        raise InputError(f"{where}: unknown FRF file type {p.suffix.lower()!r}; use .uff/.unv (UFF58), "
                         ".h5/.hdf5 or .csv")
    return fmt


def read_frf_file(path: Path | str) -> FRF:
    """Read an FRF from UFF58 (``.uff``, ``.unv``), HDF5 (``.h5``, ``.hdf5``) or CSV by suffix.

    Raises
    ------
    NotFoundError, InputError
    """
    from jointdb import io

    p = Path(path)
    fmt = frf_format(p)
    if not p.exists():
        raise NotFoundError(f"FRF file {p} does not exist")
    if fmt == "uff58":
        return io.read_frf_uff58(p)
    if fmt == "hdf5":
        return io.read_frf_hdf5(p)
    return io.read_frf_csv(p)


def write_frf_file(path: Path | str, frf: FRF, *, binary: bool = False, round_freq: bool = True,
                   option: str = "--out") -> Path:
    """Write an FRF as UFF58 / HDF5 / CSV chosen by the suffix (atomically).

    ``binary`` writes UFF58 as 58b (exact); ``round_freq`` lets ASCII UFF58
    round frequencies to its 6 significant digits (see :func:`jointdb.io.write_uff58`).
    """
    from jointdb import io

    p = Path(path)
    fmt = frf_format(p, option)
    if not p.parent.is_dir():
        raise InputError(f"{option} {str(p)!r}: directory {str(p.parent)!r} does not exist")
    if fmt == "uff58":
        io.write_uff58(p, frf, binary=binary, round_freq=round_freq)
    elif fmt == "hdf5":
        io.write_frf_hdf5(p, frf)
    else:
        io.write_frf_csv(p, frf)
    return p


def load_stack(path: Path | str) -> StackSpec:
    """Read and validate a stack file; load a measured spindle FRF or a spindle model file it references.

    Raises
    ------
    InputError
        Naming the stack file and the field (``stack.json: tool.segments[1].length: must be > 0``).
    NotFoundError
        Missing stack / spindle files.
    """
    p = Path(path)
    doc = read_json_file(p, "stack file")
    try:
        spec = stack_from_dict(doc)
    except InputError as exc:
        raise InputError(f"{p.name}: {exc}") from None
    sp = spec.spindle
    if isinstance(sp, MeasuredSpindle):
        frf = read_frf_file(p.parent / sp.file)
        spec = spec.replace(spindle=MeasuredSpindle(sp.file, sp.node, frf))
    elif isinstance(sp, ModelledSpindle) and isinstance(sp.model, str):
        model = read_json_file(p.parent / sp.model, "spindle model file")
        spec = spec.replace(spindle=ModelledSpindle(model, sp.point))
    return spec


# ------------------------------------------------------------------ joints
@dataclass(frozen=True, eq=False)
class JointResolution:
    """How one interface's joint was chosen.

    ``kind``: rigid / explicit / catalogued / query / interpolated. For database
    joints: ``name``, ``version``, ``distance`` (0 for a pinned joint),
    ``per_condition`` terms, ``extrapolating`` and ``outside_range``; ``candidates``
    lists the nearest versions considered as ``(name, version, distance)``;
    ``warnings`` are messages for the user.
    """

    interface: str
    kind: str
    frf: FRF | None = None
    name: str | None = None
    version: int | None = None
    distance: float | None = None
    per_condition: Mapping[str, float] = field(default_factory=dict)
    extrapolating: bool = False
    outside_range: tuple[str, ...] = ()
    candidates: tuple[tuple[str, int, float], ...] = ()
    warnings: tuple[str, ...] = ()
    description: str = ""
    uncertainty: Mapping[str, Any] | None = None  # the version's parameter covariance, if it was fitted with one

    def row(self) -> dict[str, Any]:
        """A flat row for tables / JSON."""
        return {
            "interface": self.interface,
            "kind": self.kind,
            "joint": f"{self.name}@{self.version}" if self.name else self.description,
            "distance": self.distance,
            "per_condition": ", ".join(f"{k}={v:.3g}" for k, v in self.per_condition.items()) or None,
            "extrapolating": self.extrapolating,
            "warnings": "; ".join(self.warnings) or None,
        }


def _open_repo(repo_or_url):
    from jointdb.store import Repository

    if repo_or_url is None or isinstance(repo_or_url, (str, Path)):
        return Repository(repo_or_url), True
    return repo_or_url, False


def _uncertainty_of(version) -> Mapping[str, Any] | None:
    """The parameter covariance a catalogued version carries in its provenance (None if it has none)."""
    params = getattr(getattr(version, "provenance", None), "parameters", None) or {}
    unc = params.get("uncertainty") if isinstance(params, Mapping) else None
    return unc if isinstance(unc, Mapping) else None


def identical_version(repo, name: str, joint_type: str, frf: FRF, conditions, model_kind: str):
    """The joint's current version when it already holds exactly this record, else ``None``.

    Identical means the same joint FRF (blob hash), the same conditions, joint type
    and model kind: cataloguing it again would add a version that says nothing
    new, so ``jointdb catalogue`` (unless ``--allow-identical``) and ``jointdb demo``
    report "identical to vN" and write nothing.
    """
    from jointdb.store import Conditions, frf_sha256

    try:
        latest = repo.get(name)
    except NotFoundError:
        return None
    if not isinstance(conditions, Conditions):
        conditions = Conditions.from_dict(dict(conditions or {}))
    def key(c):
        return (sorted(c.materials), c.preload_n, c.torque_nm, dict(c.geometry), dict(c.extra))

    same = (latest.blob_sha256 == frf_sha256(frf) and key(latest.conditions) == key(conditions)
            and latest.joint_type == joint_type and latest.model_kind == model_kind)
    return latest if same else None


def resolve_joints(spec: StackSpec, repo=None) -> dict[str, JointResolution]:
    """Resolve every interface of a stack against the joint database.

    Parameters
    ----------
    spec
        The stack.
    repo
        A :class:`jointdb.store.Repository`, or a database URL / path (``None``:
        ``JOINTDB_URL`` or the per-user default). Only opened when some
        interface needs the database.

    Raises
    ------
    NotFoundError
        A pinned joint/version that does not exist, or no catalogued joint of the queried type.
    """
    from jointdb.store import Conditions, OutsideCatalogueWarning

    out: dict[str, JointResolution] = {}
    needs_db = any(spec.interfaces[n].kind in ("catalogued", "query") for n in INTERFACE_NAMES)
    handle, owned = _open_repo(repo) if needs_db else (None, False)
    try:
        for name in INTERFACE_NAMES:
            choice = spec.interfaces[name]
            if choice.kind in ("rigid", "explicit"):
                out[name] = JointResolution(name, choice.kind, description=choice.reference)
                continue
            if choice.kind == "catalogued":
                version = choice.version
                if isinstance(version, int):
                    jv = handle.get(choice.name, version=version)
                else:
                    jv = handle.get(choice.name, label=str(version))
                notes = ()
                if jv.state != "active":
                    notes = (f"{jv.name}@{jv.version} is {jv.state}",)
                out[name] = JointResolution(name, "catalogued", handle.load_frf(jv), jv.name, jv.version, 0.0,
                                            warnings=notes, description=choice.reference,
                                            uncertainty=_uncertainty_of(jv))
                continue
            conditions = Conditions.from_dict(dict(choice.conditions or {}))
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always", OutsideCatalogueWarning)
                # interpolation picks the joints bracketing the request along the condition axes: it needs the
                # catalogued grid around the request, not only the `neighbours` nearest
                pool = max(choice.neighbours, INTERPOLATION_POOL) if choice.interpolate else choice.neighbours
                matches = handle.nearest(choice.joint_type, conditions, k=pool)
                if len(matches) > choice.neighbours:  # the pool beyond the nearest: joints it can be mixed with
                    kind, dofs = matches[0].version.model_kind, tuple(matches[0].version.dofs)
                    matches = matches[:choice.neighbours] + [
                        m for m in matches[choice.neighbours:]
                        if m.version.model_kind == kind and tuple(m.version.dofs) == dofs]
            texts = tuple(str(w.message) for w in caught if issubclass(w.category, OutsideCatalogueWarning))
            if not matches:
                raise NotFoundError(f"interfaces.{name}: no catalogued joint of type {choice.joint_type!r}")
            best = matches[0]
            cands = tuple((m.version.name, m.version.version, float(m.distance)) for m in matches[:choice.neighbours])
            if choice.interpolate and len(matches) > 1:
                joint = handle.interpolate(matches, conditions)
                out[name] = JointResolution(
                    name, "interpolated", joint.frf, best.version.name, best.version.version, float(best.distance),
                    dict(best.per_condition), bool(best.extrapolating), tuple(best.outside_range), cands,
                    texts, joint.describe(),
                )
                continue
            out[name] = JointResolution(
                name, "query", handle.load_frf(best.version), best.version.name, best.version.version,
                float(best.distance), dict(best.per_condition), bool(best.extrapolating),
                tuple(best.outside_range), cands, texts, choice.reference, _uncertainty_of(best.version),
            )
    finally:
        if owned and handle is not None:
            handle.close()
    return out


@dataclass(frozen=True, eq=False)
class StackPrediction:
    """A prediction with the record of how each joint was resolved."""

    spec: StackSpec
    prediction: Prediction
    joints: Mapping[str, JointResolution]


def predict_stack(spec: StackSpec | Path | str, repo=None, freq=None) -> StackPrediction:
    """Resolve a stack's joints from the database, then predict its tool-tip FRF (docs/theory.md §4).

    ``spec`` may be a path to a stack file. See :func:`resolve_joints` for ``repo``.
    """
    if not isinstance(spec, StackSpec):
        spec = load_stack(spec)
    joints = resolve_joints(spec, repo)
    f = prediction_grid(spec, freq)
    resolved = {n: r.frf for n, r in joints.items() if r.frf is not None}
    pred = predict_tool_tip(spec, resolved, f)
    return StackPrediction(spec, pred, joints)


# ------------------------------------------------------------------ campaigns
@dataclass(frozen=True, eq=False)
class CatalogueOutcome:
    """What cataloguing a campaign did.

    ``identified`` is the :class:`jointdb.campaign._run.IdentifyOutcome`
    (campaign, IRC result, re-coupled and rigid assemblies, constant (k, c) fit);
    ``version`` the stored :class:`jointdb.store.JointVersion`; ``reused`` is
    True when the latest version already held this exact record (:func:`identical_version`).
    """

    identified: Any
    version: Any
    reused: bool

    @property
    def campaign(self):
        return self.identified.campaign

    def row(self) -> dict[str, Any]:
        """A flat row: joint, conditions, constant (k, c), residuals."""
        cond = self.campaign.conditions
        kc = self.identified.kc
        res = self.identified.result
        row: dict[str, Any] = {
            "joint": f"{self.version.name}@{self.version.version}",
            "materials": "+".join(cond.get("materials", [])),
            "torque_nm": cond.get("torque_nm"),
        }
        if kc is not None and len(kc.k) == 2:
            row.update({"k_x_n_per_m": float(kc.k[0]), "k_theta_nm_per_rad": float(kc.k[1]),
                        "c_x_ns_per_m": float(kc.c[0]), "c_theta_nms_per_rad": float(kc.c[1])})
        row["residual_median"] = float(np.median(res.residual))
        row["unreliable_fraction"] = float(np.mean(res.unreliable))
        row["new"] = not self.reused
        return row


def _campaign_files(camp) -> dict[str, str]:
    """SHA-256 of the campaign file and every file it references (provenance)."""
    from jointdb.store import file_sha256

    paths = [camp.path, *camp.measurements, *(s.path for s in camp.substructures.values())]
    if camp.validation:
        paths += [*camp.validation["measurements"], *(s.path for s in camp.validation["substructures"].values())]
    base = camp.path.resolve().parent
    return {Path(os.path.relpath(Path(p).resolve(), base)).as_posix(): file_sha256(p) for p in paths}


def catalogue_campaign(repo, path: Path | str, author: str | None = None) -> CatalogueOutcome:
    """Identify a campaign's joint (as ``jointdb identify`` does) and store it as a new version.

    The campaign file is the project's ``jointdb-campaign/1`` format (see
    :mod:`jointdb.campaign._file`). The stored FRF is the identified
    joint receptance; the joint name is the campaign's ``name``; provenance
    records the SHA-256 of the campaign and every file it references and the
    method's settings; quality the re-coupling and constant-(k, c) errors. If
    the latest version of that joint already holds the same record (same FRF
    blob hash, conditions, type and model kind; :func:`identical_version`)
    nothing is written and that version is returned.

    Raises
    ------
    InputError
        Bad campaign files (naming the field), bad data.
    """
    from jointdb import __version__ as software_version
    from jointdb._output import to_jsonable
    from jointdb.campaign import load_campaign
    from jointdb.campaign import identify_campaign, joint_attrs
    from jointdb.store import Conditions, Provenance

    camp = load_campaign(path)
    outcome = identify_campaign(camp)
    joint = outcome.result.joint
    kinds = {"planar": "spring-damper-planar", "n-point": "n-point-translational", "matrix": "full-matrix"}
    handle, owned = _open_repo(repo)
    try:
        same = identical_version(handle, camp.name, camp.joint_type, joint, Conditions.from_dict(camp.conditions),
                                 kinds[camp.joint_model])
        if same is not None:
            return CatalogueOutcome(outcome, same, True)
        attrs = to_jsonable(joint_attrs(outcome))
        quality = {
            "identification_residual": float(np.median(outcome.result.residual)),
            "unreliable_fraction": float(np.mean(outcome.result.unreliable)),
            "reconstruction_error_mean": float(attrs["quality"].get("reconstruction_error_mean", float("nan"))),
        }
        if outcome.kc is not None:
            for d, e in zip(outcome.kc.dofs, outcome.kc.error):
                quality[f"kc_misfit_{d.direction}"] = float(e)
        if outcome.validation is not None:
            quality["validation_error"] = float(outcome.validation["identified_joint_error_mean"])
        prov = Provenance(
            method=str(attrs.get("method", f"irc-{camp.joint_model}")),
            parameters={k: attrs[k] for k in ("settings", "interface", "campaign", "uncertainty") if k in attrs},
            input_files=_campaign_files(camp),
            software_version=str(software_version),
        )
        version = handle.catalogue(camp.name, camp.joint_type, joint, Conditions.from_dict(camp.conditions),
                                   kinds[camp.joint_model], prov,
                                   {k: v for k, v in quality.items() if np.isfinite(v)}, author=author)
        return CatalogueOutcome(outcome, version, False)
    finally:
        if owned:
            handle.close()
