"""Nearest-joint query and interpolation between neighbours.

Candidates
----------
Only joints of the requested joint type (types are never mixed), and of each
joint only its *current* version: the latest version not deprecated (as of
``at``, default now); deprecated joints are skipped. Ranking reads condition
columns only; FRF blobs are never loaded to rank.

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
Weights ``w_i ∝ 1/d_i`` (exact matches, ``d = 0``, share all the weight); the
neighbours' receptances are inverted to dynamic stiffness ``Z_i = H_i⁻¹`` (per
line, batched), averaged ``Z = Σ w_i Z_i`` and inverted back. For spring–damper
joints ``Z = k + iωc``, so this interpolates stiffness and damping linearly
(docs/theory.md §1a), which interpolating receptances would not.
"""

from __future__ import annotations

import json
import math
import warnings
from collections import Counter
from collections.abc import Mapping, Sequence
from datetime import datetime
from typing import TYPE_CHECKING, Any

import numpy as np
from sqlalchemy import Text, and_, cast, func, select

from jointdb.errors import InputError, NotFoundError, NumericalError
from jointdb.frf import FRF
from jointdb.store._models import JointRow, LabelRow, StateRow, VersionRow
from jointdb.store._records import state_of, to_version
from jointdb.store._types import Conditions, InterpolatedJoint, Match, as_conditions, check_joint_type

if TYPE_CHECKING:  # pragma: no cover
    from jointdb.store._repository import Repository

MISSING_PENALTY = 1.0
MIN_LOG_SPREAD = math.log(2.0)


class OutsideCatalogueWarning(UserWarning):
    """A nearest-joint request lies outside the catalogued range of some condition."""


def _candidates(repo: "Repository", joint_type: str, at: datetime | None, geometry_keys: Sequence[str]) -> list[tuple]:
    """Current versions of a type: ``(version_id, joint_id, version, materials_json_text,
    preload, torque, *geometry values)``.

    Plain SQL columns only: materials come back as JSON text (decoded once per
    distinct value by the caller) and geometry numbers are extracted by the
    database (``json_extract`` / ``->>``), so ranking stays cheap at 10^5 rows.
    """
    cols = [
        VersionRow.id,
        VersionRow.joint_id,
        VersionRow.version,
        cast(VersionRow.materials, Text),
        VersionRow.preload_n,
        VersionRow.torque_nm,
        *[VersionRow.geometry[key].as_float() for key in geometry_keys],
    ]
    with repo.read_engine.connect() as conn:
        inner = (
            select(VersionRow.joint_id, func.max(VersionRow.version).label("mv"))
            .join(JointRow, JointRow.id == VersionRow.joint_id)
            .where(JointRow.joint_type == joint_type)
        )
        if at is not None:
            inner = inner.where(VersionRow.created_at <= at)
        inner = inner.group_by(VersionRow.joint_id).subquery()
        rows = {
            r[1]: tuple(r)
            for r in conn.execute(
                select(*cols).join(inner, and_(VersionRow.joint_id == inner.c.joint_id, VersionRow.version == inner.c.mv))
            )
        }
        sq = select(StateRow).join(JointRow, JointRow.id == StateRow.joint_id).where(JointRow.joint_type == joint_type)
        if at is not None:
            sq = sq.where(StateRow.at <= at)
        states: dict[int, list] = {}
        for st in conn.execute(sq):
            states.setdefault(st.joint_id, []).append(st)
        for joint_id, sts in states.items():
            rows.pop(joint_id, None)
            q = select(*cols).where(VersionRow.joint_id == joint_id)
            if at is not None:
                q = q.where(VersionRow.created_at <= at)
            for r in conn.execute(q.order_by(VersionRow.version.desc())):
                if state_of(r[2], sts) == "active":
                    rows[joint_id] = tuple(r)
                    break
    return list(rows.values())


def _catalogue_stamp(repo: "Repository") -> tuple[int, int]:
    """Row counts of the two append-only tables that decide the candidates.

    Rows are never updated or deleted (migration 0002), so any committed
    catalogue, import or state change increases one of the counts.
    """
    with repo.read_engine.connect() as conn:
        n_versions = conn.execute(select(func.count()).select_from(VersionRow)).scalar_one()
        n_states = conn.execute(select(func.count()).select_from(StateRow)).scalar_one()
    return int(n_versions), int(n_states)


def _cached_candidates(repo: "Repository", joint_type: str, at: datetime | None, geometry_keys: Sequence[str]):
    """Candidates as rows, columns and a float-column accessor, cached per repository.

    The cache entry is reused only while :func:`_catalogue_stamp` is unchanged;
    point-in-time queries (``at``) are not cached.
    """
    key = (joint_type, tuple(geometry_keys))
    cache = repo.__dict__.setdefault("_nearest_cache", {})
    stamp = _catalogue_stamp(repo) if at is None else None
    if stamp is not None and key in cache and cache[key][0] == stamp:
        return cache[key][1]
    rows = _candidates(repo, joint_type, at, geometry_keys)
    columns = list(zip(*rows)) if rows else []
    floats: dict[int, np.ndarray] = {}

    def numeric(col: int) -> np.ndarray:
        if col not in floats:
            floats[col] = np.array([np.nan if x is None else x for x in columns[col]], dtype=float)
        return floats[col]

    value = (rows, columns, numeric)
    if stamp is not None:
        if len(cache) > 16:
            cache.clear()
        cache[key] = (stamp, value)
    return value


def _jaccard(a: tuple[str, ...], b: tuple[str, ...]) -> float:
    ca, cb = Counter(a), Counter(b)
    union = sum((ca | cb).values())
    return 0.0 if union == 0 else 1.0 - sum((ca & cb).values()) / union


def _log_term(values: np.ndarray, request: float, name: str, terms: dict, outside: list) -> None:
    have = np.isfinite(values)
    if not have.any():
        terms[name] = np.full(values.shape, MISSING_PENALTY)
        outside.append(name)
        return
    delta = 1e-9 * max(1.0, float(np.nanmax(values)))
    logs = np.log(values[have] + delta)
    spread = max(float(logs.max() - logs.min()), MIN_LOG_SPREAD)
    term = np.full(values.shape, MISSING_PENALTY)
    term[have] = np.abs(logs - math.log(request + delta)) / spread
    terms[name] = term
    lo, hi = float(np.nanmin(values)), float(np.nanmax(values))
    if request < lo or request > hi:
        outside.append(name)


def nearest(
    repo: "Repository",
    joint_type: str,
    conditions: Conditions | Mapping[str, Any],
    k: int = 3,
    at: datetime | None = None,
) -> list[Match]:
    """The ``k`` current versions of ``joint_type`` closest to ``conditions`` (module docstring).

    Raises
    ------
    InputError
        ``k < 1`` or bad conditions.
    NotFoundError
        No catalogued joint of that type.
    """
    joint_type = check_joint_type(joint_type)
    req = as_conditions(conditions)
    if isinstance(k, bool) or int(k) < 1:
        raise InputError(f"k must be >= 1, got {k!r}")
    geometry_keys = list(req.geometry)
    rows, columns, numeric = _cached_candidates(repo, joint_type, at, geometry_keys)
    if not rows:
        with repo._read() as s:
            types = sorted(set(s.scalars(select(JointRow.joint_type))))
        raise NotFoundError(
            f"no current catalogued joint of type {joint_type!r}; types in the catalogue: {', '.join(types) or 'none'}"
            " (joint types are never mixed)"
        )
    n = len(rows)
    terms: dict[str, np.ndarray] = {}
    outside: list[str] = []
    if req.torque_nm is not None:
        _log_term(numeric(5), req.torque_nm, "torque_nm", terms, outside)
    if req.preload_n is not None:
        _log_term(numeric(4), req.preload_n, "preload_n", terms, outside)
    if req.materials:
        want = tuple(sorted(req.materials))
        cache: dict[str, float] = {}
        for text in set(columns[3]):
            mats = tuple(sorted(json.loads(text) if text else ()))
            cache[text] = _jaccard(want, mats) if mats else MISSING_PENALTY
        terms["materials"] = np.array([cache[text] for text in columns[3]])
        if not any(value == 0.0 for value in cache.values()):
            outside.append("materials")
    for g, (key, r_val) in enumerate(req.geometry.items()):
        vals = numeric(6 + g)
        have = np.isfinite(vals)
        denom = np.maximum(np.abs(vals), abs(r_val))
        with np.errstate(invalid="ignore"):
            rel = np.where(denom > 0, np.abs(vals - r_val) / np.where(denom > 0, denom, 1.0), 0.0)
        terms[f"geometry.{key}"] = np.where(have, rel, MISSING_PENALTY)
        if not have.any() or r_val < np.nanmin(vals) or r_val > np.nanmax(vals):
            outside.append(f"geometry.{key}")
    total = np.sqrt(sum((t**2 for t in terms.values()), np.zeros(n)))
    # deterministic order: distance (to 1e-12), then joint id, then version
    joint_ids = np.array(columns[1])
    numbers = np.array(columns[2])
    order = np.lexsort((numbers, joint_ids, np.round(total, 12)))[: int(k)]
    if outside:
        warnings.warn(
            f"request lies outside the catalogued range of {joint_type} joints for: {', '.join(outside)}; "
            "the nearest joints are extrapolations",
            OutsideCatalogueWarning,
            stacklevel=3,
        )
    out: list[Match] = []
    ids = [rows[i][0] for i in order]
    with repo._read() as s:
        found = {
            v.id: (v, j)
            for v, j in s.execute(
                select(VersionRow, JointRow).join(JointRow, JointRow.id == VersionRow.joint_id).where(VersionRow.id.in_(ids))
            )
        }
        labels: dict[tuple[int, int], list[str]] = {}
        for lab in s.scalars(select(LabelRow).where(LabelRow.joint_id.in_({j.id for _, j in found.values()}))):
            labels.setdefault((lab.joint_id, lab.version), []).append(lab.label)
    for i in order:
        vrow, joint = found[rows[i][0]]
        out.append(
            Match(
                version=to_version(joint, vrow, "active", labels.get((joint.id, vrow.version), ())),
                distance=float(total[i]),
                per_condition={name: float(t[i]) for name, t in terms.items()},
                extrapolating=bool(outside),
                outside_range=tuple(outside),
            )
        )
    return out


def _weights(distances: Sequence[float]) -> np.ndarray:
    d = np.asarray(distances, dtype=float)
    exact = d <= 1e-12
    if exact.any():
        w = exact.astype(float)
    else:
        w = 1.0 / d
    return w / w.sum()


def interpolate(
    repo: "Repository",
    matches: Sequence[Match],
    conditions: Conditions | Mapping[str, Any] | None = None,
) -> InterpolatedJoint:
    """Interpolated joint FRF between neighbours, in dynamic stiffness (module docstring).

    Raises
    ------
    InputError
        No matches, or neighbours of different type, model kind or DOFs, or
        without a common frequency band.
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
    w = _weights([m.distance for m in matches])
    frfs = [repo.load_frf(m.version) for m in matches]
    lo = max(f.freq[0] for f in frfs)
    hi = min(f.freq[-1] for f in frfs)
    if lo > hi:
        raise InputError("the neighbours' frequency ranges do not overlap; cannot interpolate")
    grid = frfs[0].band(lo, hi).freq
    z = np.zeros((grid.size, len(first.dofs), len(first.dofs)), dtype=np.complex128)
    for weight, frf, m in zip(w, frfs, matches):
        if weight == 0.0:
            continue
        h = frf if (frf.n_freq == grid.size and np.array_equal(frf.freq, grid)) else frf.resample(grid)
        try:
            z += weight * np.linalg.inv(h.values)
        except np.linalg.LinAlgError:
            raise NumericalError(
                f"{m.version.name} v{m.version.version}: receptance is singular on some line; "
                "cannot form its dynamic stiffness"
            ) from None
    try:
        h_int = np.linalg.inv(z)
    except np.linalg.LinAlgError:
        raise NumericalError("interpolated dynamic stiffness is singular on some line") from None
    frf_out = FRF(grid, h_int, first.dofs, first.dofs, "receptance")
    neighbours = tuple((m.version.name, m.version.version, float(wi)) for m, wi in zip(matches, w))
    return InterpolatedJoint(
        frf=frf_out,
        joint_type=first.joint_type,
        conditions=as_conditions(conditions) if conditions is not None else Conditions(),
        neighbours=neighbours,
    )
