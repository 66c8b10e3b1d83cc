"""Resolve a stack's joints against the catalogue and predict its tool-tip FRF (docs/theory.md §4)."""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from jointdb.errors import NotFoundError
from jointdb.frf import FRF
from jointdb.stack import INTERFACE_NAMES, Prediction, StackSpec, predict_tool_tip, prediction_grid
from jointdb.usecases._files import load_stack
from jointdb.usecases._stack_shank import shank_inertia

#: How many nearest catalogued joints a stack's interpolated query ranks before the interpolation picks the
#: ones that bracket the request along the condition axes (jointdb.store._interp).
INTERPOLATION_POOL = 64
#: The joint-choice error of the band is the leave-one-out error model (jointdb.store._loo) times a factor.
#: Single joints left out, scaled by distance (a query without interpolation, an axis the catalogue never varied):
#: this one. Calibrated for coverage on the tuning seeds of bench/_stack_truth_b.py (docs/validation/
#: stack-prediction.md, *Bands*): leaving a joint out doubles the local grid spacing, while the straight-line model
#: is fitted through the origin.
CHOICE_CALIBRATION = 0.08
#: Whole condition lines left out, scaled by the request's gap product over theirs (an interpolated request): this
#: one. The model is second order, so 1 is the uncalibrated estimate; 0.5 was set on family B's tuning seeds, halved
#: to 0.25 when the band's feature-position term took over the stacks that err most (round 3 session 12,
#: jointdb.usecases._stack_band.FEATURE_POSITION_FACTOR; docs/validation/stack-bands-family-c.md).
LINE_CALIBRATION = 0.25

#: How a queried joint was chosen (the wording of docs/stacks.md): the nearest catalogued joint, an
#: interpolation between the joints whose conditions bracket the request (a simplex of the catalogued grid),
#: the catalogued edge nearest a request outside the catalogue, or exactly a catalogued condition.
METHODS = ("pinned", "nearest", "simplex interpolation", "edge", "catalogued condition")

# ------------------------------------------------------------------ joints
@dataclass(frozen=True, eq=False)
class JointResolution:
    """How one interface's joint was chosen.

    Attributes
    ----------
    interface
        ``"tool-holder"`` or ``"holder-spindle"``.
    kind
        ``rigid``, ``explicit``, ``catalogued``, ``query`` or ``interpolated``.
    frf
        The joint receptance (None for a rigid joint).
    name, version
        The catalogued joint used (database joints).
    distance
        Its distance to the request (0 for a pinned joint).
    per_condition
        The distance's terms by condition.
    extrapolating, outside_range
        Whether the request lies outside the catalogued range, and of which conditions.
    candidates
        The nearest versions considered, ``(name, version, distance)``.
    warnings
        Messages for the user.
    description
        One line saying what was used.
    uncertainty
        The version's parameter covariance, if it was fitted with one.
    method
        How a database joint was chosen, one of ``METHODS`` (``pinned``, ``nearest``, ``simplex
        interpolation``, ``edge``, ``catalogued condition``); empty otherwise.
    neighbours
        The catalogued versions used, ``(name, version, weight, distance)``: weight 1 for a single
        joint, the interpolation weights otherwise; empty for a rigid or explicit joint.
    choice_error
        The leave-one-out joint-choice error model of a queried joint
        (:class:`jointdb.store._loo.ChoiceErrorModel`), or None when the pool allows none.
    validation_errors
        Per catalogued version used, ``(name@version, weight, error)``: ``error`` is the relative error at the
        dominant peaks of its campaign's validation assembly (quality ``validation_peak_error``), None without one.
    identification_errors
        Per catalogued version used, ``(name@version, weight, error)``: the relative error at the dominant peaks of
        its campaign's own identification assembly re-coupled with the catalogued joint (quality
        ``identification_peak_error``, in-sample), None for a version catalogued without it.
    damping_references
        Per catalogued version used, ``(name@version, weight, f_ref, constant)``: ``f_ref`` [Hz] the frequency of
        the dominant peak of its campaign's identification assembly (quality ``identification_peak_hz``, None for a
        version catalogued without it), ``constant`` whether its catalogued FRF is the constant k, c of an
        output-error fit (its fit covariance describes it) rather than a per-line joint.
    constant_fallback
        True when the passivity guard (:mod:`jointdb.usecases._stack_guard`) replaced the joint's FRF by its constant
        k, c fit over a whole band (everywhere or near a spurious peak).
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
    method: str = ""  # one of METHODS for database joints
    neighbours: tuple[tuple[str, int, float, float], ...] = ()  # (name, version, weight, distance) used
    choice_error: Any = None  # jointdb.store._loo.ChoiceErrorModel of a queried joint, if the pool allows one
    validation_errors: tuple[tuple[str, float, float | None], ...] = ()  # (name@version, weight, peak error)
    identification_errors: tuple[tuple[str, float, float | None], ...] = ()  # the same, identification assembly
    damping_references: tuple[tuple[str, float, float | None, bool], ...] = ()  # (name@version, weight, f_ref, const.)
    constant_fallback: bool = False  # the passivity guard replaced its FRF by a constant k, c fit over a whole band

    def choice_perturbations(self, freq):
        """``(relative, scale)`` of the joint-choice error on ``freq`` over (x, θ), calibrated
        (:meth:`jointdb.store._loo.ChoiceErrorModel.on_grid`), or None.

        Parameters
        ----------
        freq : ndarray, shape (n_freq,)
            Frequency lines [Hz] of the prediction.

        Returns
        -------
        tuple or None
            ``(relative, scale, group)``: ``relative`` ``(m, n_freq, 2, 2)`` complex: each left-out joint's
            relative error of the dynamic stiffness, DOFs in the order (x, θ); ``scale`` ``(m,)``: the
            request's gap (or distance) over that joint's, times ``LINE_CALIBRATION`` (``CHOICE_CALIBRATION``);
            ``group`` ``(m,)``: the
            condition axis of each error (independent draws per axis). None without an error model, for a joint of
            other than two DOFs, or a request on a catalogued condition (distance 0).
        """
        m = self.choice_error
        if m is None or len(m.dofs) != 2 or m.distance <= 0:
            return None
        order = [0, 1] if m.dofs[0].endswith("x") else [1, 0]
        rel, scale, group = m.on_grid(freq, order)
        cal = np.array([LINE_CALIBRATION if p.axis else CHOICE_CALIBRATION for p in m.points])
        return rel, cal * scale, group

    def row(self) -> dict[str, Any]:
        """A flat row for tables / JSON.

        Returns
        -------
        dict
        """
        return {
            "interface": self.interface,
            "kind": self.kind,
            "method": self.method or self.kind,
            "joint": f"{self.name}@{self.version}" if self.name else self.description,
            "distance": self.distance,
            "per_condition": ", ".join(f"{k}={v:.3g}" for k, v in self.per_condition.items()) or None,
            "extrapolating": self.extrapolating,
            "outside_range": list(self.outside_range),
            "joints_used": [{"joint": f"{n}@{v}", "weight": w, "distance": d} for n, v, w, d in self.neighbours],
            "choice_error": None if self.choice_error is None else {
                "request_distance": self.choice_error.distance,
                "request_gap_by_axis": dict(getattr(self.choice_error, "gaps", {}) or {}),
                "stiffness_error_by_dof": dict(zip(self.choice_error.dofs, self.choice_error.sigma[:, 0].tolist())),
                "damping_error_by_dof": dict(zip(self.choice_error.dofs, self.choice_error.sigma[:, 1].tolist())),
                "leave_one_out_joints": [f"{p.name}@{p.version}" for p in self.choice_error.points],
                "calibration": {"lines": LINE_CALIBRATION, "single_joints": CHOICE_CALIBRATION}},
            "validation_peak_error": [{"joint": j, "weight": w, "error": e} for j, w, e in self.validation_errors],
            "identification_peak_error": [{"joint": j, "weight": w, "error": e}
                                          for j, w, e in self.identification_errors],
            "damping_reference": [{"joint": j, "weight": w, "identification_peak_hz": f, "constant_kc": c}
                                  for j, w, f, c in self.damping_references],
            "warnings": "; ".join(self.warnings) or None,
        }


def _open_repo(repo_or_url):
    """``(store, owned)``: a store as given, or one opened on a server address, database URL or path
    (``None``: the default) by :func:`jointdb.store.open_store`, which the caller closes."""
    from jointdb.store import open_store

    store = open_store(repo_or_url)
    return store, store is not repo_or_url


def _uncertainty_of(version) -> Mapping[str, Any] | None:
    """The parameter covariance a catalogued version carries in its provenance (None if it has none)."""
    params = getattr(getattr(version, "provenance", None), "parameters", None) or {}
    unc = params.get("uncertainty") if isinstance(params, Mapping) else None
    return unc if isinstance(unc, Mapping) else None


def _validation_errors(versions_weights, key: str = "validation_peak_error") -> tuple[tuple[str, float, float | None], ...]:
    """``(name@version, weight, quality[key] or None)`` of the catalogued versions a joint uses (``key``: the
    validation or the identification assembly's dominant-peak error)."""
    out = []
    for v, w in versions_weights:
        e = (getattr(v, "quality", None) or {}).get(key)
        out.append((f"{v.name}@{v.version}", float(w), None if e is None else float(e)))
    return tuple(out)


def _peak_errors(versions_weights) -> dict[str, tuple]:
    """The ``validation_errors``, ``identification_errors`` and ``damping_references`` fields of a resolution using
    these versions."""
    pairs = list(versions_weights)
    hz = _validation_errors(pairs, "identification_peak_hz")
    return {"validation_errors": _validation_errors(pairs),
            "identification_errors": _validation_errors(pairs, "identification_peak_error"),
            "damping_references": tuple((j, w, f, _is_constant_kc(v)) for (j, w, f), (v, _) in zip(hz, pairs))}


def _is_constant_kc(version) -> bool:
    """Whether a catalogued version's FRF is a constant spring–damper: its provenance carries the output-error fit's
    covariance of constant k, c and that fit is the catalogued joint (not information beside a per-line joint). A
    full-matrix model (``K + iD − ω²M``: structural damping ``D`` already), a joint body or a spring–damper whose
    log k(f), log c(f) are fitted polynomials (``order > 0``: its law is fitted) is not one."""
    unc = _uncertainty_of(version)
    if unc is None or getattr(version, "model_kind", None) == "full-matrix":
        return False
    try:
        order = int(unc.get("order", 0) or 0)
    except (TypeError, ValueError):
        return False
    # a frequency-dependent k(f), c(f) (order > 0) has its law fitted already; a joint body (K + iD - w^2 M) is
    # hysteretic already
    return (unc.get("model", "spring-damper") == "spring-damper" and order == 0
            and unc.get("describes_catalogued_joint", True) is not False)


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

    Returns
    -------
    dict
        Interface name → :class:`JointResolution`.

    Raises
    ------
    NotFoundError
        A pinned joint/version that does not exist, or no catalogued joint of the queried type.
    """
    from jointdb.store import Conditions

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
                                            uncertainty=_uncertainty_of(jv), method="pinned",
                                            neighbours=((jv.name, jv.version, 1.0, 0.0),),
                                            **_peak_errors([(jv, 1.0)]))
                continue
            conditions = Conditions.from_dict(dict(choice.conditions or {}))
            matches, texts = _pool(handle, choice, conditions)
            added = _stack_conditions(spec, choice.joint_type, conditions, matches)
            if added is not None:  # the catalogue records the insertion length: the stack's is a condition
                conditions = added
                matches, texts = _pool(handle, choice, conditions)
                texts += (f"note: the stack's insertion length {spec.insertion_length * 1e3:.4g} mm is a condition "
                          "of the query (geometry.insertion_m, recorded by the catalogued joints)",)
            if not matches:
                raise NotFoundError(f"interfaces.{name}: no catalogued joint of type {choice.joint_type!r}")
            shank = shank_inertia(spec) if choice.joint_type == "tool-holder" else None
            out[name] = _queried(name, choice, handle, matches, conditions, texts, shank)
    finally:
        if owned and handle is not None:
            handle.close()
    return out


#: The note of an interpolated tool–holder joint whose catalogued shanks' inertia was exchanged for the stack's.
SHANK_NOTE = ("note: the interpolated joint carries the stack's own inserted shank (its mass and inertia about the "
              "holder face) instead of the mix of the catalogued joints' shanks (docs/stacks.md, *The shank inside "
              "the holder*)")


#: Conditions a stack supplies to a query of a joint type when the query leaves them out and the catalogued joints
#: of that type record them: the tool's insertion (clamping) length in the holder bore.
STACK_CONDITIONS = {"tool-holder": {"insertion_m": lambda spec: spec.insertion_length}}


def _stack_conditions(spec, joint_type, conditions, matches):
    """``conditions`` with the stack's own geometry added (:data:`STACK_CONDITIONS`) where the query leaves
    it out and some catalogued joint records it; None when nothing is added."""
    from jointdb.store import Conditions

    extra = {}
    for key, value_of in STACK_CONDITIONS.get(joint_type, {}).items():
        if key in conditions.geometry or not any(key in (m.version.conditions.geometry or {}) for m in matches):
            continue
        extra[key] = float(value_of(spec))
    if not extra:
        return None
    return Conditions(conditions.materials, conditions.preload_n, conditions.torque_nm,
                      {**conditions.geometry, **extra}, conditions.extra)


def _pool(handle, choice, conditions):
    """``(matches, warning texts)`` of a query: the nearest joints and, beyond the ``neighbours`` nearest, the
    pool of joints they can be mixed with (interpolation picks the joints bracketing the request along the
    condition axes, and the joint-choice error is estimated by leave-one-out: both need the catalogued grid
    around the request)."""
    from jointdb.store import OutsideCatalogueWarning, UnvariedConditionWarning

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", OutsideCatalogueWarning)
        warnings.simplefilter("always", UnvariedConditionWarning)
        matches = handle.nearest(choice.joint_type, conditions, k=max(choice.neighbours, INTERPOLATION_POOL))
        if len(matches) > choice.neighbours:
            kind, dofs = matches[0].version.model_kind, tuple(matches[0].version.dofs)
            matches = matches[:choice.neighbours] + [
                m for m in matches[choice.neighbours:]
                if m.version.model_kind == kind and tuple(m.version.dofs) == dofs]
    texts = tuple(str(w.message) for w in caught if issubclass(w.category, OutsideCatalogueWarning))
    texts += tuple(f"note: {w.message}" for w in caught if issubclass(w.category, UnvariedConditionWarning))
    return matches, texts


def _choice_error(handle, pool, conditions, interpolate: bool, shank=None):
    """The leave-one-out joint-choice error model of a query (None when the pool has too few joints); an
    interpolated tool–holder query's leave-one-out exchanges the shanks' inertia as its prediction does
    (``shank``: :class:`jointdb.usecases._stack_shank.ShankInertia`)."""
    from jointdb.store._loo import choice_error_model, leave_one_out, line_error_model, pool_distances

    first = pool[0].version
    pool = [m for m in pool if m.version.model_kind == first.model_kind and tuple(m.version.dofs) == tuple(first.dofs)]
    here = pool_distances(pool, conditions)
    nearest = min(here, key=lambda m: m.distance)
    if interpolate:  # whole condition lines left out and interpolated across the gap, as the request is
        return line_error_model(handle.load_frf, pool, conditions, nearest.distance, first.dofs,
                                inside=not nearest.extrapolating, inertia=None if shank is None else shank.of)
    points = leave_one_out(handle.load_frf, pool, conditions, "nearest")
    return choice_error_model(points, nearest.distance, first.dofs, inside=not nearest.extrapolating)


def _passivity_notes(joint) -> tuple[str, ...]:
    """One note naming the neighbours whose non-passive lines the interpolation left out (``passivity_moved``)."""
    moved = getattr(joint, "passivity_moved", ()) or ()
    if not moved:
        return ()
    each = ", ".join(f"{n}@{v} on {k}" for n, v, k in moved)
    return ("note: where the weighted average would be non-passive (Im Z < 0) the interpolation takes the loss "
            f"from the passive neighbours only ({each} of {joint.frf.n_freq} lines)",)


def _queried(name, choice, handle, matches, conditions, texts, shank=None) -> JointResolution:
    """The resolution of a queried interface: nearest or interpolated joint, with the joints used and the
    joint-choice error model; an interpolated tool–holder joint takes the stack's shank inertia (``shank``,
    :mod:`jointdb.usecases._stack_shank`)."""
    best = matches[0]
    cands = tuple((m.version.name, m.version.version, float(m.distance)) for m in matches[:choice.neighbours])
    dist = {(m.version.name, m.version.version): float(m.distance) for m in matches}
    common = dict(per_condition=dict(best.per_condition), extrapolating=bool(best.extrapolating),
                  outside_range=tuple(best.outside_range), candidates=cands, warnings=texts,
                  choice_error=_choice_error(handle, matches, conditions, choice.interpolate, shank))
    if choice.interpolate and len(matches) > 1:
        joint = handle.interpolate(matches, conditions)
        used = tuple((n, v, float(w), dist.get((n, v), float("nan"))) for n, v, w in joint.neighbours)
        by_key = {(m.version.name, m.version.version): m.version for m in matches}
        frf, shank_note = joint.frf, ()
        if shank is not None and all((n, v) in by_key for n, v, _ in joint.neighbours):
            frf, moved = shank.moved(joint.frf, [(w, by_key[(n, v)].conditions) for n, v, w in joint.neighbours])
            shank_note = (SHANK_NOTE,) if moved else ()
        val = _peak_errors([(by_key[(n, v)], w) for n, v, w, _ in used if (n, v) in by_key])
        method = ("edge" if best.extrapolating else
                  "catalogued condition" if len(used) == 1 and used[0][3] <= 1e-12 else "simplex interpolation")
        common["warnings"] = (*texts, *_passivity_notes(joint), *shank_note)
        return JointResolution(name, "interpolated", frf, best.version.name, best.version.version,
                               float(best.distance), description=joint.describe(), method=method,
                               neighbours=used, **val, **common)
    method = "edge" if best.extrapolating else "nearest"
    return JointResolution(name, "query", handle.load_frf(best.version), best.version.name, best.version.version,
                           float(best.distance), description=choice.reference,
                           uncertainty=_uncertainty_of(best.version),
                           method=method, neighbours=((best.version.name, best.version.version, 1.0,
                                                       float(best.distance)),),
                           **_peak_errors([(best.version, 1.0)]), **common)


@dataclass(frozen=True, eq=False)
class StackPrediction:
    """A prediction with the record of how each joint was resolved.

    Attributes
    ----------
    spec
        The stack.
    prediction
        The :class:`jointdb.stack.Prediction` (tool-tip FRF with and without joints).
    joints
        Interface → :class:`JointResolution`.
    """

    spec: StackSpec
    prediction: Prediction
    joints: Mapping[str, JointResolution]


def predict_with_joints(spec: StackSpec, joints: Mapping[str, JointResolution], freq=None) -> StackPrediction:
    """Predict a stack's tool-tip FRF with joints already resolved (:func:`resolve_joints`).

    A prediction whose dominant tip peak is not passive (a negatively damped resonance from a per-line joint)
    is predicted again with constant k, c joints (:func:`jointdb.usecases._stack_guard.guarded`); the replaced
    joints' resolutions say so. A largest tip |H| on the first or last line adds a note to the prediction's
    ``notes`` (a mode may lie outside the lines: :func:`jointdb.usecases._stack_edge.tip_edge_notes`).

    Parameters
    ----------
    spec
        The stack.
    joints
        Interface -> :class:`JointResolution`; rigid / explicit ones carry no FRF.
    freq
        Frequency lines [Hz], shape ``(n_freq,)`` (default: the stack's grid,
        :func:`jointdb.stack.prediction_grid`).

    Returns
    -------
    StackPrediction
    """
    from jointdb.usecases._stack_edge import tip_edge_notes
    from jointdb.usecases._stack_guard import guarded

    f = prediction_grid(spec, freq)
    resolved = {n: r.frf for n, r in joints.items() if r.frf is not None}
    # a per-line joint can create a negatively damped tip resonance: fall back to its constant k, c (and say so)
    prediction, joints = guarded(spec, joints, predict_tool_tip(spec, resolved, f),
                                 lambda s, frfs: predict_tool_tip(s, frfs, f))
    edge = tip_edge_notes(prediction.tip)  # a dominant |H| on the first / last line: a mode may lie outside
    if edge:
        prediction = replace(prediction, notes=(*prediction.notes, *edge))
    return StackPrediction(spec, prediction, joints)


def predict_stack(spec: StackSpec | Path | str, repo=None, freq=None) -> StackPrediction:
    """Resolve a stack's joints from the database, then predict its tool-tip FRF (docs/theory.md §4).

    Parameters
    ----------
    spec
        The stack, or a path to a stack file.
    repo
        The joint store (as :func:`resolve_joints` takes it).
    freq
        Frequency lines [Hz] (as :func:`predict_with_joints` takes them).

    Returns
    -------
    StackPrediction
    """
    if not isinstance(spec, StackSpec):
        spec = load_stack(spec)
    return predict_with_joints(spec, resolve_joints(spec, repo), freq)
