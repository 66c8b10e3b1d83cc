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

An interpolated request is served differently: it lies *between* catalogued lines (a shank diameter
between Ø8 and Ø12, a torque between two torques), and its error is that of interpolating across that
gap, which a single left-out joint (its neighbours on the same lines) does not measure.
:func:`leave_line_out` therefore leaves out whole interior condition lines, interpolates every joint on
them from the joints off the line, and keeps each error with its gap product ``(v − v₋)(v₊ − v)``;
a request draws them scaled by its own gap product over theirs (:func:`request_gaps`; linear
interpolation errs by ``½ f''·(r − v₋)(v₊ − r)``), zero on a catalogued line, one independent
draw per axis (:func:`line_error_model`).

Pure numerics on the pool the caller already has (``load_frf`` reads the blobs);
no query is issued here.
"""

from __future__ import annotations

import json
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from jointdb.errors import InputError, NumericalError
from jointdb.frf import FRF
from jointdb.store._candidates import _NULL, Candidates
from jointdb.store._types import Conditions, JointVersion, Match

#: Conditions → the ``(2, 2)`` inserted-shank mass matrix of a tool–holder joint over (x, ry), or None when the
#: conditions do not give it (:class:`jointdb.usecases._stack_shank.ShankInertia`).
Inertia = Callable[[Conditions], "np.ndarray | None"]

__all__ = ["LooPoint", "ChoiceErrorModel", "leave_one_out", "leave_line_out", "request_gaps", "line_error_model",
           "choice_error_model", "pool_distances"]


@dataclass(frozen=True, eq=False)
class LooPoint:
    """One left-out joint: ``name``, ``version``, its distance to the nearest other joint of the pool,
    ``error`` ``(n_dof, 2)``: the level error of (Re Z, Im Z) per diagonal DOF (:func:`_rel_error`) when
    predicted from the others; ``inside``: its conditions lie inside the others' catalogued range (an
    interpolation, not an edge); ``freq`` and ``relative`` ``(n_freq, n_dof, n_dof)``: the relative error
    of the prediction per line, ``R = (Z − Ẑ) Ẑ⁻¹`` (so that ``Z = (I + R) Ẑ``). A point of a whole
    condition line left out (:func:`leave_line_out`) names its ``axis`` and its ``gap``: the product
    ``(v − v₋)(v₊ − v)`` of its distances to the lines bracketing it on that axis (ln units)."""

    name: str
    version: int
    distance: float
    error: np.ndarray
    inside: bool = True
    freq: np.ndarray | None = None
    relative: np.ndarray | None = None
    axis: str = ""
    gap: float = 0.0


@dataclass(frozen=True)
class ChoiceErrorModel:
    """``σ(δ) = slope·δ`` per DOF and part (``slope`` ``(n_dof, 2)``: re, im), fitted on ``points``.

    ``dofs``: the joint's DOFs (labels); ``distance``: the request's distance to the nearest
    catalogued joint of the pool; ``sigma``: ``slope·distance``, the relative standard error of
    the joint's dynamic stiffness from the choice; ``gaps``: the request's gap product per condition
    axis (:func:`request_gaps`), which scales the points of lines left out along that axis.
    """

    dofs: tuple[str, ...]
    slope: np.ndarray
    distance: float
    points: tuple[LooPoint, ...]
    gaps: Mapping[str, float] = field(default_factory=dict)

    @property
    def sigma(self) -> np.ndarray:
        return self.slope * self.distance

    def on_grid(self, freq: np.ndarray, order: Sequence[int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The left-out joints' relative errors as perturbations for a band: ``(R, scale, group)``.

        Parameters
        ----------
        freq : ndarray, shape (n_freq,)
            Lines [Hz] of the prediction.
        order : sequence of int
            The joint's DOFs in the order the band wants them.

        Returns
        -------
        R : ndarray, shape (m, n_freq, n, n)
            Each point's relative error ``(Z − Ẑ) Ẑ⁻¹`` on ``freq`` (linear in real and imaginary parts, held
            constant beyond its own band), DOFs in ``order``.
        scale : ndarray, shape (m,)
            For a point of a line left out along an axis: the request's gap product on that axis over the
            point's (interpolation error ∝ f''·(v − v₋)(v₊ − v)/2, so a request on a catalogued line of that axis
            gets nothing from it and one mid-way between two lines the most); for a single left-out joint: the
            request's distance over the point's (the straight line of :class:`ChoiceErrorModel`).
        group : ndarray of int, shape (m,)
            The axis of each point (0 for single joints): a band draws one error per group and adds them.
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
        axes = sorted({p.axis for p in self.points})
        scale = np.array([self.gaps.get(p.axis, 0.0) / p.gap if p.axis else self.distance / p.distance
                          for p in self.points])
        group = np.array([axes.index(p.axis) for p in self.points], dtype=int)
        return np.array(rs), scale, group

    def to_json(self) -> dict:
        return {"dofs": list(self.dofs), "request_distance": self.distance, "request_gaps": dict(self.gaps),
                "slope_per_unit_distance": {"re": self.slope[:, 0].tolist(), "im": self.slope[:, 1].tolist()},
                "sigma": {"re": self.sigma[:, 0].tolist(), "im": self.sigma[:, 1].tolist()},
                "leave_one_out": [{"joint": f"{p.name}@{p.version}", "distance": p.distance,
                                   "axis": p.axis or None, "gap": p.gap or None,
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
    from jointdb.store._nearest import unvaried_machine_conditions
    from jointdb.store._rank import rank

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
            keep = ((mag >= mag.mean() / 3) & (mag > 0)) if mag.size else mag > 0  # a part 0 throughout: no ratio
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
                  method: str = "axes", inertia: Inertia | None = None) -> list[LooPoint]:
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
    inertia
        Conditions → the ``(2, 2)`` inserted-shank mass matrix of a tool–holder joint (or None): each prediction
        exchanges the mixed joints' shank inertia for the left-out joint's, as a stack's prediction does
        (:func:`jointdb.stack._shank.move_shank_inertia`). None: no exchange.

    Returns
    -------
    list[LooPoint]
        One per joint that has every condition the request names (at least 3 such joints are needed;
        fewer give an empty list).
    """
    usable = [(m, c) for m in pool if (c := _restricted(m.version, request)) is not None]
    if len(usable) < 3:
        return []
    load = _cached(load_frf)
    out = []
    for j, (m, cond) in enumerate(usable):
        p = _predicted(load, m, cond, [u[0] for i, u in enumerate(usable) if i != j], method, inertia=inertia)
        if p is not None:
            out.append(p)
    return out


def _shank_moved(frf: FRF, used: Sequence[tuple[str, int, float]], ranked: Sequence[Match], own: JointVersion,
                 inertia: Inertia) -> FRF:
    """``frf`` mixed from ``used`` (``(name, version, weight)`` of versions in ``ranked``) with their shanks'
    inertia exchanged for ``own``'s (:func:`jointdb.stack._shank.exchange_shanks`; unchanged when there is
    nothing to exchange)."""
    from jointdb.stack._shank import exchange_shanks

    by_key = {(r.version.name, r.version.version): r.version for r in ranked}
    if any((n, v) not in by_key for n, v, _ in used):
        return frf
    out = exchange_shanks(frf, [(w, inertia(by_key[(n, v)].conditions)) for n, v, w in used],
                          inertia(own.conditions))
    return frf if out is None else out


def _cached(load_frf: Callable[[JointVersion], FRF]) -> Callable[[JointVersion], FRF]:
    cache: dict[tuple[str, int], FRF] = {}

    def load(v: JointVersion) -> FRF:
        key = (v.name, v.version)
        if key not in cache:
            cache[key] = load_frf(v)
        return cache[key]

    return load


def _predicted(load, m: Match, cond: Conditions, others: Sequence[Match], method: str = "axes",
               axis: str = "", gap: float = 0.0, inertia: Inertia | None = None) -> LooPoint | None:
    """``m``'s joint predicted from ``others`` at its conditions ``cond``; None when they cannot be mixed."""
    from jointdb.store._query import interpolate

    ranked = pool_distances(others, cond)
    ranked.sort(key=lambda x: x.distance)
    try:
        if method == "nearest":
            first = ranked[0].version
            frf_hat, used = load(first), ((first.name, first.version, 1.0),)
        else:
            joint = interpolate(load, ranked, cond)
            frf_hat, used = joint.frf, joint.neighbours
        if inertia is not None:
            frf_hat = _shank_moved(frf_hat, used, ranked, m.version, inertia)
        own = load(m.version)
        lo, hi = max(own.freq[0], frf_hat.freq[0]), min(own.freq[-1], frf_hat.freq[-1])
        if lo >= hi:
            return None
        grid = own.band(lo, hi).freq
        z_hat, z = _z(frf_hat, grid), _z(own, grid)
        err = _rel_error(z_hat, z)
        rel = _capped((z - z_hat) @ np.linalg.inv(z_hat))
    except (InputError, NumericalError, np.linalg.LinAlgError):
        return None  # a joint the others cannot be mixed into (no common band, singular): not a sample
    return LooPoint(m.version.name, m.version.version, float(ranked[0].distance), err, not ranked[0].extrapolating,
                    grid, rel, axis, gap)


# ------------------------------------------------------------------ whole condition lines left out
#: With only two catalogued lines on an axis the curvature along it is unknown. Each line is then predicted from
#: the other (the difference between them, ``D``) and a request mid-way between them is taken to err by this
#: fraction of ``D`` (a smooth monotone law deviates from its chord by a fraction of the rise between its ends;
#: a power law in ln(value) by nothing).
TWO_LINE_FRACTION = 0.25


def _axis_values(conditions: Conditions, request: Conditions) -> dict[str, float]:
    """ln of each numeric condition the request names (axis name → value), as :mod:`jointdb.store._interp`."""
    out = {}
    for name in ("torque_nm", "preload_n"):
        v, r = getattr(conditions, name), getattr(request, name)
        if r is not None and v is not None and v > 0:
            out[name] = float(np.log(v))
    for key, r in request.geometry.items():
        v = (conditions.geometry or {}).get(key)
        if isinstance(v, (int, float)) and not isinstance(v, bool) and v > 0 and isinstance(r, (int, float)):
            out[f"geometry.{key}"] = float(np.log(v))
    return out


def _lines(coords: Sequence[dict[str, float]], axis: str) -> np.ndarray:
    """The distinct catalogued values (ln) on ``axis``, sorted (values within 1e-9 are one line)."""
    vals = sorted(c[axis] for c in coords if axis in c)
    out: list[float] = []
    for v in vals:
        if not out or v - out[-1] > 1e-9:
            out.append(v)
    return np.array(out)


def _gap(lines: np.ndarray, r: float) -> float:
    """``|(r − a)(b − r)|`` for the cell ``[a, b]`` of ``lines`` holding ``r`` (the nearest cell outside them);
    0 on a line."""
    if lines.size < 2 or np.min(np.abs(lines - r)) <= 1e-6:
        return 0.0
    i = int(np.clip(np.searchsorted(lines, r), 1, lines.size - 1))
    return float(abs((r - lines[i - 1]) * (lines[i] - r)))


def request_gaps(pool: Sequence[Match], request: Conditions) -> dict[str, float]:
    """The request's gap product per condition axis it names: ``(r − v₋)(v₊ − r)`` in ln units between the
    catalogued lines of ``pool`` bracketing it (0 on a line; axes the pool holds at fewer than two values are
    left out)."""
    coords = [_axis_values(c, request) for m in pool if (c := _restricted(m.version, request)) is not None]
    here = _axis_values(request, request)
    return {a: _gap(lines, r) for a, r in here.items() if (lines := _lines(coords, a)).size >= 2}


def leave_line_out(load_frf: Callable[[JointVersion], FRF], pool: Sequence[Match],
                   request: Conditions, inertia: Inertia | None = None) -> list[LooPoint]:
    """Leave out whole condition lines and interpolate them across the gap (how a request between lines is served).

    For each numeric axis the request names and each *interior* catalogued line on it (a diameter, a torque with
    lines on both sides), every joint on that line is predicted from the joints *off* it
    (:func:`jointdb.store._query.interpolate`, the bracketing simplex), so across a gap as wide as the two cells
    around the line: its ``gap`` is ``(v − v₋)(v₊ − v)``. On an axis with two lines only, each line is predicted
    from the other and its gap is ``h²/(4·TWO_LINE_FRACTION)`` (``h`` the spacing), so that a request mid-way
    (gap product ``h²/4``) draws :data:`TWO_LINE_FRACTION` of the difference.

    Parameters
    ----------
    load_frf
        Reads a version's verified FRF.
    pool
        Candidates of one joint type, model kind and DOFs.
    request
        The request whose axes define the lines.
    inertia
        As :func:`leave_one_out`.

    Returns
    -------
    list[LooPoint]
        Points with ``axis`` and ``gap`` set; empty when no axis has two lines or more, or fewer than 3 joints
        have every condition the request names.
    """
    usable = [(m, c) for m in pool if (c := _restricted(m.version, request)) is not None]
    if len(usable) < 3:  # as leave_one_out: two joints cannot tell their error from the law between them
        return []
    coords = [_axis_values(c, request) for _, c in usable]
    load = _cached(load_frf)
    out = []
    for axis in _axis_values(request, request):
        lines = _lines(coords, axis)
        if lines.size < 2:
            continue
        for k, v in enumerate(lines):
            if lines.size == 2:
                gap = float((lines[1] - lines[0]) ** 2 / 4.0 / TWO_LINE_FRACTION)
            elif 0 < k < lines.size - 1:
                gap = float((v - lines[k - 1]) * (lines[k + 1] - v))
            else:
                continue
            on = [i for i, c in enumerate(coords) if axis in c and abs(c[axis] - v) <= 1e-9]
            off = [usable[i][0] for i, c in enumerate(coords) if axis in c and abs(c[axis] - v) > 1e-9]
            if len(off) < 1:
                continue
            for i in on:
                p = _predicted(load, usable[i][0], usable[i][1], off, "axes", axis, gap, inertia)
                if p is not None:
                    out.append(p)
    return out


def line_error_model(load_frf: Callable[[JointVersion], FRF], pool: Sequence[Match], request: Conditions,
                     distance: float, dofs: Sequence[str], inside: bool = True,
                     inertia: Inertia | None = None) -> ChoiceErrorModel | None:
    """The joint-choice error of an interpolated request: whole lines left out (:func:`leave_line_out`), scaled by
    the request's gaps (:func:`request_gaps`).

    A request off the catalogue along an axis the pool holds at one value only (a machine condition never
    varied) keeps the single-joint leave-one-out as well (:func:`leave_one_out`, scaled by distance): no line
    says how much that axis matters. Without any line the single-joint model is returned
    (:func:`choice_error_model`).

    Parameters
    ----------
    load_frf, pool, request
        As :func:`leave_line_out`.
    distance
        The request's distance to the nearest catalogued joint of the pool.
    dofs
        The joint's DOF labels.
    inside
        Whether the request lies inside the catalogued range.
    inertia
        As :func:`leave_one_out`.

    Returns
    -------
    ChoiceErrorModel or None
    """
    lines = leave_line_out(load_frf, pool, request, inertia)
    gaps = request_gaps(pool, request)
    coords = [_axis_values(c, request) for m in pool if (c := _restricted(m.version, request)) is not None]
    here = _axis_values(request, request)
    unvaried = [a for a, r in here.items() if (v := _lines(coords, a)).size == 1 and abs(v[0] - r) > 1e-6]
    single = leave_one_out(load_frf, pool, request, inertia=inertia) if (unvaried or not lines) else []
    base = choice_error_model(single, distance, dofs, inside) if single else None
    if not lines:
        return base
    pts = tuple(lines) + (base.points if base is not None else ())
    model = ChoiceErrorModel(tuple(dofs), np.zeros((len(dofs), 2)), float(distance), pts, gaps)
    # the summary σ (``--json``): per axis the mean square of the scaled level errors, summed over the axes
    err = np.array([p.error for p in pts])
    scale = np.array([gaps.get(p.axis, 0.0) / p.gap if p.axis else distance / p.distance for p in pts])
    var = sum(np.mean((err[g] * scale[g, None, None]) ** 2, axis=0)
              for a in {p.axis for p in pts} if (g := np.array([p.axis == a for p in pts])).any())
    return replace(model, slope=np.sqrt(var) / distance if distance > 1e-12 else np.zeros_like(np.sqrt(var)))


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
