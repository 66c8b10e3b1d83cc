"""Campaign side of the output-error identification and of the quality verdict (issue 13).

``identify`` fits the joint's parameters to the measured assembly FRFs (started from the
per-line IRC estimate), reports them with standard errors and correlations, compares the
dominant peaks of re-coupled and measured assemblies (identification and validation
sets), and writes plain verdict lines.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from jointdb.coupling import (
    IdentificationResult,
    OutputErrorResult,
    fit_joint_matrix,
    fit_n_point_joints,
    fit_planar_joint,
    spring_damper_joint,
)
from jointdb.coupling._kc import KCFit
from jointdb.coupling._propagate import uncertainty_record  # noqa: F401  (re-exported for _run)
from jointdb.coupling._quality import parameter_verdicts, peak_errors, peak_verdicts
from jointdb.frf import FRF

METHODS = ("output-error", "irc")


def method_of(c) -> str:
    """The campaign's identification method: ``options.method``, default output-error (irc for the matrix model)."""
    default = "irc" if c.joint_model == "matrix" else "output-error"
    return str(c.options.get("method", default))


def fit_output_error(c, measured: FRF, subs: Mapping[str, FRF], irc: IdentificationResult,
                     kc: KCFit | None) -> OutputErrorResult:
    """Output-error fit of the campaign's joint model, started from the IRC estimate (constant k, c or K, D, M)."""
    i = c.interface
    band = c.options.get("fit_band")
    band = (float(band[0]), float(band[1])) if band else None
    start = None if kc is None else (np.abs(kc.k), np.abs(kc.c))
    if c.joint_model == "planar":
        return fit_planar_joint(measured, subs[i["a"]], i["a_dofs"][0].node, subs[i["b"]], i["b_dofs"][0].node,
                                int(c.model_options["b_tip"]), translation=i["a_dofs"][0].direction,
                                rotation=i["a_dofs"][1].direction, start=start, band=band)
    if c.joint_model == "n-point":
        return fit_n_point_joints(measured, subs[i["a"]], c.model_options["internal"], i["a_dofs"], subs[i["b"]],
                                  i["b_dofs"], start=start, band=band)
    return fit_joint_matrix(measured, subs, c.model_options["measured"], i["a"], i["a_dofs"], i["b"], i["b_dofs"],
                            band=band)


def joint_from_fit(c, fit: OutputErrorResult, freq: np.ndarray, irc: IdentificationResult) -> IdentificationResult:
    """The IRC result with its joint replaced by the fitted parametric joint (diagnostics kept as the reference)."""
    from dataclasses import replace

    if c.joint_model == "matrix":
        from jointdb.coupling._matrices import receptance_from_matrices

        k, d, m = fit.model.matrices(fit.theta)
        joint = receptance_from_matrices(freq, k + 1j * d, m, list(fit.model.labels))
    else:
        joint = spring_damper_joint(freq, fit.values[0::2], fit.values[1::2], irc.joint.inputs)
    extra = dict(irc.extra)
    extra["irc_joint"] = irc.joint
    return replace(irc, joint=joint, extra=extra, settings={**irc.settings, "method": "output-error"})


def fit_report(fit: OutputErrorResult) -> dict[str, Any]:
    """JSON-able parameters, standard errors, correlation and covariance of an output-error fit."""
    top, a, b = fit.max_correlation()
    return {
        "parameters": fit.table(),
        "correlation": fit.correlation.tolist(),
        "covariance_of_theta": fit.covariance.tolist(),
        "theta": fit.theta.tolist(),
        "theta_is_log": bool(fit.log_parameters),
        "residual_rms": fit.residual_rms,
        "max_correlation": {"value": top, "between": [a, b]},
        "evaluations": fit.nfev,
    }


def entry_peaks(pred: FRF, meas: FRF, n: int = 2) -> list[dict]:
    """Dominant-peak errors of every driving-point entry (or the first entry) of ``pred`` vs ``meas``."""
    vb = meas.block(pred.outputs, pred.inputs)
    pairs = [(r, col) for r, o in enumerate(pred.outputs) for col, i in enumerate(pred.inputs) if o == i]
    out = []
    for r, col in pairs or [(0, 0)]:
        for p in peak_errors(pred.freq, pred.values[:, r, col], vb[:, r, col], n):
            out.append({"entry": f"{pred.outputs[r]}/{pred.inputs[col]}", **p})
    return out


def verdict(fit: OutputErrorResult | None, peaks: list[dict], mean_dev: float, vpeaks: list[dict] | None,
            vmean: float | None) -> list[str]:
    """Plain verdict lines: poorly determined parameters, missed peaks, or one line saying all is well."""
    lines: list[str] = []
    if fit is not None and fit.log_parameters:
        lines += parameter_verdicts(fit.names, fit.relative_std_error(), fit.correlation)
    lines += peak_verdicts(peaks, "re-coupled identification assembly", mean_dev)
    if vpeaks is not None:
        lines += peak_verdicts(vpeaks, "validation assembly (not used in the fit)", vmean)
    if not lines:
        worst = max((abs(p["amplitude_ratio"] - 1) for p in (vpeaks or peaks)), default=0.0)
        se = ""
        if fit is not None and fit.log_parameters:
            rel = fit.relative_std_error()
            k = int(np.argmax(rel))
            se = f"largest standard error {rel[k]:.1%} ({fit.names[k]}); "
        where = "validation" if vpeaks is not None else "identification"
        lines.append(f"OK: {se}dominant peaks of the {where} assembly within {worst:.1%} in amplitude")
    return lines



def kc_of_fit(fit: OutputErrorResult, irc_joint: FRF, irc_kc: KCFit) -> KCFit:
    """The output-error (k, c) as a :class:`KCFit` over the IRC fit's band; ``error`` is the relative
    misfit of the per-line IRC joint against it (how far the line-by-line estimate scatters)."""
    k, c = fit.values[0::2], fit.values[1::2]
    lo, hi = irc_kc.band_hz
    use = (irc_joint.freq >= lo) & (irc_joint.freq <= hi)
    h = np.diagonal(irc_joint.values[use], axis1=1, axis2=2)
    model = 1.0 / (k[None, :] + 1j * (2 * np.pi * irc_joint.freq[use])[:, None] * c[None, :])
    err = np.linalg.norm(h - model, axis=0) / np.linalg.norm(h, axis=0)
    return KCFit(irc_kc.dofs, k, c, err, irc_kc.band_hz)
