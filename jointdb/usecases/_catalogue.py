"""Catalogue a joint: ONE path from a campaign or an identified joint file to a new version.

:func:`catalogue_inputs` turns a campaign file (identified here, as ``jointdb identify``
would) or the HDF5 exchange file of ``jointdb identify`` into the arguments of
:meth:`jointdb.store.Repository.catalogue`: the joint FRF, its conditions (those the
file records, completed by the caller's), joint type, model kind, quality, the raw
measurements and the provenance. The CLI (``jointdb catalogue``), the HTTP service
(``POST /api/v1/catalogue``) and the demo (:func:`catalogue_campaign`) all call it, so a
campaign's provenance does not depend on the entry point. The one provenance rule:

- ``method``: the identification method the file records (``irc-planar``, ...), or the caller's;
- ``parameters``: the file's ``settings``, ``interface``, ``campaign`` and ``uncertainty``, as JSON;
- ``input_files``: the SHA-256 of the campaign file and of every file it names, keyed by their
  path relative to the campaign file (:func:`jointdb.campaign.file_hashes`; for an uploaded
  archive that is the path inside the archive relative to the campaign, never a server path);
  for an identified joint file, that file by its name;
- ``software_version``: left to the store (the running jointdb's version).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from jointdb.errors import InputError
from jointdb.frf import FRF
from jointdb.usecases._files import MODEL_KINDS
from jointdb.usecases._stack import _open_repo

#: The metadata keys of an identified joint that the provenance keeps as its ``parameters``.
PROVENANCE_PARAMETERS = ("settings", "interface", "campaign", "uncertainty")


def numeric_metrics(data: Any, prefix: str = "") -> dict[str, float]:
    """Finite numeric scalars of a (nested) mapping, keys joined with '.'."""
    out: dict[str, float] = {}
    if not isinstance(data, dict):
        return out
    for key, value in data.items():
        name = f"{prefix}{key}"
        if isinstance(value, bool):
            continue
        if isinstance(value, (int, float)) and math.isfinite(float(value)):
            out[name] = float(value)
        elif isinstance(value, dict):
            out.update(numeric_metrics(value, name + "."))
    return out


def _positive_number(v: Any) -> bool:
    """Whether ``v`` is a finite number > 0 (not a bool)."""
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v > 0


def _quality_peaks(quality: Any) -> list | None:
    """The non-empty ``peaks`` list of a quality record, else None."""
    peaks = quality.get("peaks") if isinstance(quality, dict) else None
    return peaks if isinstance(peaks, list) and peaks else None


def identification_peak_error(quality: Any) -> float | None:
    """The dominant-peak error of a campaign's own identification assembly re-coupled with the kept joint.

    ``exp(RMS ln r) − 1`` over the ``peaks`` rows of an identified joint's quality record (``r``: re-coupled /
    measured peak |H|, :func:`jointdb.campaign._run.peak_model_error`): in-sample, 0 for a joint that gives back
    its own campaign. The band's substructure-model term uses it for tool–holder joints
    (:func:`jointdb.usecases._stack_band.model_error`).

    Parameters
    ----------
    quality
        The ``quality`` mapping of a joint file's metadata (anything else, rows that are not finite positive
        ratios, or ratios so far from 1 that the error overflows: None).

    Returns
    -------
    float or None
    """
    peaks = _quality_peaks(quality)
    if peaks is None:
        return None
    if not all(isinstance(p, dict) and _positive_number(p.get("amplitude_ratio")) for p in peaks):
        return None
    from jointdb.campaign._run import peak_model_error

    with np.errstate(over="ignore"):
        e = float(peak_model_error(peaks))
    return e if math.isfinite(e) else None


def identification_peak_hz(quality: Any) -> float | None:
    """The frequency [Hz] of the dominant measured peak of a campaign's own identification assembly.

    The ``peaks`` row (of an identified joint's quality record) with the largest measured |H| among the
    translational driving-point entries (all entries when none is translational: a rotational receptance is in
    other units), its ``f_measured_hz``. The frequency at which the joint's constant k, c was identified: the band's
    damping-law term (:mod:`jointdb.usecases._stack_band`) scales the joint's loss away from it.

    Parameters
    ----------
    quality
        The ``quality`` mapping of a joint file's metadata (anything else, or rows without a finite positive
        ``f_measured_hz`` and ``amplitude_measured``: None).

    Returns
    -------
    float or None
    """
    peaks = _quality_peaks(quality)
    if peaks is None:
        return None
    rows = []
    for p in peaks:
        f, a = (p.get("f_measured_hz"), p.get("amplitude_measured")) if isinstance(p, dict) else (None, None)
        if not (_positive_number(f) and _positive_number(a)):
            return None
        out = str(p.get("entry", "")).split("/")[0]
        translational = out[-1:] in ("x", "y", "z") and out[-2:-1] != "r"  # "1x" yes, "1rx" no
        rows.append((translational, float(a), float(f)))
    use = [r for r in rows if r[0]] or rows
    return max(use, key=lambda r: r[1])[2]


@dataclass(frozen=True, eq=False)
class JointSource:
    """What a joint or campaign file holds for the catalogue.

    Attributes
    ----------
    frf
        The joint FRF.
    meta
        The metadata of an identified joint (``joint_model``, ``joint_type``, ``conditions``,
        ``quality``, ``settings``, ...; empty for a bare FRF blob).
    input_files
        The SHA-256 of the files it came from, by path relative to the campaign (or file) it
        was read from.
    raw
        The measured FRFs to keep with the version, by key.
    identified
        The :class:`jointdb.campaign.IdentifyOutcome` when a campaign was identified, else None.
    """

    frf: FRF
    meta: dict[str, Any]
    input_files: dict[str, str]
    raw: dict[str, FRF]
    identified: Any = None


def identify(path: Path | str, *, root: Path | str | None = None):
    """Read, check and identify a campaign file (``jointdb identify``; IRC, docs/theory.md §2).

    Parameters
    ----------
    path
        The campaign file (``jointdb-campaign/1``); the files it names are relative to it.
    root
        Confine the campaign to this folder (an unpacked upload), as
        :func:`jointdb.campaign.load_campaign` does.

    Returns
    -------
    jointdb.campaign.IdentifyOutcome
        The campaign, the identified joint, the re-coupled and rigid assemblies, the constant
        (k, c) fit, the validation and the quality record.

    Raises
    ------
    InputError
        Naming the campaign file and field; NotFoundError for a missing campaign file.
    """
    from jointdb.campaign import identify_campaign, load_campaign

    return identify_campaign(load_campaign(path, root=root))


def read_joint_file(path: Path | str, root: Path | str | None = None) -> JointSource:
    """Read a joint or campaign file for the catalogue.

    Accepts the HDF5 exchange file of ``jointdb identify`` (``format = jointdb-frf``,
    metadata ``joint_model``, ``joint_type``, ``conditions``, ``quality``,
    ``settings``), a jointdb FRF blob file, or a campaign JSON file (identified
    here first, as ``jointdb identify`` would). With ``root`` a campaign may only
    name files inside that folder (an unpacked upload; see :func:`jointdb.campaign.load_campaign`).

    Parameters
    ----------
    path
        The joint HDF5 file, FRF blob file or campaign JSON file.
    root
        Confine a campaign to this folder, or None.

    Returns
    -------
    JointSource

    Raises
    ------
    InputError
        A missing or unreadable file, or a campaign that names a file wrongly (naming the field).
    """
    import h5py

    from jointdb.store import file_sha256, read_frf_file

    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: no such file")
    if path.suffix.lower() == ".json":
        from jointdb.campaign import file_hashes, joint_attrs

        outcome = identify(path, root=root)
        raw = {"measured": outcome.measured} if outcome.measured is not None else {}
        meta = joint_attrs(outcome)
        meta["quality"] = {**meta.get("quality", {}), **_identification_quality(outcome)}
        return JointSource(outcome.result.joint, meta, file_hashes(outcome.campaign), raw, outcome)
    hashes = {path.name: file_sha256(path)}
    try:
        with h5py.File(path, "r", locking=False) as f:
            fmt = f.attrs.get("format")
            fmt = fmt.decode() if isinstance(fmt, bytes) else str(fmt)
    except OSError as exc:
        raise InputError(f"{path}: not an HDF5 file ({exc})") from None
    if fmt == "jointdb-frf-blob":
        return JointSource(read_frf_file(path), {}, hashes, {})
    from jointdb.io import read_frf_hdf5_full

    frf, meta = read_frf_hdf5_full(path)
    return JointSource(frf, dict(meta or {}), hashes, {})


def _identification_quality(outcome) -> dict[str, float]:
    """Summary numbers of an identification: median residual, unreliable fraction, the constant
    (k, c) misfit per direction and the validation error (finite values only)."""
    quality = {
        "identification_residual": float(np.median(outcome.result.residual)),
        "unreliable_fraction": float(np.mean(outcome.result.unreliable)),
    }
    if outcome.kc is not None:
        for d, e in zip(outcome.kc.dofs, outcome.kc.error):
            quality[f"kc_misfit_{d.direction}"] = float(e)
    if outcome.validation is not None:
        quality["validation_error"] = float(outcome.validation["identified_joint_error_mean"])
        # the dominant peaks' error of the validation assembly: the band's substructure-model term (issue 22)
        quality["validation_peak_error"] = float(outcome.validation.get("peak_model_error", float("nan")))
    return {k: v for k, v in quality.items() if np.isfinite(v)}


def _differs(a: Any, b: Any) -> bool:
    if isinstance(a, (int, float)) and isinstance(b, (int, float)) and not isinstance(a, bool):
        return not math.isclose(float(a), float(b), rel_tol=1e-12, abs_tol=0.0)
    return a != b


def merge_conditions(path: Path, recorded: Any, given, force: bool):
    """The conditions to catalogue: those the joint file records, completed by the options.

    An option that contradicts a value the file records is refused (one line
    naming both values) unless ``force``; then the option wins.

    Parameters
    ----------
    path
        The joint file (named in messages).
    recorded
        The conditions the file records (their dict form), or anything else for none.
    given
        The caller's :class:`jointdb.store.Conditions`.
    force
        Let the caller's values override the file's.

    Returns
    -------
    Conditions
        The file's conditions merged with the caller's, in SI units.

    Raises
    ------
    InputError
        A conflict without ``force``, or invalid conditions in the file.
    """
    from jointdb.store import Conditions

    base = dict(recorded) if isinstance(recorded, dict) else {}
    try:
        stored = Conditions.from_dict(base)
    except InputError as exc:
        raise InputError(f"{path}: the conditions recorded in the file are invalid: {exc}") from None
    conflicts: list[str] = []

    def clash(field: str, option: str, in_file: Any, in_option: Any) -> None:
        conflicts.append(f"{field} = {in_file} but {option} gives {in_option}")

    if given.materials and stored.materials and sorted(given.materials) != sorted(stored.materials):
        clash("materials", "--material", "+".join(stored.materials), "+".join(given.materials))
    for field, option in (("preload_n", "--preload"), ("torque_nm", "--torque")):
        a, b = getattr(stored, field), getattr(given, field)
        if a is not None and b is not None and _differs(a, b):
            clash(field, option, f"{a:g}", f"{b:g}")
    for part, option in (("geometry", "--geometry"), ("extra", "--extra")):
        a_map, b_map = dict(getattr(stored, part)), dict(getattr(given, part))
        for key in sorted(set(a_map) & set(b_map)):
            if _differs(a_map[key], b_map[key]):
                clash(f"{part}.{key}", option, a_map[key], b_map[key])
    if conflicts and not force:
        raise InputError(f"{path} records {'; '.join(conflicts)}: leave the option out to keep the file's value, "
                         "or add --force to store the option's value")
    return Conditions(
        materials=given.materials or stored.materials,
        preload_n=given.preload_n if given.preload_n is not None else stored.preload_n,
        torque_nm=given.torque_nm if given.torque_nm is not None else stored.torque_nm,
        geometry={**dict(stored.geometry), **dict(given.geometry)},
        extra={**dict(stored.extra), **dict(given.extra)},
    )


def catalogue_inputs(joint_file: Path | str, given=None, *, joint_type: str | None = None,
                     model_kind: str | None = None, method: str | None = None,
                     quality: dict[str, float] | None = None, author: str | None = None, force: bool = False,
                     root: Path | str | None = None, source: JointSource | None = None) -> dict[str, Any]:
    """What the catalogue stores from a joint or campaign file (CLI, HTTP service and demo alike).

    Reads the file (:func:`read_joint_file`; or takes the already read ``source``), takes
    model kind, joint type, method, quality and conditions from it, completed by the
    caller's (``given`` :class:`jointdb.store.Conditions` are merged by
    :func:`merge_conditions`), and makes the provenance by the one rule of this module.
    With ``root`` (the HTTP service: an unpacked upload) a campaign file may only name
    files inside that folder.

    Parameters
    ----------
    joint_file
        The joint or campaign file.
    given
        :class:`jointdb.store.Conditions` completing (or, with ``force``, overriding) the file's.
    joint_type, model_kind, method
        Take precedence over what the file records (None: the file's value).
    quality
        Quality numbers to store, merged over the file's.
    author
        The provenance's author.
    force
        As :func:`merge_conditions`.
    root
        Confine a campaign to this folder (an unpacked upload), or None.
    source
        The file already read by :func:`read_joint_file` (it is not read again).

    Returns
    -------
    dict
        The keyword arguments of :meth:`jointdb.store.Repository.catalogue` except
        ``name``, ``parent``, ``label``: ``joint_type``, ``frf``, ``conditions``,
        ``model_kind``, ``provenance``, ``quality``, ``raw_frfs``.

    Raises
    ------
    InputError
        A file without joint type or model kind (and none given), a conflict of
        conditions, or any value the catalogue would refuse.
    """
    from jointdb.io._jsonable import to_jsonable
    from jointdb.store import Conditions, Provenance
    from jointdb.store._types import check_joint_type, check_model_kind

    joint_file = Path(joint_file)
    src = source if source is not None else read_joint_file(joint_file, root)
    meta = src.meta
    kind = model_kind or meta.get("model_kind") or MODEL_KINDS.get(str(meta.get("joint_model")))
    if not kind:
        raise InputError(f"{joint_file}: the file does not say its joint model; give --model-kind")
    jtype = joint_type or meta.get("joint_type")
    if not jtype:
        raise InputError(f"{joint_file}: the file does not say its joint type; give --type")
    q = numeric_metrics(meta.get("quality"))
    own = identification_peak_error(meta.get("quality"))
    if own is not None:  # computed from the file's own peaks: it wins over a flat value of the same name
        q["identification_peak_error"] = own
    f_ref = identification_peak_hz(meta.get("quality"))
    if f_ref is not None:  # where the constant k, c was identified: the band's damping-law term (issue 22)
        q["identification_peak_hz"] = f_ref
    q.update(quality or {})
    params = {k: meta[k] for k in PROVENANCE_PARAMETERS if k in meta}
    file_method = meta.get("method") or (f"irc-{meta['joint_model']}" if meta.get("joint_model") else None)
    prov = Provenance(
        method=method or str(file_method or "imported-file"),
        parameters=json.loads(json.dumps(to_jsonable(params), default=str)),
        input_files=src.input_files,
        author=author or "",
    )
    conditions = merge_conditions(joint_file, meta.get("conditions"), given if given is not None else Conditions(),
                                  force)
    return {"joint_type": check_joint_type(jtype), "frf": src.frf, "conditions": conditions,
            "model_kind": check_model_kind(kind, src.frf), "provenance": prov, "quality": q, "raw_frfs": src.raw}


@dataclass(frozen=True, eq=False)
class CatalogueOutcome:
    """What cataloguing a campaign did.

    Attributes
    ----------
    identified
        The :class:`jointdb.campaign.IdentifyOutcome` (campaign, IRC result, re-coupled and
        rigid assemblies, constant (k, c) fit).
    version
        The stored :class:`jointdb.store.JointVersion`.
    reused
        True when the latest version already held this exact record (nothing written).
    """

    identified: Any
    version: Any
    reused: bool

    @property
    def campaign(self):
        return self.identified.campaign

    def row(self) -> dict[str, Any]:
        """A flat row: joint, conditions, constant (k, c), residuals.

        Returns
        -------
        dict
        """
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


def catalogue_campaign(repo, path: Path | str, author: str | None = None) -> CatalogueOutcome:
    """Identify a campaign's joint (as ``jointdb identify`` does) and store it as a new version (the demo).

    The joint's name is the campaign's ``name``; everything else is :func:`catalogue_inputs`
    (the path ``jointdb catalogue campaign.json`` and ``POST /api/v1/catalogue`` take). If the
    latest version of that joint already holds the same record (same FRF, conditions and
    model kind) nothing is written and that version is returned (``reused``).

    Parameters
    ----------
    repo
        A :class:`jointdb.store.Repository` or :class:`jointdb.client.RemoteRepository`, or a
        database URL / SQLite path (``None``: ``JOINTDB_URL`` or the per-user default).
    path
        The campaign file (``jointdb-campaign/1``, :mod:`jointdb.campaign`).
    author
        Who catalogues (default: ``$JOINTDB_AUTHOR`` or the login).

    Returns
    -------
    CatalogueOutcome

    Raises
    ------
    InputError
        Bad campaign files (naming the field), bad data.
    """
    source = read_joint_file(path)
    args = catalogue_inputs(path, author=author, source=source)
    handle, owned = _open_repo(repo)
    try:
        version, created = handle.catalogue_outcome(source.identified.campaign.name, author=author, **args)
        return CatalogueOutcome(source.identified, version, not created)
    finally:
        if owned:
            handle.close()
