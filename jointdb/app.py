"""Use cases that span layers: files → numerics → database, called by the CLI (and an HTTP API).

- :func:`load_stack` — read a stack file, load a referenced spindle FRF / model file.
- :func:`resolve_joints` — fetch each interface's joint from the database
  (pinned ``name@version`` or the nearest to the requested conditions),
  reporting the chosen version, its distance and extrapolation warnings.
- :func:`predict_stack` — resolve, then :func:`jointdb.stack.predict_tool_tip`.
- :func:`load_campaign`, :func:`identify_campaign`, :func:`catalogue_campaign` —
  identify a joint from a measurement campaign (IRC, theory §2a) and catalogue it.

Campaign file (JSON, paths relative to the file)::

    {
      "format": "jointdb-campaign/1",
      "name": "th-er32-carbide-080nm",           # joint name in the catalogue
      "joint_type": "tool-holder",
      "model_kind": "spring-damper-planar",
      "conditions": {"materials": ["tungsten-carbide", "steel"], "torque_nm": 80,
                     "geometry": {"shank_diameter_m": 0.012}},
      "measured": {"file": "x.uff", "tip_node": 1, "contact_node": 2},   # G_11, G_12 (UFF58/HDF5/CSV)
      "substructure_a": {"model": "a.json", "point": "nose"},            # machine + holder, with rotations
      "substructure_b": {"model": "b.json", "tip": "tip", "contact": "base"},   # the tool
      "identification": {"method": "irc-planar", "smoothing": 9},       # Savitzky–Golay window or null
      "reference": {"k": [...], "c": [...]}                             # optional: known answer
    }
"""

from __future__ import annotations

import json
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

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
    "Campaign",
    "CatalogueOutcome",
    "read_frf_file",
    "load_stack",
    "resolve_joints",
    "predict_stack",
    "load_campaign",
    "identify_campaign",
    "catalogue_campaign",
]

CAMPAIGN_FORMAT = "jointdb-campaign/1"


# ------------------------------------------------------------------ files
def _read_json(path: Path, what: str) -> Any:
    try:
        text = Path(path).read_text(encoding="utf-8")
    except FileNotFoundError:
        raise NotFoundError(f"{what} {path} does not exist") from None
    except OSError as exc:
        raise InputError(f"cannot read {what} {path}: {exc.strerror}") from None
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(f"{what} {path}: not valid JSON (line {exc.lineno}, column {exc.colno}: {exc.msg})") from None


def read_frf_file(path: Path | str) -> FRF:
    """Read an FRF from UFF58 (``.uff``, ``.unv``), HDF5 (``.h5``, ``.hdf5``) or CSV by suffix.

    Raises
    ------
    NotFoundError, InputError
    """
    from jointdb import io

    p = Path(path)
    if not p.exists():
        raise NotFoundError(f"FRF file {p} does not exist")
    suffix = p.suffix.lower()
    if suffix in (".uff", ".unv", ".uf"):
        return io.read_frf_uff58(p)
    if suffix in (".h5", ".hdf5"):
        return io.read_frf_hdf5(p)
    if suffix == ".csv":
        return io.read_frf_csv(p)
    raise InputError(f"{p}: unknown FRF file type {suffix!r}; use .uff/.unv (UFF58), .h5/.hdf5 or .csv")


def write_frf_file(path: Path | str, frf: FRF) -> Path:
    """Write an FRF as UFF58 / HDF5 / CSV chosen by the suffix."""
    from jointdb import io

    p = Path(path)
    suffix = p.suffix.lower()
    if suffix in (".uff", ".unv"):
        io.write_uff58(p, frf, round_freq=True)
    elif suffix in (".h5", ".hdf5"):
        io.write_frf_hdf5(p, frf)
    elif suffix == ".csv":
        io.write_frf_csv(p, frf)
    else:
        raise InputError(f"--out {p}: unknown file type {suffix!r}; use .uff, .h5 or .csv")
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
    doc = _read_json(p, "stack file")
    try:
        spec = stack_from_dict(doc)
    except InputError as exc:
        raise InputError(f"{p.name}: {exc}") from None
    sp = spec.spindle
    if isinstance(sp, MeasuredSpindle):
        frf = read_frf_file(p.parent / sp.file)
        spec = spec.replace(spindle=MeasuredSpindle(sp.file, sp.node, frf))
    elif isinstance(sp, ModelledSpindle) and isinstance(sp.model, str):
        model = _read_json(p.parent / sp.model, "spindle model file")
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
                                            warnings=notes, description=choice.reference)
                continue
            conditions = Conditions.from_dict(dict(choice.conditions or {}))
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always", OutsideCatalogueWarning)
                matches = handle.nearest(choice.joint_type, conditions, k=choice.neighbours)
            texts = tuple(str(w.message) for w in caught if issubclass(w.category, OutsideCatalogueWarning))
            if not matches:
                raise NotFoundError(f"interfaces.{name}: no catalogued joint of type {choice.joint_type!r}")
            best = matches[0]
            cands = tuple((m.version.name, m.version.version, float(m.distance)) for m in matches)
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
                tuple(best.outside_range), cands, texts, choice.reference,
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
    """Resolve a stack's joints from the database, then predict its tool-tip FRF (theory §4).

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
class Campaign:
    """A loaded measurement campaign (see the module docstring for the file)."""

    path: Path
    name: str
    joint_type: str
    model_kind: str
    conditions: Mapping[str, Any]
    measured: FRF
    measured_file: Path
    tip_node: int
    contact_node: int
    a_model: Any
    a_point: str
    a_file: Path
    b_model: Any
    b_tip: str
    b_contact: str
    b_file: Path
    smoothing: int | None
    reference: Mapping[str, Any] | None
    description: str = ""


def _need(obj: Mapping[str, Any], key: str, where: str) -> Any:
    if not isinstance(obj, Mapping):
        raise InputError(f"{where}: must be an object")
    if key not in obj:
        raise InputError(f"{where}.{key}: required field is missing")
    return obj[key]


def load_campaign(path: Path | str) -> Campaign:
    """Read a campaign file with its measured FRFs and substructure models.

    Raises
    ------
    InputError
        Naming the file and field; NotFoundError for missing files.
    """
    from jointdb.fe import load_model

    p = Path(path)
    doc = _read_json(p, "campaign file")
    w = p.name
    if not isinstance(doc, Mapping):
        raise InputError(f"{w}: must be a JSON object")
    if doc.get("format", CAMPAIGN_FORMAT) != CAMPAIGN_FORMAT:
        raise InputError(f"{w}: format: unsupported {doc.get('format')!r}; this jointdb reads {CAMPAIGN_FORMAT!r}")
    meas = _need(doc, "measured", w)
    sa, sb = _need(doc, "substructure_a", w), _need(doc, "substructure_b", w)
    mfile = p.parent / str(_need(meas, "file", f"{w}: measured"))
    afile = p.parent / str(_need(sa, "model", f"{w}: substructure_a"))
    bfile = p.parent / str(_need(sb, "model", f"{w}: substructure_b"))
    ident = doc.get("identification", {}) or {}
    smoothing = ident.get("smoothing")
    if smoothing is not None and (isinstance(smoothing, bool) or not isinstance(smoothing, int) or smoothing < 5
                                  or smoothing % 2 == 0):
        raise InputError(f"{w}: identification.smoothing: must be an odd window >= 5 lines or null, got {smoothing!r}")
    for key in ("tip_node", "contact_node"):
        v = _need(meas, key, f"{w}: measured")
        if isinstance(v, bool) or not isinstance(v, int) or v < 0:
            raise InputError(f"{w}: measured.{key}: must be a node number, got {v!r}")
    return Campaign(
        path=p,
        name=str(_need(doc, "name", w)),
        joint_type=str(_need(doc, "joint_type", w)),
        model_kind=str(doc.get("model_kind", "spring-damper-planar")),
        conditions=dict(_need(doc, "conditions", w)),
        measured=read_frf_file(mfile),
        measured_file=mfile,
        tip_node=meas["tip_node"],
        contact_node=meas["contact_node"],
        a_model=load_model(afile),
        a_point=str(_need(sa, "point", f"{w}: substructure_a")),
        a_file=afile,
        b_model=load_model(bfile),
        b_tip=str(_need(sb, "tip", f"{w}: substructure_b")),
        b_contact=str(_need(sb, "contact", f"{w}: substructure_b")),
        b_file=bfile,
        smoothing=smoothing,
        reference=doc.get("reference"),
        description=str(doc.get("description", "")),
    )


def identify_campaign(campaign: Campaign, every: int = 1):
    """IRC identification of a campaign's planar joint (theory §2a).

    ``every`` keeps every n-th measured line and the last (a coarser grid, for quick runs).

    Returns
    -------
    (IdentificationResult, KCFit)
        The identified joint FRF with diagnostics, and constant (k, c) fitted over the band.
    """
    from jointdb.coupling import fit_constant_kc, identify_planar_joint

    if isinstance(every, bool) or not isinstance(every, int) or every < 1:
        raise InputError(f"every must be a positive whole number of lines, got {every!r}")
    meas = campaign.measured.band(fmin=np.nextafter(0.0, 1.0)).to("receptance")
    if every > 1:  # keep both band edges so the joint covers the same band
        keep = np.unique(np.append(np.arange(0, meas.n_freq, every), meas.n_freq - 1))
        meas = meas.replace(freq=meas.freq[keep], values=meas.values[keep])
    f = meas.freq
    a = campaign.a_model.frf(f, [campaign.a_point])
    b = campaign.b_model.frf(f, [campaign.b_tip, campaign.b_contact])
    a_node = campaign.a_model.point(campaign.a_point).node
    result = identify_planar_joint(
        meas, a, a_node, b, campaign.b_model.point(campaign.b_contact).node,
        campaign.b_model.point(campaign.b_tip).node, smoothing=campaign.smoothing,
    )
    return result, fit_constant_kc(result.joint)


@dataclass(frozen=True, eq=False)
class CatalogueOutcome:
    """What cataloguing a campaign did."""

    campaign: Campaign
    version: Any  # jointdb.store.JointVersion
    k: np.ndarray
    c: np.ndarray
    kc_error: np.ndarray
    residual_median: float
    unreliable_fraction: float
    reused: bool

    def row(self) -> dict[str, Any]:
        cond = self.campaign.conditions
        return {
            "joint": f"{self.version.name}@{self.version.version}",
            "materials": "+".join(cond.get("materials", [])),
            "torque_nm": cond.get("torque_nm"),
            "k_x_n_per_m": float(self.k[0]),
            "k_theta_nm_per_rad": float(self.k[1]),
            "c_x_ns_per_m": float(self.c[0]),
            "c_theta_nms_per_rad": float(self.c[1]),
            "residual": self.residual_median,
            "new": not self.reused,
        }


def catalogue_campaign(repo, path: Path | str, author: str | None = None, every: int = 1) -> CatalogueOutcome:
    """Identify a campaign's joint and store it as a new version (or reuse an identical latest version).

    The stored FRF is the identified joint receptance; provenance records the
    SHA-256 of every input file and the method's settings; quality the median
    re-coupling residual, the fraction of flagged lines and the constant-(k, c)
    misfit.
    """
    from jointdb import __version__ as software_version
    from jointdb.store import Conditions, Provenance, file_sha256, frf_sha256

    camp = load_campaign(path)
    result, kc = identify_campaign(camp, every)
    handle, owned = _open_repo(repo)
    try:
        joint = result.joint
        try:
            latest = handle.get(camp.name)
        except NotFoundError:
            latest = None
        if latest is not None and latest.blob_sha256 == frf_sha256(joint):
            version, reused = latest, True
        else:
            files = {f.name: file_sha256(f) for f in (camp.path, camp.measured_file, camp.a_file, camp.b_file)}
            prov = Provenance(
                method="irc-planar",
                parameters={"smoothing": camp.smoothing, "campaign": camp.path.name, "every": every,
                            "kc_fit": {"k": kc.k.tolist(), "c": kc.c.tolist()}},
                input_files=files,
                software_version=str(software_version),
            )
            quality = {
                "identification_residual": float(np.median(result.residual)),
                "unreliable_fraction": float(np.mean(result.unreliable)),
                "kc_misfit_translation": float(kc.error[0]),
                "kc_misfit_rotation": float(kc.error[1]),
            }
            version = handle.catalogue(camp.name, camp.joint_type, joint, Conditions.from_dict(camp.conditions),
                                       camp.model_kind, prov, quality, author=author)
            reused = False
    finally:
        if owned:
            handle.close()
    return CatalogueOutcome(camp, version, kc.k, kc.c, kc.error, float(np.median(result.residual)),
                            float(np.mean(result.unreliable)), reused)
