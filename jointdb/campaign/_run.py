"""Run a campaign: identify the joint, or couple with a joint (application layer of the CLI)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from jointdb.campaign._file import (
    Campaign,
    _err,
    file_hashes,
    grid_for_couple,
    load_substructure,
    merge_measurements,
)
from jointdb.coupling import (
    IdentificationResult,
    Interface,
    couple,
    fit_constant_kc,
    identify_joint_matrix,
    identify_n_point_joints,
    identify_planar_joint,
    spring_damper_joint,
)
from jointdb.coupling._kc import KCFit
from jointdb.errors import InputError, NumericalError
from jointdb.frf import FRF, Dof


@dataclass(frozen=True, eq=False)
class IdentifyOutcome:
    """What :func:`identify_campaign` found; ``report()`` gives it as a JSON-ready dict.

    Attributes
    ----------
    campaign
        The :class:`Campaign` identified.
    result
        The IRC :class:`jointdb.coupling.IdentificationResult` (the output-error joint when
        that method was used and kept).
    measured
        The measured assembly FRF on the campaign's band.
    reconstructed
        The assembly re-coupled with the identified joint (same DOFs and lines).
    rigid
        The assembly coupled with rigid joints.
    kc
        Constant (k, c) fitted to the joint (:class:`jointdb.coupling.KCFit`), or None.
    validation
        The joint against the validation assembly (errors, FRFs, peaks), or None.
    output_error
        The :class:`jointdb.coupling.OutputErrorResult` (None for method ``irc``).
    quality
        Peak errors and verdict lines, or None.
    """

    campaign: Campaign
    result: IdentificationResult
    measured: FRF
    reconstructed: FRF
    rigid: FRF
    kc: KCFit | None
    validation: Mapping[str, Any] | None
    output_error: Any = None  # OutputErrorResult of the output-error fit (None for method irc)
    quality: Mapping[str, Any] | None = None  # peak errors and verdict lines

    def report(self) -> dict:
        """The outcome as a JSON-ready dict (joint, errors, constant (k, c), validation, quality).

        Returns
        -------
        dict
        """
        c = self.campaign
        rep: dict[str, Any] = {
            "campaign": c.name,
            "joint_type": c.joint_type,
            "conditions": dict(c.conditions),
            "joint_model": c.joint_model,
            "joint_dofs": [str(d) for d in self.result.joint.inputs],
            **self.result.summary(),
            "reconstruction_error_mean": _mean_rel(self.reconstructed, self.measured),
            "rigid_joint_error_mean": _mean_rel(self.rigid, self.measured),
        }
        if self.kc is not None:
            rep["fit_band_hz"] = list(self.kc.band_hz)
            rep["constant_fit"] = [
                {"dof": str(d), "k": float(k), "c": float(cc), "error": float(e)}
                for d, k, cc, e in zip(self.kc.dofs, self.kc.k, self.kc.c, self.kc.error)
            ]
        if self.validation is not None:
            rep["validation"] = {k: v for k, v in self.validation.items() if not isinstance(v, FRF)}
        if self.output_error is not None:
            from jointdb.campaign._oe import fit_report

            rep["output_error"] = fit_report(self.output_error)
        if self.quality is not None:
            rep.update(self.quality)
        rep["settings"] = {k: (v if not isinstance(v, tuple) else list(v)) for k, v in self.result.settings.items()}
        return rep


def _mean_rel(a: FRF, b: FRF) -> float:
    """Mean over lines and entries of |a − b| / |b| (the thesis's 'mean relative deviation')."""
    vb = b.block(a.outputs, a.inputs)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.abs(a.values - vb) / np.abs(vb)
    return float(np.mean(r[np.isfinite(r)]))


def _pairs(c: Campaign, frf: FRF, subs: Mapping[str, FRF]) -> list[tuple[str, Dof]]:
    """(substructure, DOF) for each measured output/input label, looked up among the substructures."""
    out = []
    for d in dict.fromkeys(list(frf.outputs) + list(frf.inputs)):
        owners = [n for n, s in subs.items() if d in set(s.outputs) | set(s.inputs)]
        if not owners:
            raise _err(c.path, "measurements", f"measured DOF {d} belongs to no substructure")
        out.append((owners[0], d))
    return out


def _interfaces(c: Campaign, joint) -> list[Interface]:
    i = c.interface
    return [Interface(i["a"], i["a_dofs"], i["b"], i["b_dofs"], joint)]


def _couple_like(c: Campaign, subs, joint, like: FRF) -> FRF:
    owner = {d: n for n, d in _pairs(c, like, subs)}
    return couple(subs, _interfaces(c, joint), [(owner[d], d) for d in like.outputs],
                  [(owner[d], d) for d in like.inputs])


def _joint_for_couple(result: IdentificationResult):
    return result.joint_substructure() if result.model == "matrix" else result.joint


def _identify_joint(c: Campaign, measured: FRF, subs: dict) -> IdentificationResult:
    """The campaign's joint model identified from its measurements and substructures (InputError
    naming the campaign file)."""
    i, o = c.interface, c.options
    common = dict(smoothing=o.get("smoothing"), smoothing_order=int(o.get("smoothing_order", 4)))
    try:
        if c.joint_model == "planar":
            res = identify_planar_joint(measured, subs[i["a"]], i["a_dofs"][0].node, subs[i["b"]],
                                        i["b_dofs"][0].node, int(c.model_options["b_tip"]),
                                        translation=i["a_dofs"][0].direction, rotation=i["a_dofs"][1].direction,
                                        **common)
        elif c.joint_model == "n-point":
            res = identify_n_point_joints(measured, subs[i["a"]], c.model_options["internal"], i["a_dofs"],
                                          subs[i["b"]], i["b_dofs"], regularisation=o.get("regularisation"),
                                          diagonal=bool(o.get("diagonal", True)),
                                          symmetrize=bool(o.get("symmetrize", True)), **common)
        else:
            res = identify_joint_matrix(measured, subs, c.model_options["measured"], i["a"], i["a_dofs"],
                                        i["b"], i["b_dofs"], regularisation=o.get("regularisation"),
                                        symmetrize=bool(o.get("symmetrize", True)), **common)
    except InputError as exc:
        raise InputError(f"campaign {c.path.name}: {exc}") from None
    return res


def peak_model_error(peaks) -> float:
    """The substructure model's relative error at the dominant peaks of a validation assembly (issue 22).

    Parameters
    ----------
    peaks
        :func:`jointdb.campaign._oe.entry_peaks` of the predicted against the measured validation assembly
        (each with ``amplitude_ratio`` = predicted / measured peak |H|).

    Returns
    -------
    float
        ``exp(RMS ln ratio) − 1`` over the peaks: 0 when the prediction meets every measured peak, 0.05
        for a model 5 % off at each (either way); NaN without a finite ratio.
    """
    r = np.array([float(p["amplitude_ratio"]) for p in peaks], dtype=float)
    r = r[np.isfinite(r) & (r > 0)]
    return float(np.expm1(np.sqrt(np.mean(np.log(r) ** 2)))) if r.size else float("nan")


def _validate(c: Campaign, subs: dict, joint, freq: np.ndarray) -> dict:
    """The identified joint against the validation assembly (and rigid joints): errors, FRFs, peaks."""
    from jointdb.campaign._oe import entry_peaks

    vmeas = merge_measurements(c.path, "validation.measurements", c.validation["measurements"], c.band)
    if vmeas.freq.shape != freq.shape or not np.allclose(vmeas.freq, freq, rtol=1e-9, atol=1e-9):
        raise _err(c.path, "validation.measurements", "must share the identification measurements' grid")
    vsubs = dict(subs)
    for n, s in c.validation["substructures"].items():
        vsubs[n] = load_substructure(c.path, f"validation.substructures.{n}", s, freq)
    pred = _couple_like(c, vsubs, joint, vmeas)
    vrig = _couple_like(c, vsubs, None, vmeas)
    peaks = entry_peaks(pred, vmeas)
    return {
        "identified_joint_error_mean": _mean_rel(pred, vmeas),
        "rigid_joint_error_mean": _mean_rel(vrig, vmeas),
        "peak_model_error": peak_model_error(peaks),
        "measured": vmeas, "predicted": pred, "rigid": vrig,
        "peaks": peaks,
    }


def _quality(method: str, measured: FRF, reconstructed: FRF, irc_reconstructed, adequacy, oe, validation) -> dict:
    """Peaks of the re-coupled assembly, the model-adequacy check and the verdict lines."""
    from jointdb.campaign._oe import entry_peaks, verdict

    peaks = entry_peaks(reconstructed, measured)
    quality: dict[str, Any] = {"method": method, "peaks": peaks}
    if irc_reconstructed is not None:
        quality["peaks_irc_joint"] = entry_peaks(irc_reconstructed, measured)
    lines = []
    if adequacy is not None:
        quality["model_adequacy"] = adequacy.as_dict()
        lines = [adequacy.verdict()] if adequacy.verdict() else []
    kept_fit = None if adequacy is not None and adequacy.keep_per_line else oe
    quality["verdict"] = lines + verdict(kept_fit, peaks, _mean_rel(reconstructed, measured),
                                         None if validation is None else validation["peaks"],
                                         None if validation is None else validation["identified_joint_error_mean"])
    return quality


def identify_campaign(c: Campaign) -> IdentifyOutcome:
    """Load everything, identify the joint, re-couple, fit constant (k, c), validate if asked.

    Parameters
    ----------
    c
        A campaign from :func:`load_campaign`.

    Returns
    -------
    IdentifyOutcome

    Raises
    ------
    InputError
        With the campaign file and field named, for bad files, DOFs or grids.
    NumericalError
        If the identification is singular.
    """
    measured = merge_measurements(c.path, "measurements", c.measurements, c.band)
    freq = measured.freq
    subs = {n: load_substructure(c.path, f"substructures.{n}", s, freq) for n, s in c.substructures.items()}
    o = c.options
    res = _identify_joint(c, measured, subs)
    from jointdb.campaign._oe import METHODS, entry_peaks, fit_output_error, joint_from_fit, kc_of_fit, method_of

    method = method_of(c)
    if method not in METHODS:
        raise _err(c.path, "options.method", f"{method!r}: use one of {', '.join(METHODS)}")
    kc = None
    if c.joint_model != "matrix":
        band = o.get("fit_band")
        band = (float(band[0]), float(band[1])) if band else None
        kc = fit_constant_kc(res.joint, band, mask=~res.unreliable)
    oe = None
    irc_reconstructed = None
    adequacy = None
    if method == "output-error":
        oe = fit_output_error(c, measured, subs, res, kc)
        kc_irc = kc
        if kc is not None and oe.log_parameters and oe.model.order == 0:
            kc = kc_of_fit(oe, res.joint, kc)
        irc_reconstructed = _couple_like(c, subs, _joint_for_couple(res), measured)
        irc_res = res
        res = joint_from_fit(c, oe, freq, res)
    joint = _joint_for_couple(res)
    reconstructed = _couple_like(c, subs, joint, measured)
    if oe is not None and oe.log_parameters:  # spring–dampers: is constant k, c adequate? (else keep per-line)
        from jointdb.campaign._adequacy import assess_constant_model

        fb = o.get("fit_band")
        use = np.ones(freq.size, bool) if not fb else (freq >= float(fb[0])) & (freq <= float(fb[1]))
        adequacy = assess_constant_model(measured.values[use], reconstructed.values[use],
                                         entry_peaks(reconstructed, measured), entry_peaks(irc_reconstructed, measured))
        if adequacy.keep_per_line:
            from dataclasses import replace as _replace

            res = _replace(irc_res, settings={**irc_res.settings, "method": "irc (constant k, c rejected)"})
            joint, reconstructed, kc = _joint_for_couple(res), irc_reconstructed, kc_irc  # kc: of the kept joint
    rigid = _couple_like(c, subs, None, measured)
    validation = _validate(c, subs, joint, freq) if c.validation is not None else None
    quality = _quality(method, measured, reconstructed, irc_reconstructed, adequacy, oe, validation)
    return IdentifyOutcome(c, res, measured, reconstructed, rigid, kc, validation, oe, quality)


def joint_attrs(out: IdentifyOutcome) -> dict:
    """Metadata stored with the joint FRF in the HDF5 exchange file.

    Parameters
    ----------
    out
        An :class:`IdentifyOutcome`.

    Returns
    -------
    dict
        JSON-ready: kind, joint model, campaign, joint type, conditions, interface, report.
    """
    from jointdb.io._jsonable import to_jsonable

    rep = to_jsonable(out.report())
    method = (out.quality or {}).get("method", "irc")
    per_line = _per_line_kept(out)
    if per_line:
        method = "irc"
    attrs = {
        "kind": "joint",
        "joint_model": out.result.model,
        "campaign": out.campaign.name,
        "joint_type": out.campaign.joint_type,
        "conditions": dict(out.campaign.conditions),
        "interface": {
            "a": out.campaign.interface["a"], "a_dofs": [str(d) for d in out.campaign.interface["a_dofs"]],
            "b": out.campaign.interface["b"], "b_dofs": [str(d) for d in out.campaign.interface["b_dofs"]],
        },
        "quality": {k: v for k, v in rep.items() if k not in ("settings", "conditions", "campaign")},
        "settings": rep["settings"],
        "provenance": {"method": f"{method} {out.result.model} (jointdb.coupling)",
                       "input_sha256": file_hashes(out.campaign)},
        "method": f"{method}-{out.result.model}",
    }
    if out.output_error is not None:
        from jointdb.campaign._oe import uncertainty_record

        attrs["uncertainty"] = uncertainty_record(out.output_error)
        if per_line:  # information only: the catalogued FRF is the per-line joint, not this constant one
            attrs["uncertainty"]["describes_catalogued_joint"] = False
            attrs["provenance"]["method"] += " (output-error constant k, c rejected by the adequacy check)"
    return attrs


def _per_line_kept(out: IdentifyOutcome) -> bool:
    """True when the output-error constant joint was rejected and the per-line IRC joint is catalogued."""
    return ((out.quality or {}).get("model_adequacy") or {}).get("catalogued_joint") == "per-line"


def load_joint_file(path: Path) -> tuple[FRF, str]:
    """A joint FRF written by ``jointdb identify`` and its model kind.

    Parameters
    ----------
    path
        The joint HDF5 file.

    Returns
    -------
    frf : FRF
        The joint receptance.
    model : str
        ``"planar"``, ``"n-point"`` or ``"matrix"``.

    Raises
    ------
    InputError
        Not a joint file written by ``jointdb identify``.
    """
    from jointdb.io import read_frf_hdf5_full

    frf, meta = read_frf_hdf5_full(path)
    model = meta.get("joint_model")
    if model not in ("planar", "n-point", "matrix"):
        raise InputError(f"{path}: not a joint file written by 'jointdb identify' (no joint_model in its metadata)")
    return frf, str(model)


def _couple_dofs(c: Campaign, subs: dict, key: str, raw) -> list[tuple[str, Dof]]:
    """``couple.outputs`` / ``couple.inputs`` as ``(substructure, Dof)`` pairs, each one checked by name."""
    if not isinstance(raw, list) or not raw:
        raise _err(c.path, f"couple.{key}", 'must be a non-empty list of [substructure, DOF] pairs, e.g. [["tool", "1x"]]')
    out = []
    for i, pair in enumerate(raw):
        where = f"couple.{key}[{i}]"
        if not (isinstance(pair, list) and len(pair) == 2 and all(isinstance(v, str) for v in pair)):
            raise _err(c.path, where, f'must be a [substructure, DOF] pair such as ["tool", "1x"], got {pair!r}'[:200])
        name, label = pair
        if name not in subs:
            raise _err(c.path, where, f"unknown substructure {name!r} (have: {', '.join(subs)})")
        try:
            dof = Dof.parse(label)
        except (InputError, ValueError) as exc:
            raise _err(c.path, where, str(exc)) from None
        have = set(subs[name].outputs) | set(subs[name].inputs)
        if dof not in have:
            raise _err(c.path, where, f"substructure {name!r} has no DOF {dof} (it has "
                       f"{' '.join(str(d) for d in sorted(have, key=str))})")
        out.append((name, dof))
    return out


def couple_campaign(c: Campaign, joint_override: Path | None = None) -> dict:
    """Couple the campaign's substructures with a joint; compare with measurements if there are any.

    Parameters
    ----------
    c
        A campaign from :func:`load_campaign`.
    joint_override
        A joint HDF5 file (``jointdb couple --joint FILE``); default the campaign's
        ``couple.joint``: ``"rigid"``, a joint HDF5 file, or ``{"k": [...], "c": [...]}``
        (spring–dampers on the interface's a_dofs).

    Returns
    -------
    dict
        ``assembly`` (coupled FRF), ``joint`` (its label), ``measured`` (or None) and, with a
        measurement to compare with, ``error_mean``, ``peaks`` and ``verdict``.
    """
    freq = grid_for_couple(c)
    subs = {n: load_substructure(c.path, f"substructures.{n}", s, freq) for n, s in c.substructures.items()}
    spec = str(joint_override) if joint_override is not None else c.couple.get("joint", "rigid")
    a_dofs = c.interface["a_dofs"]
    if spec == "rigid":
        joint, label = None, "rigid"
    elif isinstance(spec, dict):
        if "k" not in spec or "c" not in spec:
            raise _err(c.path, "couple.joint", "a spring–damper joint needs \"k\" and \"c\" lists")
        for key in ("k", "c"):
            if len(spec[key]) != len(a_dofs):
                raise _err(c.path, f"couple.joint.{key}", f"has {len(spec[key])} value(s); give one per "
                           f"interface.a_dofs ({' '.join(map(str, a_dofs))})")
        try:
            joint = spring_damper_joint(freq, spec["k"], spec["c"], a_dofs)
        except InputError as exc:
            raise _err(c.path, "couple.joint", str(exc)) from None
        label = "spring-damper"
    else:
        p = Path(spec) if joint_override is not None else (c.path.parent / spec)
        if not p.is_file():
            raise _err(c.path, "couple.joint", f"joint file '{spec}' not found")
        frf, model = load_joint_file(p)
        if frf.freq.shape != freq.shape or not np.allclose(frf.freq, freq, rtol=1e-9, atol=1e-9):
            raise _err(c.path, "couple.joint", f"{p.name} has {frf.n_freq} lines {frf.freq[0]:g}–{frf.freq[-1]:g} Hz, "
                       f"the coupling grid {freq.size} lines {freq[0]:g}–{freq[-1]:g} Hz")
        if model == "matrix":
            from jointdb.coupling import JointSubstructure

            n = len(frf.inputs) // 2
            joint = JointSubstructure(frf, frf.inputs[:n], frf.inputs[n:])
        else:
            joint = frf
        label = p.name
    outs_raw = c.couple.get("outputs")
    measured = merge_measurements(c.path, "measurements", c.measurements, c.band) if c.measurements else None
    if c.couple.get("inputs") and not outs_raw:
        raise _err(c.path, "couple.inputs", "given without couple.outputs; name the outputs too")
    if outs_raw:
        outs = _couple_dofs(c, subs, "outputs", outs_raw)
        ins = _couple_dofs(c, subs, "inputs", c.couple.get("inputs") or outs_raw)
        try:
            g = couple(subs, _interfaces(c, joint), outs, ins)
        except InputError as exc:
            raise InputError(f"campaign {c.path.name}: {exc}") from None
    elif measured is not None:
        g = _couple_like(c, subs, joint, measured)
    else:
        raise _err(c.path, "couple.outputs", "name the outputs to compute (no measurements to copy them from)")
    res: dict[str, Any] = {"assembly": g, "joint": label, "measured": None}
    if measured is not None and all(d in measured.outputs for d in g.outputs) and all(
        d in measured.inputs for d in g.inputs
    ) and np.array_equal(measured.freq, g.freq):
        res["measured"] = measured
        res["error_mean"] = _mean_rel(g, measured)
        from jointdb.campaign._oe import entry_peaks
        from jointdb.coupling._quality import peak_verdicts

        res["peaks"] = entry_peaks(g, measured)
        res["verdict"] = peak_verdicts(res["peaks"], "coupled vs measured", res["error_mean"]) or [
            "OK: dominant peaks within {:.1%} in amplitude of the measurement".format(
                max(abs(p["amplitude_ratio"] - 1) for p in res["peaks"]))]
    return res


__all__ = ["IdentifyOutcome", "identify_campaign", "couple_campaign", "joint_attrs", "load_joint_file",
           "NumericalError"]
