"""Identifiability before naming: a candidate whose key parameters the recordings do not pin down is
not named as the answer.

A parameter is *identified* when its reported 1σ — the linearised statistical σ scaled by χ²_red (the
misfit beyond the noise) and by the residual's correlation length, combined with the model-form
spread of a jackknife over frequency blocks (:mod:`jointdb.diagnose._fit`) — is at most
:data:`IDENTIFIED` × its value, and it does not sit at a bound of its fit range (a parameter at a bound
has a one-sided, flat likelihood: the data only say "at least" or "at most"). A candidate is
identified when all its *key* parameters are (:attr:`Param.key`); of key parameters sharing an
``either`` group one suffices (a joint rigid in translation but compliant in rotation is identified by
its rotational stiffness; the other is shown as "not resolved").

A joint's loss factor is not key: whether the joint has damping of its own is decided by model
comparison (the damped variant is selected only if it beats the undamped one by more than the
parsimony tolerance); how much is shown with its σ, or as "not resolved" when the damped variants of
the same place (point joint, contact layer) disagree about it.
"""

from __future__ import annotations

import numpy as np

from jointdb.diagnose._uncertainty import jackknife_spread
from jointdb.diagnose.physics._candidate import IDENTIFIED

__all__ = ["IDENTIFIED", "unidentified", "identify_advice", "damping_grows", "DAMPING_GROWTH", "combination_note",
           "identified", "model_form_sigmas", "next_ranked"]

#: An amplitude-dependent explanation of damping that grows with level must itself lose at least this
#: factor more energy per cycle (loss factor) at the highest level than at the lowest.
DAMPING_GROWTH = 1.1


def unidentified(fit) -> dict[str, float]:
    """The key parameters of ``fit`` that are not identified: ``{name: σ / |value|}`` (inf at a bound).

    Parameters
    ----------
    fit
        A :class:`jointdb.diagnose._fit.Fit` with ``sigmas`` (SI) set.

    Returns
    -------
    dict
        Empty when the candidate is identified.
    """
    params = fit.candidate.params if fit.candidate is not None else ()
    rel = {}
    for q in params:
        if not q.key:
            continue
        r = q.relative_sigma(fit.values[q.name], fit.sigmas.get(q.name))
        rel[q.name] = float("inf") if q.name in fit.at_bound else r
    bad = {k: v for k, v in rel.items() if v > IDENTIFIED}
    groups: dict[tuple, list[str]] = {}
    for q in params:
        if q.key and q.either:
            prefix = q.name.split(".")[0] if "." in q.name else ""
            groups.setdefault((prefix, q.either), []).append(q.name)
    for names in groups.values():
        if any(rel[n] <= IDENTIFIED for n in names) or _combination_identified(fit, names):
            for n in names:
                bad.pop(n, None)
    return bad


def _relative_cov(fit, names: list[str]) -> np.ndarray | None:
    """Covariance of the relative errors ``δv/|v|`` of ``names`` (statistical, with the model-form
    variance added on the diagonal), or None without a covariance."""
    if fit.cov_u is None:
        return None
    params = list(fit.candidate.params)
    idx = [next(i for i, q in enumerate(params) if q.name == n) for n in names]
    d = []
    for i in idx:
        q = params[i]
        v = abs(fit.values[q.name])
        d.append(1.0 if q.log else (q.scale / v if v > 0 else np.inf))
    d = np.asarray(d)
    if not np.all(np.isfinite(d)):
        return None
    cov = np.asarray(fit.cov_u)[np.ix_(idx, idx)] * np.outer(d, d)
    model = np.array([(fit.sigmas_model.get(n, 0.0) / abs(fit.values[n])) if fit.values[n] else 0.0
                      for n in names])
    return cov + np.diag(model**2)


def _combination_identified(fit, names: list[str]) -> bool:
    """True if some combination of the group's parameters is identified although none is alone:
    the best-determined direction of their relative covariance has σ ≤ IDENTIFIED (e.g. a contact's
    equivalent stiffness and length trade off, their product — the joint's stiffness — does not)."""
    if len(names) < 2 or any(n in fit.at_bound for n in names):
        return False
    cov = _relative_cov(fit, names)
    if cov is None or not np.all(np.isfinite(cov)):
        return False
    lam = float(np.linalg.eigvalsh(0.5 * (cov + cov.T))[0])
    return np.sqrt(max(lam, 0.0)) <= IDENTIFIED


def combination_note(fit) -> str:
    """A sentence when a named fit's group is identified only as a combination (else ``""``)."""
    params = fit.candidate.params if fit.candidate is not None else ()
    groups: dict[tuple, list] = {}
    for q in params:
        if q.key and q.either:
            groups.setdefault((q.name.split(".")[0] if "." in q.name else "", q.either), []).append(q)
    notes = []
    for qs in groups.values():
        alone = [q.relative_sigma(fit.values[q.name], fit.sigmas.get(q.name)) <= IDENTIFIED for q in qs]
        if not any(alone) and _combination_identified(fit, [q.name for q in qs]):
            notes.append(" and ".join(q.label for q in qs))
    return "".join(f" The {n} trade off against each other: only their combination (the joint's overall "
                   "stiffness) is identified." for n in notes)


def identify_advice(fit, n_points: int, n_levels: int) -> str:
    """The measurement that would identify ``fit``'s parameters, in words."""
    c = fit.candidate.parts[0] if hasattr(fit.candidate, "parts") else fit.candidate
    fam = fit.family.split(" + ")[0]
    pos = getattr(c, "position", None)
    if fam == "softening_joint":
        return ("record at more excitation levels, spanning at least ×10 in force, so that the stiffness loss "
                "and the damping growth are both seen to level off")
    if fam.startswith("joint"):
        where = f"z = {pos * 1e3:.0f} mm" if pos is not None else "the suspected interface"
        return (f"record the response at two points a few mm apart on each side of {where} (the kink in the "
                "mode shape there separates the joint's translational and rotational stiffness)"
                + ("" if n_points > 1 else "; one recorded point cannot"))
    if fam == "sensor_mass":
        return "repeat the tap test with the sensor moved or replaced by a lighter one"
    if fam == "fluted_diameter":
        return "measure the section's diameter, or record a point on each side of the section"
    if fam in ("gain", "delay"):
        return "check the measurement chain with a calibrated reference (a known mass or a back-to-back test)"
    return "add a measurement point where this candidate changes the FRF most, or another excitation level"


def damping_grows(fit) -> bool:
    """Whether ``fit``'s loss factor grows from the lowest to the highest excitation level.

    A level-dependent candidate whose loss cannot grow (a loss-growth parameter at the bound of its
    range, or a loss at the highest level below :data:`DAMPING_GROWTH` × the lowest's) cannot be the
    explanation of recorded damping that grows with level. Candidates without a per-level state
    (``state(values, level)``) do not grow.
    """
    cand = fit.candidate
    parts = cand.parts if hasattr(cand, "parts") else (cand,)
    prefixes = ("a.", "b.") if hasattr(cand, "parts") else ("",)
    for part, pre in zip(parts, prefixes):
        state = getattr(part, "state", None)
        levels = getattr(part, "levels", None)
        if state is None or not levels:
            continue
        if any(n.startswith(pre) and n[len(pre):] in ("eta_max",) for n in fit.at_bound):
            continue
        vals = {k[len(pre):]: v for k, v in fit.values.items() if k.startswith(pre)}
        etas = [state(vals, lv)[1] for lv in range(len(levels))]
        known = all(x is not None for x in levels)
        lo, hi = (int(min(range(len(levels)), key=lambda i: levels[i])),
                  int(max(range(len(levels)), key=lambda i: levels[i]))) if known else (0, len(levels) - 1)
        if etas[hi] >= DAMPING_GROWTH * etas[lo]:
            return True
    return False


def next_ranked(best, fits: list):
    """The first ranked fit after ``best`` that is another explanation (not its own unrefined start)."""
    base = best.name.removesuffix("+hb")
    return next((f for f in fits if f is not best and f.name != base), None)


def model_form_sigmas(ev, model, fit, fits: list, rules) -> None:
    """Honest uncertainty of a fit: statistical (χ²_red, τ) ⊕ model-form (jackknife over frequency blocks,
    and the spread across the accepted variants of the same physics, e.g. a sensor as point mass, with
    rotary inertia, with an offset: RMS deviation of their estimates of a shared parameter)."""
    fit.sigmas_model = jackknife_spread(ev, model, fit)
    if fit.candidate.slot:
        rivals = [g for g in fits if g is not fit and g.candidate.slot == fit.candidate.slot
                  and rules.passes(g, rules.nominal)]
        for k in fit.values:
            dev = [g.values[k] - fit.values[k] for g in rivals if k in g.values]
            if dev:
                v = float(np.sqrt(np.mean(np.square(dev))))
                fit.sigmas_model[k] = float(np.hypot(fit.sigmas_model.get(k, 0.0), v))
    fit.sigmas = {k: float(np.hypot(v, fit.sigmas_model.get(k, 0.0))) for k, v in fit.sigmas_stat.items()}


#: Accepted alternatives (within close_call of the selected one) tried when the selected one is not identified.
IDENTIFY_TRIES = 2


def identified(ev, model, best, ok: list, fits: list, rules, close_call: float):
    """``(named, unresolved)``: the selected fit if its key parameters are identified; else an accepted,
    nearly as good alternative that is (``unresolved`` = the selected one), else ``(None, selected)``."""
    if not unidentified(best):
        return best, None
    tried = 0
    for f in ok:
        if f is best or f.mismatch > close_call * best.mismatch or not rules.eligible(f):
            continue
        if tried == IDENTIFY_TRIES:
            break
        tried += 1
        if not f.sigmas_model:
            model_form_sigmas(ev, model, f, fits, rules)
        if not unidentified(f):
            return f, best
    return None, best
