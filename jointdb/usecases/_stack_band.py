"""The predictive band of a stack prediction: measurement noise and joint choice, term by term (issue 22).

:func:`prediction_band` samples every interface whose joint carries an error estimate — its fit's
covariance (measurement noise) and, for a queried joint, the leave-one-out joint-choice error
(:mod:`jointdb.store._loo`: whole condition lines left out for an interpolated joint, calibrated by
:data:`jointdb.usecases._stack.LINE_CALIBRATION`; single joints for a nearest one, by ``CHOICE_CALIBRATION``) — plus the
prediction path's own model-form error (:data:`MODEL_FORM_SIGMA`), and couples them all; the draws of a line left out
lean the way its signed error points (:data:`LINE_BIAS`)
(:func:`jointdb.stack._band.tip_band`). :func:`band_terms` also samples each term alone,
to say which one dominates.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from jointdb.errors import InputError

__all__ = ["BandTerms", "prediction_band", "band_terms", "choice_perturbation", "TERMS", "LINE_BIAS"]

#: The error terms a band can carry, in the order they are reported.
TERMS = ("measurement noise", "joint choice", "prediction path")
#: Relative standard error of the prediction path's own tip receptance (model form: three beams joined at two
#: points where a real stack has distributed contact, a holder model, a spindle receptance). Not estimable from
#: the catalogue (each per-line joint reproduces its own campaign): calibrated on the tuning seeds of
#: bench/_stack_truth_b.py, with LINE_CALIBRATION (docs/validation/stack-prediction.md, *Bands*).
MODEL_FORM_SIGMA = 0.02
#: Mean of the joint-choice amplitude of a line left out along an axis, in units of the request's gap ratio (0: a band
#: centred on the interpolated joint; 1: centred on the joint the leave-one-out error extrapolates to, the second-order
#: correction of the interpolation). The catalogue's own line errors have a sign (an axis that bends one way, e.g. a
#: contact stiffness linear in the shank diameter interpolated in ln d, is interpolated too stiff everywhere on it), so
#: the band leans that way. Calibrated with LINE_CALIBRATION on the tuning seeds (docs/validation/stack-prediction.md).
LINE_BIAS = 0.5


def _with_bias(resolution, perturbation):
    """The joint-choice perturbation ``(relative, scale, group)`` with each line point's mean amplitude appended."""
    from jointdb.usecases._stack import LINE_CALIBRATION

    rel, scale, group = perturbation
    lines = np.array([bool(p.axis) for p in resolution.choice_error.points])
    shift = np.where(lines, LINE_BIAS * scale / LINE_CALIBRATION, 0.0)
    return rel, scale, group, shift


def choice_perturbation(resolution, freq):
    """The joint-choice error of one resolved joint as the band samples it, or None.

    Parameters
    ----------
    resolution
        A :class:`jointdb.usecases.JointResolution`.
    freq : ndarray, shape (n_freq,)
        Lines [Hz] of the prediction.

    Returns
    -------
    tuple or None
        ``(relative, scale, group, shift)`` for :func:`jointdb.stack._band.choice_perturbed`: the leave-one-out
        errors on ``freq``, their calibrated spread, axis and mean amplitude (:data:`LINE_BIAS` × the request's
        gap ratio for lines left out, 0 for single joints); None without a joint-choice error.
    """
    if getattr(resolution, "choice_error", None) is None:
        return None
    s = resolution.choice_perturbations(freq)
    return None if s is None else _with_bias(resolution, s)


def _inputs(result, terms=TERMS) -> tuple[dict, dict, list[str]]:
    from jointdb.stack._band import sampleable_uncertainties

    unc, notes = sampleable_uncertainties(result.joints) if "measurement noise" in terms else ({}, [])
    sigma = {}
    if "joint choice" in terms:
        for name, r in result.joints.items():
            s = choice_perturbation(r, result.prediction.tip.freq)
            if s is not None:
                sigma[name] = s
            elif r.kind in ("query", "interpolated") and r.choice_error is None:
                notes.append(f"{name}: no joint-choice error — fewer than 3 catalogued joints of its kind share the "
                             "conditions the query names, so leave-one-out cannot estimate one")
    return unc, sigma, notes


def prediction_band(result, n: int = 200, seed: int = 0, terms=TERMS):
    """``(TipBand or None, notes)`` for a :class:`jointdb.usecases.StackPrediction`.

    Parameters
    ----------
    result
        The prediction with its joint resolutions.
    n, seed
        Ensemble size and seed.
    terms
        Which error terms to sample (:data:`TERMS`).

    Returns
    -------
    (TipBand | None, list[str])
        None (with a note saying why) when no interface carries an error estimate.
    """
    from jointdb.stack._band import tip_band

    unc, sigma, notes = _inputs(result, terms)
    tip_sigma = MODEL_FORM_SIGMA if "prediction path" in terms else 0.0
    queried = any(r.kind in ("query", "interpolated") for r in result.joints.values())
    if not unc and not sigma and not queried and tuple(terms) != ("prediction path",):
        notes.append("no band: no interface joint carries a covariance or a joint-choice error "
                     "(rigid, explicit or pinned joints without an uncertainty record)")
        return None, notes
    resolved = {name: r.frf for name, r in result.joints.items() if r.frf is not None}
    try:
        b = tip_band(result.spec, resolved, unc, result.prediction.tip.freq, n=n, seed=seed, choice=sigma,
                     tip_sigma=tip_sigma)
    except InputError as exc:
        notes.append(f"no band: {exc}")
        return None, notes
    return b, notes


@dataclass(frozen=True, eq=False)
class BandTerms:
    """The band with every term, and with each term alone: ``half_width[term][direction]`` is the relative
    5–95 % half-width of the tip's dominant peak |H|; ``dominant``: the term with the widest band."""

    band: object
    notes: tuple[str, ...]
    half_width: Mapping[str, Mapping[str, float]]

    @property
    def dominant(self) -> str | None:
        alone = {t: max(v.values()) for t, v in self.half_width.items() if t != "all" and v}
        return max(alone, key=alone.get) if alone else None

    def to_json(self) -> dict:
        return {"peak_half_width": {t: dict(v) for t, v in self.half_width.items()}, "dominant_term": self.dominant}


def _half_widths(b) -> dict[str, float]:
    return {d: float((p[2] - p[0]) / 2 / p[1]) for d, p in b.peak.items()} if b is not None else {}


def band_terms(result, n: int = 200, seed: int = 0) -> BandTerms:
    """The full band and each term's own (:class:`BandTerms`)."""
    full, notes = prediction_band(result, n, seed)
    widths = {"all": _half_widths(full)}
    if full is not None:
        for term in TERMS:
            alone, _ = prediction_band(result, n, seed, terms=(term,))
            widths[term] = _half_widths(alone)
    return BandTerms(full, tuple(notes), widths)
