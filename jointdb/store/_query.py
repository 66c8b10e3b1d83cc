"""Nearest-joint query and interpolation between neighbours.

Candidates
----------
Only versions of the requested joint type (types are never mixed). By default,
of each joint only its *current* version: the newest version not deprecated (as
of ``at``, default now); deprecated joints are skipped. Options: ``label``
(only versions carrying that label now), ``include_deprecated`` (deprecated
versions are kept), ``all_versions`` (every version ranks, not only the newest
of its joint); see :class:`jointdb.store._nearest.Selection`. Ranking reads the
query index (typed condition columns, :mod:`jointdb.store._index`); FRF blobs
are never loaded to rank. Queries at a past time ``at`` rank over the history
tables instead (:func:`candidates_from_history`), with the same distance.

Distance
--------
``distance = sqrt(sum of squared per-condition terms)`` over the conditions the
request specifies (a condition the request leaves out contributes nothing):

- ``torque_nm``, ``preload_n``: ``|ln((c+δ)/(r+δ))| / s`` where ``s`` is the spread
  ``max ln(x+δ) − min ln(x+δ)`` of that quantity over the candidates, floored at
  ``ln 2`` (so without spread a factor 2 costs 1.0); ``δ = 1e-9·max(1, max x)``
  only guards zero values. A candidate without the value costs 1.0.
- ``materials``: Jaccard distance of the two material multisets
  (``1 − |A∩B| / |A∪B|``): 0 for the same materials, 1 for none in common.
- ``geometry.<key>``: relative difference ``|c − r| / max(|c|, |r|)`` (in [0, 1]);
  a candidate without the key costs 1.0.

A request value outside the catalogued ``[min, max]`` of a numeric condition,
or a material no candidate has, is reported in ``Match.outside_range``
(``extrapolating=True``) and warned about with :class:`OutsideCatalogueWarning`.

Interpolation
-------------
Weights (method ``"axes"``, the default): the joints that bracket the request
along the condition axes it gives — ``ln`` torque, ``ln`` preload, ``ln`` of each
geometry number — with their barycentric weights (piecewise-linear interpolation
on the Delaunay triangulation of the catalogued conditions; two joints along one
axis, three on a triangle of a two-axis grid; outside the catalogued hull, its
nearest point). See :mod:`jointdb.store._interp`. A stiffness linear in those
coordinates is reproduced exactly, a power law in torque or force approximately.
Without a numeric axis in the request, or with method ``"idw"``: ``w_i ∝ 1/d_i``
over all the given neighbours (exact matches, ``d = 0``, share all the weight).

The neighbours' receptances are inverted to dynamic stiffness ``Z_i = H_i⁻¹`` (per
line, batched), combined and inverted back (docs/theory.md §1a; interpolating receptances
would mix resonances instead). Each diagonal entry's storage ``Re Z_ii`` and loss ``Im Z_ii``
are combined as a power law, ``exp(Σ w_i ln Re Z_ii,i)`` (and the same for the loss), on every
*contact line*: one where all neighbours taking weight have positive storage and loss on every
diagonal entry (:func:`contact_lines`). Contact stiffness and damping grow as powers of torque,
force and shank diameter, which the log coordinates then reproduce exactly. Elsewhere (a
neighbour mass-like or active on the line) and for off-diagonal entries the average is linear,
``Σ w_i Z_i`` (:data:`INTERPOLATION_LAW`), both parts alike.
On a line where that average would be non-passive (``Im Z_ii < 0``) and some
neighbour is passive, the loss ``Im Z`` is averaged over the passive ones only
(:func:`passive_line_weights`); the storage stiffness ``Re Z`` keeps the
barycentric weights (docs/stacks.md), and ``InterpolatedJoint.passivity_moved``
says on how many lines.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from datetime import datetime
from typing import TYPE_CHECKING, Any

import numpy as np
from sqlalchemy import select

from jointdb.errors import InputError, NumericalError
from jointdb.frf import FRF
from jointdb.store._access import read_session
from jointdb.store._candidates import _NULL, Candidates
from jointdb.store._dberrors import translate_error
from jointdb.store._interp import bracketing_weights
from jointdb.store._index import materials_key, standing
from jointdb.store._models import JointRow, LabelRow, StateRow, VersionRow
from jointdb.store._nearest import (
    OutsideCatalogueWarning,
    Reader,
    Selection,
    check_request,
    matches,
    nearest_now,
    not_found,
)
from jointdb.store._types import Conditions, InterpolatedJoint, JointVersion, Match, as_conditions

if TYPE_CHECKING:  # pragma: no cover
    from jointdb.store._protocol import ReadAccess

#: what :func:`interpolate` needs of a store: the verified FRF of a version
LoadFRF = Callable[[JointVersion], FRF]

__all__ = ["OutsideCatalogueWarning", "nearest", "interpolate", "candidates_from_history", "INTERPOLATION_METHODS"]

#: ``"axes"``: barycentric weights of the joints bracketing the request along the condition axes
#: (:mod:`jointdb.store._interp`; inverse distance when the request has no numeric axis);
#: ``"idw"``: inverse-distance weights of all the given neighbours.
INTERPOLATION_METHODS = ("axes", "idw")


def candidates_from_history(store: "ReadAccess", sel: Selection, at: datetime | None,
                            geometry_keys: Sequence[str]) -> tuple[Candidates, dict[int, str]]:
    """The candidates of ``sel`` as of ``at`` (None: now), computed from the history tables.

    Straightforward: every version of the type catalogued by ``at`` and every state
    row written by ``at`` are read, each joint's standing is worked out in Python
    and the selection applied. Labels are the current ones. Returns the candidates
    and ``{version_id: state}`` at that time.
    """
    with read_session(store) as s:
        vq = (select(VersionRow.id, VersionRow.joint_id, VersionRow.version, VersionRow.materials,
                     VersionRow.torque_nm, VersionRow.preload_n, VersionRow.geometry)
              .join(JointRow, JointRow.id == VersionRow.joint_id).where(JointRow.joint_type == sel.joint_type))
        sq = (select(StateRow.at, StateRow.id, StateRow.joint_id, StateRow.version, StateRow.state)
              .join(JointRow, JointRow.id == StateRow.joint_id).where(JointRow.joint_type == sel.joint_type))
        if at is not None:
            vq = vq.where(VersionRow.created_at <= at)
            sq = sq.where(StateRow.at <= at)
        per_joint: dict[int, list] = {}
        for row in s.execute(vq):
            per_joint.setdefault(row[1], []).append(tuple(row))
        states: dict[int, list] = {}
        for at_, sid, jid, number, state in s.execute(sq):
            states.setdefault(jid, []).append((at_, sid, number, state))
        labelled = None
        if sel.label is not None:
            labelled = {tuple(r) for r in s.execute(select(LabelRow.joint_id, LabelRow.version)
                                                    .where(LabelRow.label == sel.label))}
    rows, geometry, state_of = [], [], {}
    for jid, versions in per_joint.items():
        flags = standing([(v[0], v[2]) for v in versions], states.get(jid, ()))
        kept = [v for v in versions
                if (sel.include_deprecated or not flags[v[0]][0])
                and (labelled is None or (jid, v[2]) in labelled)]
        if not sel.all_versions and kept:
            kept = [max(kept, key=lambda v: v[2])]
        for vid, _, number, mats, torque, preload, geo in kept:
            rows.append((vid, jid, number, _NULL if torque is None else torque,
                         _NULL if preload is None else preload, materials_key(mats)))
            geometry.append((vid, geo or {}))
            state_of[vid] = "deprecated" if flags[vid][0] else "active"
    cand = Candidates.from_rows(rows)
    for key in geometry_keys:
        cand.geometry[key] = cand.align([(vid, g[key]) for vid, g in geometry if key in g])
    return cand, state_of


def nearest(
    store: "ReadAccess",
    joint_type: str,
    conditions: Conditions | Mapping[str, Any],
    k: int = 3,
    at: datetime | None = None,
    *,
    label: str | None = None,
    all_versions: bool = False,
    include_deprecated: bool = False,
) -> list[Match]:
    """The ``k`` versions of ``joint_type`` closest to ``conditions`` (module docstring).

    Raises
    ------
    InputError
        ``k < 1``, bad conditions or label, or ``label`` with ``at`` (labels point now).
    NotFoundError
        No catalogued version of that type in the selection.
    """
    if at is not None and label is not None:
        raise InputError("a label names one version now; do not combine --label with --at")
    joint_type, req, k, label = check_request(joint_type, conditions, k, label)
    engine = store.read_engine
    raw = engine.raw_connection()
    try:
        reader = Reader(raw, engine.dialect.name)
        if at is None:
            return nearest_now(reader, store.url, joint_type, req, k, label=label, all_versions=all_versions,
                               include_deprecated=include_deprecated, stacklevel=5)
        sel = Selection(joint_type, None, bool(all_versions), bool(include_deprecated))
        cand, states = candidates_from_history(store, sel, at, list(req.geometry))
        with reader.snapshot():
            if cand.version_id.size == 0:
                raise not_found(reader, sel)
            return matches(reader, cand, req, k, sel, states, stacklevel=5)
    except engine.dialect.dbapi.Error as exc:
        raise translate_error(exc, store.url) from None
    finally:
        raw.close()


def _weights(distances: Sequence[float]) -> np.ndarray:
    d = np.asarray(distances, dtype=float)
    exact = d <= 1e-12
    if exact.any():
        w = exact.astype(float)
    else:
        w = 1.0 / d
    return w / w.sum()


#: a catalogued line is non-passive where a diagonal dynamic-stiffness term loses energy with the wrong sign,
#: ``Im Z_ii < −tol·|Z_ii|`` (the identification's passivity test, ``jointdb.coupling.identify_planar``)
PASSIVITY_TOL = 1e-6


def passive_line_weights(weights: np.ndarray, z: np.ndarray, tol: float = PASSIVITY_TOL) -> tuple[np.ndarray, np.ndarray]:
    """Per-line interpolation weights that take no energy-generating (non-passive) line of a neighbour.

    A real joint dissipates: every diagonal term of its dynamic stiffness has ``Im Z_ii ≥ 0``. A per-line
    joint can break that on a stretch of lines where the lumped joint cannot represent the campaign's contact
    (an internal resonance of the clamped zone: its IRC flags those lines ``non_passive``), and the stretch
    lies at a different frequency for each neighbour. Averaging such a line into the request's joint cancels
    the other neighbours' loss (family C, Ø7 between Ø6 and Ø10 at 10.3 kHz: ``Im Z_xx`` 0.5 % of the
    truth's, tip peak 10× too high: docs/validation/stack-bands-family-c.md, *High modes*). On a line where
    the plain average is itself non-passive, a non-passive neighbour's weight *for the loss* goes to the
    passive neighbours, in proportion to theirs; where the plain average is passive, or every neighbour is
    non-passive (or all passive), the nominal weights stay: the rule steps in only where the interpolation
    would otherwise make an energy-generating joint out of a passive one. The interpolation
    (:func:`interpolate`) applies these weights to ``Im Z`` only: a neighbour's storage stiffness ``Re Z``
    stays informative (taking another neighbour's with the loss moved Ø15–Ø19 stacks' 1 kHz peaks by up to
    −35 points where Ø10 and Ø20 joints differ 2× in stiffness).

    Parameters
    ----------
    weights
        Nominal weights ``(n_neighbours,)``, summing to 1.
    z
        The neighbours' dynamic stiffness ``(n_neighbours, n_freq, n, n)``.
    tol
        Passivity tolerance (relative to ``|Z_ii|``).

    Returns
    -------
    (w_lines, moved)
        Weights per line ``(n_neighbours, n_freq)`` (each column sums to 1) and, per neighbour, the number of
        lines whose weight was moved to the others ``(n_neighbours,)``.
    """
    weights = np.asarray(weights, float)
    diag = np.diagonal(z, axis1=2, axis2=3)  # (k, f, n)
    passive = np.all(diag.imag >= -tol * np.abs(diag), axis=2)  # (k, f)
    mean = np.einsum("k,kfn->fn", weights, diag)  # the plain average's diagonal, (f, n)
    mean_passive = np.all(mean.imag >= -tol * np.abs(mean), axis=1)  # (f,)
    w = weights[:, None] * passive
    total = w.sum(axis=0)
    keep = (total > 0) & ~np.all(passive, axis=0) & ~mean_passive
    w_lines = np.where(keep[None, :], w / np.where(total > 0, total, 1.0)[None, :], weights[:, None])
    moved = np.count_nonzero(keep[None, :] & ~passive & (weights[:, None] > 0), axis=1)
    return w_lines, moved


#: How :func:`interpolate` combines the neighbours' dynamic stiffness: ``"power-law"`` (diagonal storage and loss
#: geometrically where positive, the module docstring) or ``"linear"`` (``Σ w_i Z_i`` throughout, before round 3
#: session 9; docs/validation/stack-bands-family-c.md, *Power-law interpolation*).
INTERPOLATION_LAW = "power-law"


def contact_lines(weights: np.ndarray, z: np.ndarray) -> np.ndarray:
    """The lines on which every neighbour taking weight behaves as a contact: each diagonal entry of its dynamic
    stiffness has positive storage and positive loss.

    Parameters
    ----------
    weights : ndarray, shape (n_neighbours, n_freq)
        Per-line weights (a neighbour with weight 0 on a line does not count there).
    z : ndarray, shape (n_neighbours, n_freq, n, n)
        The neighbours' dynamic stiffness.

    Returns
    -------
    ndarray of bool, shape (n_freq,)
        Where the power law may combine them (:func:`combine_stiffness`). Off these lines some neighbour is
        mass-like (``Re Z_ii ≤ 0``, near or above a resonance the joint model carries) or active; a power law
        of the conditions does not describe it, and a geometric mean of one part beside a linear mean of the
        other would mix two laws in one joint.
    """
    diag = np.diagonal(z, axis1=2, axis2=3)  # (k, f, n), a view (as passive_line_weights reads it)
    contact = (diag.real > 0) & (diag.imag > 0)
    return np.all(contact | (weights[:, :, None] == 0), axis=(0, 2))


def combine_stiffness(weights: np.ndarray, part: np.ndarray, contact: np.ndarray | None = None) -> np.ndarray:
    """One part (real or imaginary) of the neighbours' dynamic stiffness combined with per-line weights.

    Parameters
    ----------
    weights : ndarray, shape (n_neighbours, n_freq)
        Each column sums to 1.
    part : ndarray, shape (n_neighbours, n_freq, n, n)
        ``Re Z`` or ``Im Z`` of each neighbour.
    contact : ndarray of bool, shape (n_freq,), optional
        The lines the power law may be used on (:func:`contact_lines`); None: every line.

    Returns
    -------
    ndarray, shape (n_freq, n, n)
        ``Σ w_i part_i``, except on the diagonal under :data:`INTERPOLATION_LAW` ``"power-law"``: on a ``contact``
        line where every neighbour with weight > 0 has ``part_ii > 0``, ``exp(Σ w_i ln part_ii)`` (exact for a
        part that is a power law of the conditions whose log coordinates the weights interpolate).
    """
    out = np.einsum("kf,kfij->fij", weights, part)
    if INTERPOLATION_LAW != "power-law":
        return out
    ii = np.arange(part.shape[-1])
    diag = part[:, :, ii, ii]  # (k, f, n)
    w = weights[:, :, None]
    positive = np.all((diag > 0) | (w == 0), axis=0)  # (f, n)
    if contact is not None:
        positive &= np.asarray(contact, bool)[:, None]
    logs = np.log(np.where(diag > 0, diag, 1.0))
    geometric = np.exp(np.sum(np.where(w > 0, w * logs, 0.0), axis=0))
    out[:, ii, ii] = np.where(positive, geometric, out[:, ii, ii])
    return out


def interpolate(
    load_frf: LoadFRF,
    matches: Sequence[Match],
    conditions: Conditions | Mapping[str, Any] | None = None,
    *,
    method: str = "axes",
) -> InterpolatedJoint:
    """Interpolated joint FRF between neighbours, in dynamic stiffness (module docstring).

    Parameters
    ----------
    load_frf
        Reads the verified FRF of a version (:meth:`jointdb.store.Repository.load_frf`).
    matches
        Candidates (e.g. from :func:`nearest`); the ``"axes"`` method uses only those bracketing the
        request, so give it the catalogued grid around the request, not only the two nearest.
    conditions
        The request (None: inverse-distance weights).
    method
        ``"axes"`` or ``"idw"`` (:data:`INTERPOLATION_METHODS`).

    Returns
    -------
    InterpolatedJoint
        Receptance on the used neighbours' common band; ``neighbours`` lists those with weight > 0.

    Raises
    ------
    InputError
        No matches, an unknown method, neighbours of different type, model kind or DOFs, or
        used neighbours without a common frequency band.
    NumericalError
        A neighbour's receptance is singular on some line.
    """
    matches = list(matches)
    if not matches:
        raise InputError("no neighbours to interpolate between")
    first = matches[0].version
    for m in matches[1:]:
        v = m.version
        if v.joint_type != first.joint_type:
            raise InputError(f"cannot interpolate between {first.joint_type} and {v.joint_type} joints")
        if v.model_kind != first.model_kind or tuple(v.dofs) != tuple(first.dofs):
            raise InputError(
                f"cannot interpolate {first.name} v{first.version} ({first.model_kind}, {' '.join(first.dofs)}) "
                f"with {v.name} v{v.version} ({v.model_kind}, {' '.join(v.dofs)}): model kind and DOFs must match"
            )
    if method not in INTERPOLATION_METHODS:
        raise InputError(f"interpolation method must be one of {', '.join(INTERPOLATION_METHODS)}, got {method!r}")
    w = None
    if conditions is not None and method == "axes":
        w = bracketing_weights(as_conditions(conditions), matches)
    if w is None:
        w = _weights([m.distance for m in matches])
    used = [(float(wi), m) for wi, m in zip(w, matches) if wi > 0.0]
    frfs = [load_frf(m.version) for _, m in used]
    lo = max(f.freq[0] for f in frfs)
    hi = min(f.freq[-1] for f in frfs)
    if lo > hi:
        raise InputError("the neighbours' frequency ranges do not overlap; cannot interpolate")
    grid = frfs[0].band(lo, hi).freq
    zs = []
    for (weight, m), frf in zip(used, frfs):
        h = frf if (frf.n_freq == grid.size and np.array_equal(frf.freq, grid)) else frf.resample(grid)
        try:
            zs.append(np.linalg.inv(h.values))
        except np.linalg.LinAlgError:
            raise NumericalError(
                f"{m.version.name} v{m.version.version}: receptance is singular on some line; "
                "cannot form its dynamic stiffness"
            ) from None
    z_all = np.stack(zs)  # (n_used, n_freq, n, n)
    w_used = np.array([wi for wi, _ in used])
    w_lines, moved = passive_line_weights(w_used, z_all)
    # storage (Re Z) with the barycentric weights, loss (Im Z) with the passive-first ones
    w_storage = np.repeat(w_used[:, None], grid.size, axis=1)
    contact = contact_lines(w_storage, z_all)  # every used neighbour counts (the loss weights drop some: a subset)
    z = combine_stiffness(w_storage, z_all.real, contact) + 1j * combine_stiffness(w_lines, z_all.imag, contact)
    try:
        h_int = np.linalg.inv(z)
    except np.linalg.LinAlgError:
        raise NumericalError("interpolated dynamic stiffness is singular on some line") from None
    frf_out = FRF(grid, h_int, first.dofs, first.dofs, "receptance")
    neighbours = tuple((m.version.name, m.version.version, wi) for wi, m in used)
    return InterpolatedJoint(
        frf=frf_out,
        joint_type=first.joint_type,
        conditions=as_conditions(conditions) if conditions is not None else Conditions(),
        neighbours=neighbours,
        passivity_moved=tuple((m.version.name, m.version.version, int(n)) for (_, m), n in zip(used, moved) if n),
    )
