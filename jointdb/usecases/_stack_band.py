"""The predictive band of a stack prediction, term by term (issue 22): measurement noise, joint choice, the position
of the chosen tool–holder joint's features, the damping law of constant joints, the spindle's estimate, the
substructure model and the prediction path.

:func:`prediction_band` samples every interface whose joint carries an error estimate — its fit's
covariance (measurement noise) and, for a queried joint, the leave-one-out joint-choice error
(:mod:`jointdb.store._loo`: whole condition lines left out for an interpolated joint, calibrated by
:data:`jointdb.usecases._stack.LINE_CALIBRATION`; single joints for a nearest one, by ``CHOICE_CALIBRATION``) — plus the
prediction path's own model-form error (:data:`MODEL_FORM_SIGMA`), and couples them all; the draws of a line left out
lean the way its signed error points (:data:`LINE_BIAS`)
(:func:`jointdb.stack._band.tip_band`). A spindle estimated from extension-bar taps carries its estimate's
noise (:mod:`jointdb.stack._spindle_band`); joints whose campaigns recorded a validation assembly (or, for tool–holder
joints, whose own identification assembly the catalogued joint does not give back) carry the substructure model's
error it showed (:func:`model_error`); a tool–holder joint chosen for conditions it was not identified at carries
the dominant peak's sensitivity to where its features sit (:func:`feature_position`); joints kept as constant k, c
carry the unknown law of their loss away from the frequency they were identified at (:func:`damping_laws`).
:func:`band_terms` also samples each term alone, to say which one dominates, and says why a term is 0.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from jointdb.errors import InputError
from jointdb.usecases._stack_edge import band_edge_notes

__all__ = ["BandTerms", "prediction_band", "band_terms", "choice_perturbation", "model_error", "spindle_estimate",
           "absent_terms", "damping_laws", "feature_position", "TERMS", "LINE_BIAS"]

#: The error terms a band can carry, in the order they are reported.
TERMS = ("measurement noise", "joint choice", "feature position", "damping law", "spindle estimate",
         "substructure model", "prediction path")
#: Relative standard error of the prediction path's own tip receptance (model form: three beams joined at two
#: points where a real stack has distributed contact, a holder model, a spindle receptance). Not estimable from
#: the catalogue (each per-line joint reproduces its own campaign): calibrated on the tuning seeds of
#: bench/_stack_truth_b.py, with LINE_CALIBRATION (docs/validation/stack-prediction.md, *Bands*). Halved with ι and λ
#: when the feature-position term came in, it left family B's prediction-path bands at ±2 % against 3–5 % errors
#: (fresh B seeds 42 / 41 of 48 inside); back at 0.02 by a rule written before its runs (fresh B 47 / 46 of 48,
#: family C unchanged in coverage; docs/validation/stack-bands-family-c.md, *the prediction path at 2 % (P2)*).
MODEL_FORM_SIGMA = 0.02
#: Mean of the joint-choice amplitude of a line left out along an axis, in units of the request's gap ratio (0: a band
#: centred on the interpolated joint; 1: centred on the joint the leave-one-out error extrapolates to, the second-order
#: correction of the interpolation). The catalogue's own line errors have a sign (an axis that bends one way, e.g. a
#: contact stiffness linear in the shank diameter interpolated in ln d, is interpolated too stiff everywhere on it), so
#: the band leans that way. Calibrated with LINE_CALIBRATION on the tuning seeds (docs/validation/stack-prediction.md).
LINE_BIAS = 0.5
#: The feature-position term (:func:`feature_position`): the tool–holder joint, when it is chosen for conditions it
#: was not identified at (it carries a joint-choice error), is read at ``f (1 ± FEATURE_POSITION_SHIFT)``, and the RMS
#: change ``s`` of the tip's dominant peak (log units) gives a log-normal tip term of σ = ``FEATURE_POSITION_FACTOR``
#: · s. Only the tool–holder interface: on truth family C, ``s`` from that joint correlates with the |peak error|
#: (ln–ln 0.44 over 288 stacks), from both interfaces' joints only 0.19, and the band built on the latter was wider
#: than without it (docs/validation/stack-bands-family-c.md, *Feature position*).
FEATURE_POSITION_INTERFACES = ("tool-holder",)
#: Relative frequency shift of the joint's features for ``s``: ±3 %, session 11's proxy (its ``s`` correlated with the
#: |peak error|; the factor k absorbs the scale, other shifts were not tried).
FEATURE_POSITION_SHIFT = 0.03
#: Factor ``k`` on ``s`` (with ι and λ halved when the term was introduced, round 3 session 12), by a rule written
#: before the runs: of six (a, k) configurations on family C's 288 seen stacks, the narrowest band keeping ≥ 90 % of
#: peaks and of floors inside that also keeps ≥ 90 % on family B's tuning seeds. k 0.35 was narrower on C (91.7 /
#: 91.0 % inside) but left 43 / 48 of B's floors inside; k 0.5 keeps 94.4 / 93.4 % on C and 47 / 44 of 48 on B
#: (with :data:`MODEL_FORM_SIGMA` back at 0.02: 95.1 / 94.4 % on C at 3.4× / 2.9× the median |error|, 48 / 48 on B;
#: docs/validation/stack-bands-family-c.md, *The feature-position term in the product*).
FEATURE_POSITION_FACTOR = 0.5


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


#: The interface whose campaigns' own identification assemblies are stacks of the kind predicted (a tool in its
#: holder on the spindle, measured at the tool tip): their in-sample dominant-peak error is an error of the
#: predicted quantity itself. A holder–spindle campaign's assembly ends at the holder, and the tool–holder
#: campaigns identified on top of its catalogued joint absorb what it misses at its own peaks (their own
#: assemblies include it), so for that interface only a validation assembly counts.
IDENTIFICATION_TERM_INTERFACES = ("tool-holder",)


#: Factor on a tool–holder version's identification-assembly error before the substructure-model term takes it as
#: σ (validation-assembly errors are taken as they are). That error is one in-sample observation at the mode the kept
#: joint was fitted around (truth family C's campaigns give their own dominant peak back within 3–12 %, the same at
#: zero noise: the model form of a point joint standing for a distributed contact). Checked for coverage on the 288
#: seen stacks of bench/_stack_truth_c.py (bench/stack_model_calibration.py, factors 1 / 0.75 / 0.5 / 0.25: peaks
#: inside 93 / 90 / 85 / 77 % with the linear interpolation, 92 / 88 / 84 / 75 % with the power-law one): the rule
#: written before each run (the smallest factor keeping both peaks and floors ≥ 90 %) kept 1
#: (docs/validation/stack-bands-family-c.md, *The identification term, checked*). Halved to 0.5 with LINE_CALIBRATION
#: when the feature-position term was introduced (:data:`FEATURE_POSITION_FACTOR`): alone it had to cover the stacks
#: whose mode sits on a joint feature, and now that term does.
IDENTIFICATION_CALIBRATION = 0.5

#: The largest peak error the substructure-model term takes from a catalogued record (σ ≤ ln 11): a record's quality
#: can come from an uploaded file, and a value outside [0, MAX_PEAK_ERROR] is no error estimate (left out, said so).
MAX_PEAK_ERROR = 10.0


def usable_peak_error(e) -> bool:
    """Whether a recorded peak error is a finite number in ``[0, MAX_PEAK_ERROR]``."""
    return (isinstance(e, (int, float)) and not isinstance(e, bool) and math.isfinite(e)
            and 0.0 <= e <= MAX_PEAK_ERROR)


def _interface_rows(name: str, r) -> list[tuple[str, float, float | None]]:
    """Per version used, ``(name@version, weight, error or None)``: its validation assembly's error, else (on
    :data:`IDENTIFICATION_TERM_INTERFACES`) its identification assembly's."""
    ident = {j: e for j, _, e in getattr(r, "identification_errors", ())} if name in IDENTIFICATION_TERM_INTERFACES else {}
    return [(j, w, e if e is not None else ident.get(j)) for j, w, e in getattr(r, "validation_errors", ())]


def _interface_errors(name: str, r) -> tuple[list[tuple[str, float, float, bool]], str, list[str]]:
    """``([(name@version, weight, error, from_validation)], source, left_out)``: the rows of :func:`_interface_rows`
    that carry a usable error, whether it is a validation assembly's, where they come from, and the versions whose
    recorded error is not usable."""
    validated = {j for j, _, e in getattr(r, "validation_errors", ()) if e is not None}
    rows = [(j, w, e) for j, w, e in _interface_rows(name, r) if w > 0 and e is not None]
    have = [(j, w, e, j in validated) for j, w, e in rows if usable_peak_error(e)]
    sources = {"validation" if v else "identification" for *_, v in have}
    return (have, " and ".join(f"{s} assemblies" for s in sorted(sources, reverse=True)),
            [j for j, _, e in rows if not usable_peak_error(e)])


def model_error(joints) -> tuple[float, list[str]]:
    """The substructure model's relative error (log units) shown by the campaigns' assemblies, and what it is made of.

    Per interface, the RMS of ``ln(1 + e)`` over the catalogued versions it uses, weighted by their interpolation
    weights, where ``e`` is the error at the dominant peaks of the version's validation assembly (quality
    ``validation_peak_error``: measured against its prediction, not used in the fit) or, without one and on the
    tool–holder interface (:data:`IDENTIFICATION_TERM_INTERFACES`), of its own identification assembly re-coupled
    with the catalogued joint (``identification_peak_error``: in-sample; large where the kept joint model — constant
    k, c, or a per-line joint with masked lines at the peak — does not give back its own campaign), times
    :data:`IDENTIFICATION_CALIBRATION`. Interfaces add independently (root sum of squares).

    Parameters
    ----------
    joints
        Interface → :class:`jointdb.usecases.JointResolution`.

    Returns
    -------
    (float, list[str])
        σ (0 when no joint used carries such an error) and one line per interface that contributes.
    """
    total, parts = 0.0, []
    for name, r in joints.items():
        have, source, bad = _interface_errors(name, r)
        if bad:
            parts.append(f"{name}: peak error of {', '.join(bad)} left out (not a number in 0..{MAX_PEAK_ERROR:g})")
        if not have:
            continue
        wsum = sum(w for _, w, _, _ in have)
        raw = sum(w * np.log1p(e) ** 2 for _, w, e, _ in have) / wsum
        s2 = sum(w * (np.log1p(e) * (1.0 if v else IDENTIFICATION_CALIBRATION)) ** 2 for _, w, e, v in have) / wsum
        total += s2
        taken = ("" if s2 == raw else
                 f"; taken as {np.expm1(np.sqrt(s2)):.1%}, identification errors × {IDENTIFICATION_CALIBRATION:g}")
        parts.append(f"{name}: {source} of {', '.join(j for j, *_ in have)} "
                     f"(peak error {np.expm1(np.sqrt(raw)):.1%}{taken})")
    return float(np.sqrt(total)), parts


def _damping_law(r) -> tuple[tuple[float, float] | None, str]:
    """``((f_ref, share), "")`` of one resolved joint for the damping-law term, or ``(None, why it is 0)``."""
    if r.kind == "explicit":
        return None, "explicit k, c written in the stack: the frequency they were identified at is not known"
    if getattr(r, "constant_fallback", False):
        return None, ("the passivity guard replaced the catalogued joint by its constant k, c fit over a whole band "
                      "(not at one mode): its damping law is not sampled")
    refs = [row for row in getattr(r, "damping_references", ()) if row[1] > 0]
    if not refs:
        return None, "the joint records no catalogued version it was identified from"
    const = [row for row in refs if row[3]]
    if not const:
        return None, ("per-line joint (" + ", ".join(j for j, *_ in refs) + "): no constant k, c fit describes its "
                      "catalogued FRF; its loss is measured line by line over its campaign's band, not assumed "
                      "by a law")
    if len(const) < len(refs):
        return None, ("an interpolation of constant k, c (" + ", ".join(j for j, *_ in const) + ") and per-line ("
                      + ", ".join(j for j, _, _, c in refs if not c) + ") joints: the constant part's loss cannot be "
                      "separated from the interpolated dynamic stiffness, so its law is not sampled")
    missing = [j for j, _, f, _ in const if not (isinstance(f, (int, float)) and math.isfinite(f) and f > 0)]
    if missing:
        return None, (f"constant k, c of {', '.join(missing)} records no identification frequency "
                      "(quality identification_peak_hz; catalogued before it was recorded: catalogue it again)")
    wc = sum(w for _, w, _, _ in const)
    f_ref = math.exp(sum(w * math.log(f) for _, w, f, _ in const) / wc)
    return (f_ref, 1.0), ""


def damping_laws(joints) -> tuple[dict[str, tuple[float, float]], dict[str, str]]:
    """Which joints the damping-law term samples, and why the others do not.

    A joint kept as constant k, c (``Z = K + i 2πf C``, a viscous damper) was fitted to its campaign's
    identification assembly, whose dominant mode (frequency ``f_ref``) fixes its loss there and not its law away
    from it: viscous, hysteretic (``Im Z = η K``) or between (fractional derivative,
    :func:`jointdb.stack._band.damping_law`). Each sample draws the law's exponent β uniform on [0, 1] — the
    campaign at one mode cannot tell the laws apart, so every exponent between the two classical limits is taken
    as equally likely. For an interpolation of constant joints, ``f_ref`` is the interpolation-weighted geometric mean
    of theirs; an interpolation mixing constant and per-line joints is not sampled (said why), nor is a joint the
    passivity guard replaced by its constant fit over a whole band.

    Parameters
    ----------
    joints
        Interface → :class:`jointdb.usecases.JointResolution`.

    Returns
    -------
    (dict, dict)
        Interface → ``(f_ref [Hz], 1.0)`` of the joints sampled; interface → why a joint is not (rigid
        interfaces are in neither).
    """
    laws, why = {}, {}
    for name, r in joints.items():
        if r.kind == "rigid":
            continue
        law, reason = _damping_law(r)
        if law is None:
            why[name] = reason
        else:
            laws[name] = law
    return laws, why


def spindle_estimate(spec):
    """The spindle's extension-bar estimate, if the band can sample it.

    Parameters
    ----------
    spec
        A :class:`jointdb.stack.StackSpec`.

    Returns
    -------
    (SpindleEstimate or None, str)
        The :class:`jointdb.stack._spindle_band.SpindleEstimate` and ``""``, or None and the reason the
        spindle-estimate term is 0.
    """
    from jointdb.stack._spindle_band import SpindleEstimate

    est = getattr(spec.spindle, "estimate", None)
    if isinstance(est, dict):
        return None, "the spindle's extension-bar taps are named but were not read (load the stack from its file)"
    if not isinstance(est, SpindleEstimate):
        return None, ("the spindle is taken as exact (a model, or a measured receptance that names no "
                      "extension-bar taps it was estimated from)")
    frf = getattr(spec.spindle, "frf", None)
    if frf is not None and any(d.direction in ("y", "rx") for d in frf.outputs):
        return None, ("the spindle is measured in both bending planes; its extension-bar estimate describes one "
                      "plane and is not sampled")
    return est, ""


def absent_terms(result, feature_sigma: float | None = None) -> dict[str, str]:
    """The terms that are 0 for a prediction, and why.

    Parameters
    ----------
    result
        A :class:`jointdb.usecases.StackPrediction`.
    feature_sigma
        The feature-position term's σ if already computed (:func:`feature_position`); None: only whether a joint
        it would shift is used is checked.

    Returns
    -------
    dict[str, str]
        Term (of :data:`TERMS`) → the reason it is 0; terms not named carry an error estimate.
    """
    from jointdb.stack._band import sampleable_uncertainties

    out = {}
    if not sampleable_uncertainties(result.joints)[0]:
        out["measurement noise"] = "no joint used carries a sampleable fit covariance"
    if not any(choice_perturbation(r, result.prediction.tip.freq) is not None for r in result.joints.values()):
        out["joint choice"] = "every joint is pinned, rigid, explicit or on a catalogued condition"
    if not _feature_interfaces(result.joints, result.prediction.tip.freq):
        out["feature position"] = ("no per-line " + " or ".join(FEATURE_POSITION_INTERFACES) + " joint is chosen for "
                                   "conditions it was not identified at (a catalogued condition's joint has its "
                                   "features where its own campaign put them; a constant k, c joint has none)")
    elif feature_sigma == 0:
        out["feature position"] = ("the tip's dominant peak does not move when the chosen joint's features are "
                                   f"shifted by ±{FEATURE_POSITION_SHIFT:.0%}")
    laws, why_not = damping_laws(result.joints)
    if not laws:
        out["damping law"] = ("; ".join(f"{k}: {v}" for k, v in why_not.items())
                              or "no catalogued joint is used (rigid interfaces)")
    est, why = spindle_estimate(result.spec)
    if est is None:
        out["spindle estimate"] = why
    if model_error(result.joints)[0] == 0:
        shown = any(e is not None for name, r in result.joints.items() for _, _, e in _interface_rows(name, r))
        out["substructure model"] = ("the assemblies of the joints used show no error at their dominant peaks" if shown
                                     else "no campaign of the catalogued joints used recorded a validation assembly, "
                                     "and no tool–holder joint used records its identification assembly's peak error")
    return out


def _has_features(r) -> bool:
    """Whether a resolved joint is (or interpolates) a per-line catalogued joint: a constant k, c joint has no
    features to misplace (read at ``f (1 ± δ)`` it would only change its viscous loss by ±δ), nor has a joint the
    passivity guard replaced by its constant fit."""
    if getattr(r, "constant_fallback", False):
        return False
    return any(not const for _, w, _, const in getattr(r, "damping_references", ()) if w > 0)


def _feature_interfaces(joints, freq) -> list[str]:
    """The interfaces of :data:`FEATURE_POSITION_INTERFACES` whose joint carries a joint-choice error on ``freq`` and
    uses a per-line catalogued joint (:func:`_has_features`)."""
    return [k for k in FEATURE_POSITION_INTERFACES if k in joints and _has_features(joints[k])
            and choice_perturbation(joints[k], freq) is not None]


def feature_position(spec, joints, tip) -> tuple[float, list[str]]:
    """The feature-position term's σ (log units) for a prediction, and what it is made of.

    The tool–holder joint chosen for conditions it was not identified at (:data:`FEATURE_POSITION_INTERFACES`,
    those with a joint-choice error), when it is or interpolates a per-line catalogued joint, is read at
    ``f (1 ± FEATURE_POSITION_SHIFT)``; ``s``, the RMS change of the tip's dominant peak in log units
    (:func:`jointdb.stack._feature.peak_shift_sensitivity`, the larger of the two bending planes), gives
    σ = :data:`FEATURE_POSITION_FACTOR` · s. A per-line joint interpolated between catalogued conditions cannot place
    the features the real joint has where it absorbs its campaign's dynamics; a stack whose mode sits on one errs by
    its sensitivity to where they are, one that does not barely moves (docs/stacks.md, *Bands*, term 3).

    Parameters
    ----------
    spec
        The stack (:class:`jointdb.stack.StackSpec`).
    joints
        Interface → :class:`jointdb.usecases.JointResolution` of the prediction.
    tip
        The prediction's tip receptance over (1x, 1y) (its lines are the prediction's).

    Returns
    -------
    (float, list[str])
        σ (0 when no such joint is used) and one line saying how far the peak moved.
    """
    from jointdb.stack._feature import peak_shift_sensitivity

    names = _feature_interfaces(joints, tip.freq)
    if not names:
        return 0.0, []
    resolved = {k: r.frf for k, r in joints.items() if r.frf is not None}
    s = peak_shift_sensitivity(spec, resolved, tip, names, FEATURE_POSITION_SHIFT)
    worst = max(s, key=s.get)
    sigma = FEATURE_POSITION_FACTOR * s[worst]
    return sigma, [f"{', '.join(names)}: the joint read at f (1 ± {FEATURE_POSITION_SHIFT:.0%}) moves the tip's "
                   f"dominant peak by {np.expm1(s[worst]):.1%} RMS ({worst}); feature-position σ "
                   f"{FEATURE_POSITION_FACTOR:g} × that"]


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


def prediction_band(result, n: int = 200, seed: int = 0, terms=TERMS, feature_sigma: float | None = None):
    """``(TipBand or None, notes)`` for a :class:`jointdb.usecases.StackPrediction`.

    Parameters
    ----------
    result
        The prediction with its joint resolutions.
    n, seed
        Ensemble size and seed.
    terms
        Which error terms to sample (:data:`TERMS`).
    feature_sigma
        The feature-position term's σ if already computed (:func:`feature_position`: two more predictions);
        None: computed here when ``terms`` holds it.

    Returns
    -------
    (TipBand | None, list[str])
        None (with a note saying why) when no interface carries an error estimate.
    """
    from jointdb.stack._band import tip_band

    unc, sigma, notes = _inputs(result, terms)
    tip_sigma = MODEL_FORM_SIGMA if "prediction path" in terms else 0.0
    est = spindle_estimate(result.spec)[0] if "spindle estimate" in terms else None
    m_sigma = model_error(result.joints)[0] if "substructure model" in terms else 0.0
    if "feature position" not in terms:
        feature_sigma = 0.0
    elif feature_sigma is None:
        feature_sigma = feature_position(result.spec, result.joints, result.prediction.tip)[0]
    laws = damping_laws(result.joints)[0] if "damping law" in terms else {}
    queried = any(r.kind in ("query", "interpolated") for r in result.joints.values())
    if (not unc and not sigma and not queried and est is None and m_sigma == 0 and feature_sigma == 0 and not laws
            and tuple(terms) != ("prediction path",)):
        notes.append("no band: no interface joint carries a covariance or a joint-choice error "
                     "(rigid, explicit or pinned joints without an uncertainty record)")
        return None, notes
    resolved = {name: r.frf for name, r in result.joints.items() if r.frf is not None}
    try:
        b = tip_band(result.spec, resolved, unc, result.prediction.tip.freq, n=n, seed=seed, choice=sigma,
                     tip_sigma=tip_sigma, spindle_estimate=est, model_sigma=m_sigma, damping=laws,
                     feature_sigma=feature_sigma)
    except InputError as exc:
        notes.append(f"no band: {exc}")
        return None, notes
    return b, notes


@dataclass(frozen=True, eq=False)
class BandTerms:
    """The band with every term, and with each term alone: ``half_width[term][direction]`` is the relative
    5–95 % half-width of the tip's dominant peak |H|; ``dominant``: the term with the widest band;
    ``zero``: term → why it is 0 (a term not sampled for this prediction); ``grid_edge``: the notes (also in
    ``notes``) saying the band's dominant |H| reaches the first or last line predicted
    (:func:`jointdb.usecases._stack_edge.band_edge_notes`)."""

    band: object
    notes: tuple[str, ...]
    half_width: Mapping[str, Mapping[str, float]]
    zero: Mapping[str, str] = None
    grid_edge: tuple[str, ...] = ()

    def term_rows(self) -> list[dict]:
        """One row per term of :data:`TERMS`: its peak half-width alone per direction (0 when absent) and why."""
        zero = self.zero or {}
        return [{"term": t, "peak_half_width": dict(self.half_width.get(t) or {}),
                 "zero_because": zero.get(t)} for t in TERMS]

    @property
    def dominant(self) -> str | None:
        alone = {t: max(v.values()) for t, v in self.half_width.items() if t != "all" and v}
        return max(alone, key=alone.get) if alone else None

    def to_json(self) -> dict:
        return {"peak_half_width": {t: dict(v) for t, v in self.half_width.items()}, "dominant_term": self.dominant,
                "terms": self.term_rows(), "grid_edge": list(self.grid_edge)}


def _half_widths(b) -> dict[str, float]:
    return {d: float((p[2] - p[0]) / 2 / p[1]) for d, p in b.peak.items()} if b is not None else {}


def band_terms(result, n: int = 200, seed: int = 0) -> BandTerms:
    """The full band and each term's own (:class:`BandTerms`)."""
    feature_sigma, feature_notes = feature_position(result.spec, result.joints, result.prediction.tip)
    full, notes = prediction_band(result, n, seed, feature_sigma=feature_sigma)
    widths = {"all": _half_widths(full)}
    zero = absent_terms(result, feature_sigma)
    for term in TERMS:
        if term in zero or full is None:
            widths[term] = {}
            continue
        alone, _ = prediction_band(result, n, seed, terms=(term,), feature_sigma=feature_sigma)
        widths[term] = _half_widths(alone)
    notes += feature_notes + model_error(result.joints)[1]
    laws, why_not = damping_laws(result.joints)
    notes += [f"{k}: damping law sampled between viscous and hysteretic about f_ref {f:.4g} Hz"
              + (f" (constant joints' interpolation weight {w:.2f})" if w < 1 else "") for k, (f, w) in laws.items()]
    if laws:
        notes += [f"{k}: damping law not sampled — {v}" for k, v in why_not.items()]
    edge = band_edge_notes(full, result.prediction.tip)
    return BandTerms(full, (*notes, *edge), widths, zero, edge)
