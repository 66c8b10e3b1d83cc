"""How well the catalogue predicts its own joints: leave-one-out over a query's candidate pool.

A joint taken from the catalogue for a request it was not identified at is wrong by
what the choice — the nearest joint, or the interpolation between the joints that
bracket the request — cannot know. The catalogue itself says how large that error is:
each catalogued joint ``j`` of the pool is predicted from the *others* exactly as a
request at ``j``'s conditions would be (same axes, same distance, same bracketing
weights, :func:`jointdb.store._query.interpolate`), and compared with ``j``'s own FRF.

What is kept per left-out joint ``j`` (:class:`LooPoint`): its distance ``d_j`` to the nearest
other joint (the query distance of :mod:`jointdb.store._query`, computed over the pool), whether
it lies inside the others' catalogued range (an interpolation) or not (an edge), and

- ``relative``: the relative error of its dynamic stiffness ``Z = H⁻¹`` per line,
  ``R_j = (Z_j − Ẑ_j) Ẑ_j⁻¹`` (so ``Z_j = (I + R_j) Ẑ_j``), capped per line at
  :data:`CAP_OVER_MEDIAN` × its median over the lines. A band draws these patterns
  (:func:`jointdb.stack._band.choice_perturbed`) with amplitudes scaled by the request's
  distance over ``d_j`` (:meth:`ChoiceErrorModel.on_grid`);
- ``error``: a level summary per diagonal DOF, ``|ln|`` of the median ratio of predicted to
  true Re Z (stiffness) and Im Z (damping) over the lines away from zero crossings; the straight
  line ``σ(δ) = b·δ`` with ``b² = Σ e_j² / Σ d_j²`` through those is what ``--json`` reports
  (``choice_error``), a joint at a catalogued condition erring only by its noise.

Pure numerics on the pool the caller already has (``load_frf`` reads the blobs);
no query is issued here.
"""

from __future__ import annotations

import json
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from jointdb.errors import InputError, NumericalError
from jointdb.frf import FRF
from jointdb.store._candidates import _NULL, Candidates
from jointdb.store._types import Conditions, JointVersion, Match

__all__ = ["LooPoint", "ChoiceErrorModel", "leave_one_out", "choice_error_model", "pool_distances"]


@dataclass(frozen=True, eq=False)
class LooPoint:
    """One left-out joint: ``name``, ``version``, its distance to the nearest other joint of the pool,
    ``error`` ``(n_dof, 2)``: the level error of (Re Z, Im Z) per diagonal DOF (:func:`_rel_error`) when
    predicted from the others; ``inside``: its conditions lie inside the others' catalogued range (an
    interpolation, not an edge); ``freq`` and ``relative`` ``(n_freq, n_dof, n_dof)``: the relative error
    of the prediction per line, ``R = (Z − Ẑ) Ẑ⁻¹`` (so that ``Z = (I + R) Ẑ``)."""

    name: str
    version: int
    distance: float
    error: np.ndarray
    inside: bool = True
    freq: np.ndarray | None = None
    relative: np.ndarray | None = None


@dataclass(frozen=True)
class ChoiceErrorModel:
    """``σ(δ) = slope·δ`` per DOF and part (``slope`` ``(n_dof, 2)``: re, im), fitted on ``points``.

    ``dofs``: the joint's DOFs (labels); ``distance``: the request's distance to the nearest
    catalogued joint of the pool; ``sigma``: ``slope·distance``, the relative standard error of
    the joint's dynamic stiffness from the choice.
    """

    dofs: tuple[str, ...]
    slope: np.ndarray
    distance: float
    points: tuple[LooPoint, ...]

    @property
    def sigma(self) -> np.ndarray:
        return self.slope * self.distance

    def on_grid(self, freq: np.ndarray, order: Sequence[int]) -> tuple[np.ndarray, np.ndarray]:
        """The left-out joints' relative errors as perturbations for a band: ``(R, scale)``.

        ``R`` ``(m, n_freq, n, n)``: each point's relative error ``(Z − Ẑ) Ẑ⁻¹`` on ``freq`` (linear in real
        and imaginary parts, held constant beyond its own band), DOFs in ``order``; ``scale`` ``(m,)``:
        the request's distance over the point's (a request twice as far from the catalogue as a left-out
        joint was from the others errs twice as much, :data:`ChoiceErrorModel` is that straight line).
        """
        f = np.asarray(freq, float)
        order = list(order)
        rs = []
        for p in self.points:
            r = p.relative[:, order][:, :, order]
            flat = r.reshape(r.shape[0], -1)
            cols = [np.interp(f, p.freq, flat[:, k].real) + 1j * np.interp(f, p.freq, flat[:, k].imag)
                    for k in range(flat.shape[1])]
            rs.append(np.stack(cols, axis=-1).reshape(f.size, *r.shape[1:]))
        scale = np.array([self.distance / p.distance for p in self.points])
        return np.array(rs), scale

    def to_json(self) -> dict:
        return {"dofs": list(self.dofs), "request_distance": self.distance,
                "slope_per_unit_distance": {"re": self.slope[:, 0].tolist(), "im": self.slope[:, 1].tolist()},
                "sigma": {"re": self.sigma[:, 0].tolist(), "im": self.sigma[:, 1].tolist()},
                "leave_one_out": [{"joint": f"{p.name}@{p.version}", "distance": p.distance,
                                   "error_re": p.error[:, 0].tolist(), "error_im": p.error[:, 1].tolist()}
                                  for p in self.points]}


def _restricted(version: JointVersion, request: Conditions) -> Conditions | None:
    """``version``'s conditions on the request's axes only (None if it lacks one of them)."""
    c = version.conditions
    geo = {}
    for key in request.geometry:
        if key not in (c.geometry or {}):
            return None
        geo[key] = c.geometry[key]
    if (request.torque_nm is not None and c.torque_nm is None) or (request.preload_n is not None
                                                                 and c.preload_n is None):
        return None
    return Conditions(materials=c.materials if request.materials else (),
                      torque_nm=c.torque_nm if request.torque_nm is not None else None,
                      preload_n=c.preload_n if request.preload_n is not None else None, geometry=geo)


def _candidates(pool: Sequence[Match], keys: Sequence[str]) -> Candidates:
    rows = []
    for i, m in enumerate(pool):
        c = m.version.conditions
        rows.append((i, i, m.version.version, _NULL if c.torque_nm is None else c.torque_nm,
                     _NULL if c.preload_n is None else c.preload_n, json.dumps(sorted(c.materials)),
                     *[(c.geometry or {}).get(k, _NULL) for k in keys]))
    return Candidates.from_rows(rows, list(keys))


def pool_distances(pool: Sequence[Match], request: Conditions) -> list[Match]:
    """The pool re-ranked against ``request`` with the query distance computed over the pool itself
    (same spread normalisation for the request and every left-out joint). Order as given."""
    from jointdb.store._nearest import rank, unvaried_machine_conditions

    cand = _candidates(pool, list(request.geometry))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        _, total, terms, outside = rank(cand, request, len(pool))
    if pool:  # a machine condition the catalogue never varied is a note, not an edge; its distance still counts:
        # that no data show a dependence does not show there is none (docs/stacks.md, *Bands*)
        for name, _ in unvaried_machine_conditions(pool[0].version.joint_type, cand, outside):
            outside.remove(name)
    return [Match(m.version, float(total[i]), {k: float(t[i]) for k, t in terms.items()}, bool(outside),
                  tuple(outside)) for i, m in enumerate(pool)]


def _z(frf: FRF, grid: np.ndarray) -> np.ndarray:
    h = frf if (frf.n_freq == grid.size and np.array_equal(frf.freq, grid)) else frf.resample(grid)
    try:
        return np.linalg.inv(h.values)
    except np.linalg.LinAlgError:
        raise NumericalError("a joint receptance is singular on some line") from None


def _rel_error(z_hat: np.ndarray, z: np.ndarray) -> np.ndarray:
    """``(n_dof, 2)``: |ln| of the typical ratio of predicted to true Re Z and Im Z per diagonal DOF.

    The ratio is the median over the lines where the true part is not near a zero crossing (at least
    a third of its median magnitude): a per-line IRC joint is noisy on some lines (near the
    substructures' antiresonances), and what shifts a tool tip is the joint's level, not those lines.
    """
    d = np.arange(z.shape[1])
    a, b = z_hat[:, d, d], z[:, d, d]
    out = np.zeros((d.size, 2))
    for p, part in enumerate((np.real, np.imag)):
        pa, pb = part(a), part(b)
        for k in range(d.size):
            mag = np.abs(pb[:, k])
            keep = mag >= mag.mean() / 3 if mag.size else mag > 0
            ratio = pa[keep, k] / pb[keep, k]
            ratio = ratio[ratio > 0]
            if ratio.size:
                out[k, p] = abs(float(np.log(np.median(ratio))))
    return out


#: A left-out joint's relative error on a line is capped at this multiple of its median over the lines: a per-line
#: IRC joint is near singular on a few lines (the substructures' antiresonances), where ``Ẑ⁻¹`` spikes without
#: telling anything about the joint's level.
CAP_OVER_MEDIAN = 3.0


def _capped(rel: np.ndarray) -> np.ndarray:
    norm = np.linalg.norm(rel, axis=(1, 2))
    cap = CAP_OVER_MEDIAN * float(np.median(norm)) if norm.size else 0.0
    scale = np.where(norm > cap, cap / np.where(norm > 0, norm, 1.0), 1.0)
    return rel * scale[:, None, None]


def leave_one_out(load_frf: Callable[[JointVersion], FRF], pool: Sequence[Match], request: Conditions,
                  method: str = "axes") -> list[LooPoint]:
    """Predict every joint of ``pool`` from the others (module docstring).

    Parameters
    ----------
    load_frf
        Reads a version's verified FRF.
    pool
        Candidates of one joint type, model kind and DOFs (e.g. a query's nearest 64).
    request
        The request whose axes (the conditions it names) define the distance and the interpolation.
    method
        ``"axes"`` (interpolation between the bracketing joints, as ``interpolate: true``) or
        ``"nearest"`` (the nearest other joint, as a query without interpolation).

    Returns
    -------
    list[LooPoint]
        One per joint that has every condition the request names (at least 3 such joints are needed;
        fewer give an empty list).
    """
    from jointdb.store._query import interpolate

    usable = [(m, c) for m in pool if (c := _restricted(m.version, request)) is not None]
    if len(usable) < 3:
        return []
    cache: dict[tuple[str, int], FRF] = {}

    def load(v: JointVersion) -> FRF:
        key = (v.name, v.version)
        if key not in cache:
            cache[key] = load_frf(v)
        return cache[key]

    out = []
    for j, (m, cond) in enumerate(usable):
        others = [u[0] for i, u in enumerate(usable) if i != j]
        ranked = pool_distances(others, cond)
        ranked.sort(key=lambda x: x.distance)
        try:
            if method == "nearest":
                frf_hat = load(ranked[0].version)
            else:
                frf_hat = interpolate(load, ranked, cond).frf
            own = load(m.version)
            lo, hi = max(own.freq[0], frf_hat.freq[0]), min(own.freq[-1], frf_hat.freq[-1])
            if lo >= hi:
                continue
            grid = own.band(lo, hi).freq
            z_hat, z = _z(frf_hat, grid), _z(own, grid)
            err = _rel_error(z_hat, z)
            rel = _capped((z - z_hat) @ np.linalg.inv(z_hat))
        except (InputError, NumericalError, np.linalg.LinAlgError):
            continue  # a joint the others cannot be mixed into (no common band, singular): not a sample
        out.append(LooPoint(m.version.name, m.version.version, float(ranked[0].distance), err,
                            not ranked[0].extrapolating, grid, rel))
    return out


def choice_error_model(points: Sequence[LooPoint], distance: float, dofs: Sequence[str],
                       inside: bool = True) -> ChoiceErrorModel | None:
    """The straight-line error model ``σ = slope·δ`` (module docstring) at the request's ``distance``,
    from the left-out joints like the request: interpolations for a request inside the catalogued
    range (``inside``), edges for one outside (all points when none is like it); None without points
    at a positive distance."""
    pts = [p for p in points if p.distance > 1e-9]
    like = [p for p in pts if p.inside == inside]
    pts = like or pts
    if not pts:
        return None
    err = np.array([p.error for p in pts])
    dist = np.array([p.distance for p in pts])
    slope = np.sqrt(np.sum(err ** 2, axis=0) / np.sum(dist ** 2))
    return ChoiceErrorModel(tuple(dofs), slope, float(distance), tuple(pts))
