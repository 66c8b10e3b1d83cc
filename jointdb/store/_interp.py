"""Interpolation weights that respect the condition axes (piecewise-linear on the catalogued conditions).

Inverse-distance weighting of the nearest joints mixes axes: a request for a
Ø10 mm shank at 90 N·m, with Ø10 joints catalogued at 40 and 120 N·m and a Ø12
joint at 80 N·m, takes the Ø12 joint (one distance unit away in diameter) and
the Ø10 120 N·m joint, never the Ø10 40 N·m joint that brackets the torque —
and so predicts the joint of a shank it never saw. This module instead finds the
catalogued conditions that *bracket* the request and their barycentric weights.

Coordinates
-----------
Each numeric condition the request gives is one axis, on a log scale (contact
stiffness grows as a power of torque and force, so catalogues space them
geometrically): ``ln(torque)``, ``ln(preload)``, divided by the log spread of the
candidates as in the query distance (``jointdb.store._query``), and ``ln(value)`` of
each positive geometry key (its relative difference, as in the distance). A
candidate lacking a value on some axis cannot be placed and takes no weight (unless
no candidate can be placed: then the caller falls back).

The caller (``jointdb.store._query.combine_stiffness``) combines each diagonal entry's
storage ``Re Z_ii`` and loss ``Im Z_ii`` geometrically with these weights on the lines where
every neighbour's storage and loss are positive on every diagonal entry (``contact_lines``), so a
power law ``k ∝ T^n d^m`` is reproduced exactly (linear weights would make k 2.7 % too stiff for
n = 0.5, joints at 40 and 120 N·m, request 90 N·m), and averages linearly on the other lines (a
shank resonating on its contact layer makes ``Re Z_xx`` negative above it) and off the diagonal. (A complex
``ln Z`` of whole entries was tried before and was worse: it is ill-defined where the
entries change sign.)

Weights
-------
The linear programme

    minimise   Σ w_i (|x_i − r|² + m_i²) + Λ Σ |s|
    subject to Σ w_i x_i + s = r,  Σ w_i = 1,  w_i ≥ 0

(``x_i`` a candidate's coordinates, ``r`` the request's, ``m_i`` its materials
distance, ``s`` a slack used only outside the candidates' hull) picks the
simplex of the Delaunay triangulation of the candidates that contains the
request, with its barycentric weights (the "lifting" characterisation of
Delaunay triangulations): two joints bracketing the request along one axis, three
on a triangle of a 2-D grid, one when the request is catalogued. Quantities that
vary linearly in those coordinates are reproduced exactly inside the hull; outside
it the request is projected onto the hull (the nearest catalogued edge: no
extrapolation beyond the catalogue, which the query warns about anyway).
Candidates at identical conditions share their weight equally.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from jointdb.store._types import Conditions, Match

__all__ = ["axis_coordinates", "bracketing_weights"]

_MIN_LOG_SPREAD = math.log(2.0)
#: weights and slacks below the LP solver's feasibility tolerance are round-off, not a choice
_DROP = 1e-7


def _log_axis(values: list[float | None], request: float, spread_scale: bool) -> tuple[np.ndarray, float] | None:
    have = [v for v in values if v is not None and v > 0]
    if request is None or request <= 0 or not have:
        return None
    logs = np.array([math.log(v) if v is not None and v > 0 else np.nan for v in values])
    scale = 1.0
    if spread_scale:
        scale = max(float(np.nanmax(logs) - np.nanmin(logs)), _MIN_LOG_SPREAD)
    return logs / scale, math.log(request) / scale


def axis_coordinates(request: Conditions, matches: Sequence[Match]) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Coordinates of the candidates and the request on the request's numeric axes (module docstring).

    Returns
    -------
    (x, r, axes)
        ``x`` ``(n_candidates, n_axes)`` (NaN where a candidate lacks a value), ``r`` ``(n_axes,)``,
        and the axis names (``torque_nm``, ``preload_n``, ``geometry.<key>``).
    """
    cols, r, axes = [], [], []
    conds = [m.version.conditions for m in matches]
    for name in ("torque_nm", "preload_n"):
        req = getattr(request, name)
        if req is None:
            continue
        got = _log_axis([getattr(c, name) for c in conds], req, spread_scale=True)
        if got is not None:
            cols.append(got[0])
            r.append(got[1])
            axes.append(name)
    for key, req in request.geometry.items():
        got = _log_axis([(c.geometry or {}).get(key) for c in conds], float(req), spread_scale=False)
        if got is not None:
            cols.append(got[0])
            r.append(got[1])
            axes.append(f"geometry.{key}")
    x = np.column_stack(cols) if cols else np.zeros((len(matches), 0))
    return x, np.asarray(r, dtype=float), axes


def bracketing_weights(request: Conditions, matches: Sequence[Match]) -> np.ndarray | None:
    """Barycentric weights of ``matches`` for ``request`` (module docstring), or None when the request gives
    no numeric axis on which some candidate can be placed (the caller then uses inverse-distance weights).

    Returns
    -------
    ndarray ``(len(matches),)`` or None
        Non-negative weights summing to 1; zero for candidates off the chosen simplex.
    """
    from scipy.optimize import linprog

    x, r, axes = axis_coordinates(request, matches)
    if not axes:
        return None
    placed = np.flatnonzero(np.all(np.isfinite(x), axis=1))
    if placed.size == 0:
        return None
    mats = np.array([m.per_condition.get("materials", 0.0) for m in matches])
    # candidates at identical coordinates and materials distance are one point sharing its weight
    keys: dict[tuple, list[int]] = {}
    for i in placed:
        keys.setdefault(tuple(np.round(np.append(x[i], mats[i]), 12)), []).append(int(i))
    groups = list(keys.values())
    pts = np.array([x[g[0]] for g in groups])
    cost = np.array([float(np.sum((x[g[0]] - r) ** 2) + mats[g[0]] ** 2) for g in groups])
    n, d = pts.shape
    big = 1e3 * (1.0 + float(cost.max()))
    # variables: w (n), s_plus (d), s_minus (d)
    c = np.concatenate([cost, np.full(2 * d, big)])
    a_eq = np.zeros((d + 1, n + 2 * d))
    a_eq[:d, :n] = pts.T
    a_eq[:d, n:n + d] = np.eye(d)
    a_eq[:d, n + d:] = -np.eye(d)
    a_eq[d, :n] = 1.0
    b_eq = np.append(r, 1.0)
    bounds = [(0, None)] * (n + 2 * d)
    res = linprog(c, A_eq=a_eq, b_eq=b_eq, bounds=bounds, method="highs")
    if res.status != 0:  # pragma: no cover - the programme is always feasible (slacks) and bounded (w ≥ 0)
        return None
    z = _centre_of_optimal_face(res, c, a_eq, b_eq, bounds, n)
    wg = _polished(z, a_eq[:, :n], r, n, d)
    w = np.zeros(len(matches))
    for weight, g in zip(wg, groups):
        w[g] = weight / len(g)
    return w / w.sum()


def _polished(z: np.ndarray, a: np.ndarray, r: np.ndarray, n: int, d: int) -> np.ndarray:
    """The weights of a solver's solution ``z`` made exact: weights below the solver's feasibility
    tolerance dropped, then the smallest correction on the remaining support that satisfies
    ``Σ w x = r − s`` and ``Σ w = 1`` to round-off (``s`` the slack, zero inside the hull)."""
    w = np.clip(z[:n], 0.0, None)
    w[w < _DROP] = 0.0
    support = np.flatnonzero(w)
    slack = z[n:n + d] - z[n + d:]
    slack[np.abs(slack) < _DROP] = 0.0
    target = np.append(r - slack, 1.0)
    block = a[:, support]
    w[support] += np.linalg.lstsq(block, target - block @ w[support], rcond=None)[0]
    return np.clip(w, 0.0, None)


def _centre_of_optimal_face(res, c, a_eq, b_eq, bounds, n: int) -> np.ndarray:
    """One canonical optimum when the optimum is not unique (degenerate Delaunay cells).

    Catalogues are planned on grids, and four corners of a grid cell lie on one circle: the
    Delaunay triangulation of the cell is then not unique, every triangulation is optimal, and
    the solver's vertex would pick one diagonal by the order of the candidates. Instead: the
    candidates that can carry weight in some optimum are those with zero reduced cost; for each,
    the optimum that gives it the most weight; their mean (itself optimal, since the optimal set
    is convex) is returned. It does not depend on the candidates' order, is symmetric on a
    symmetric cell (the centre of a rectangle: a quarter each) and, like every optimum,
    reproduces quantities linear in the coordinates exactly. A unique optimum is returned as is.
    """
    try:
        duals = np.asarray(res.eqlin.marginals, dtype=float)
    except AttributeError:  # pragma: no cover - older SciPy without HiGHS marginals
        return res.x
    reduced = c[:n] - a_eq[:, :n].T @ duals
    tol = 1e-9 * (1.0 + float(np.abs(c[:n]).max()))
    face = np.flatnonzero(reduced <= tol)
    if face.size <= int(np.count_nonzero(res.x[:n] > 1e-12)):
        return res.x  # every candidate that can carry weight already does: the optimum is unique
    from scipy.optimize import linprog

    cap = float(res.fun) + tol
    optima = []
    for j in face:
        obj = np.zeros_like(c)
        obj[j] = -1.0
        sub = linprog(obj, A_ub=c[None, :], b_ub=[cap], A_eq=a_eq, b_eq=b_eq, bounds=bounds, method="highs")
        if sub.status == 0:
            optima.append(sub.x)
    return np.mean(optima, axis=0) if optima else res.x

