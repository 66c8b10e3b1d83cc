"""Resolve a stack's joints against the catalogue and predict its tool-tip FRF (docs/theory.md §4)."""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from jointdb.errors import NotFoundError
from jointdb.frf import FRF
from jointdb.stack import INTERFACE_NAMES, Prediction, StackSpec, predict_tool_tip, prediction_grid
from jointdb.usecases._files import load_stack

#: How many nearest catalogued joints a stack's interpolated query ranks before the interpolation picks the
#: ones that bracket the request along the condition axes (jointdb.store._interp).
INTERPOLATION_POOL = 64

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


def predict_with_joints(spec: StackSpec, joints: Mapping[str, JointResolution], freq=None) -> StackPrediction:
    """Predict a stack's tool-tip FRF with joints already resolved (:func:`resolve_joints`).

    Parameters
    ----------
    spec
        The stack.
    joints
        Interface -> :class:`JointResolution`; rigid / explicit ones carry no FRF.
    freq
        Frequency lines [Hz], shape ``(n_freq,)`` (default: the stack's grid,
        :func:`jointdb.stack.prediction_grid`).
    """
    resolved = {n: r.frf for n, r in joints.items() if r.frf is not None}
    return StackPrediction(spec, predict_tool_tip(spec, resolved, prediction_grid(spec, freq)), joints)


def predict_stack(spec: StackSpec | Path | str, repo=None, freq=None) -> StackPrediction:
    """Resolve a stack's joints from the database, then predict its tool-tip FRF (docs/theory.md §4).

    ``spec`` may be a path to a stack file. See :func:`resolve_joints` for ``repo``,
    :func:`predict_with_joints` for ``freq``.
    """
    if not isinstance(spec, StackSpec):
        spec = load_stack(spec)
    return predict_with_joints(spec, resolve_joints(spec, repo), freq)
