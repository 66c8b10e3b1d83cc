"""Interpolation that respects the condition axes: the joints bracketing the request, barycentric weights in
ln(torque) and ln(geometry); inverse-distance weighting kept as ``method="idw"``."""

from __future__ import annotations

import math

import numpy as np
import pytest
from store_helpers import spring_joint

from jointdb.errors import InputError
from jointdb.store import Conditions, OutsideCatalogueWarning

MATS = ("tungsten-carbide", "steel")
#: (shank Ø [m], torque [N·m]) catalogued: a grid like a real campaign plan (Ø12 has a middle torque).
GRID = [(0.010, 40.0), (0.010, 120.0), (0.012, 40.0), (0.012, 80.0), (0.012, 120.0), (0.016, 40.0), (0.016, 120.0)]


def _k(d, t):
    """A stiffness that is a power law in torque and diameter, i.e. ln k linear in ln(torque) and ln(diameter) (what
    the interpolation must reproduce: jointdb.store._query.combine_stiffness)."""
    return 3e7 * (t / 40.0) ** (1 / 3) * (d / 0.010) ** 2


def _name(d, t):
    return f"th-d{round(d * 1e3):02d}-{int(t):03d}nm"


@pytest.fixture
def grid(repo):
    for d, t in GRID:
        repo.catalogue(_name(d, t), "tool-holder", spring_joint(k=(_k(d, t), 8e4)),
                       Conditions(MATS, torque_nm=t, geometry={"shank_diameter_m": d}), "spring-damper-planar")
    return repo


def _request(d, t):
    return Conditions(MATS, torque_nm=t, geometry={"shank_diameter_m": d})


def _k_of(ij):
    return (1.0 / ij.frf.values[:, 0, 0]).real


def test_on_an_edge_of_the_grid_only_the_joints_bracketing_the_torque_are_used(grid):
    req = _request(0.010, 90.0)
    pool = grid.nearest("tool-holder", req, k=len(GRID))
    # the two NEAREST are a Ø12 joint and Ø10 120 N·m: inverse distance mixes in the wrong shank
    assert {m.version.name for m in pool[:2]} == {"th-d12-080nm", "th-d10-120nm"}
    idw = grid.interpolate(pool[:2], req, method="idw")
    assert "th-d12-080nm" in {n for n, _, _ in idw.neighbours}
    ij = grid.interpolate(pool, req)
    w = {n: wt for n, _, wt in ij.neighbours}
    assert set(w) == {"th-d10-040nm", "th-d10-120nm"}
    t = math.log(90 / 40) / math.log(120 / 40)  # barycentric in ln(torque)
    assert w["th-d10-120nm"] == pytest.approx(t, rel=1e-9) and w["th-d10-040nm"] == pytest.approx(1 - t, rel=1e-9)
    assert np.allclose(_k_of(ij), _k(0.010, 90.0), rtol=1e-9)  # a power law of T: exact
    assert not np.allclose(_k_of(idw), _k(0.010, 90.0), rtol=1e-2)


@pytest.mark.parametrize("d, t", [(0.014, 110.0), (0.011, 60.0), (0.013, 45.0)])
def test_inside_the_grid_a_triangle_reproduces_a_power_law_exactly(grid, d, t):
    req = _request(d, t)
    ij = grid.interpolate(grid.nearest("tool-holder", req, k=len(GRID)), req)
    assert 2 <= len(ij.neighbours) <= 3
    assert sum(wt for _, _, wt in ij.neighbours) == pytest.approx(1.0, abs=1e-12)
    assert np.allclose(_k_of(ij), _k(d, t), rtol=1e-9)


def test_a_catalogued_request_takes_that_joint_alone(grid):
    req = _request(0.012, 80.0)
    ij = grid.interpolate(grid.nearest("tool-holder", req, k=len(GRID)), req)
    assert [(n, w) for n, _, w in ij.neighbours] == [("th-d12-080nm", 1.0)]


def test_outside_the_grid_the_nearest_edge_not_an_extrapolation(grid):
    req = _request(0.012, 200.0)
    with pytest.warns(OutsideCatalogueWarning, match="torque_nm"):
        pool = grid.nearest("tool-holder", req, k=len(GRID))
    ij = grid.interpolate(pool, req)
    assert [n for n, _, _ in ij.neighbours] == ["th-d12-120nm"]
    assert np.allclose(_k_of(ij), _k(0.012, 120.0), rtol=1e-9)


def test_joints_at_the_same_conditions_share_the_weight(grid):
    grid.catalogue("th-d10-040nm-repeat", "tool-holder", spring_joint(k=(2 * _k(0.010, 40.0), 8e4)),
                   Conditions(MATS, torque_nm=40.0, geometry={"shank_diameter_m": 0.010}), "spring-damper-planar")
    req = _request(0.010, 40.0)
    ij = grid.interpolate(grid.nearest("tool-holder", req, k=len(GRID) + 1), req)
    assert sorted((n, w) for n, _, w in ij.neighbours) == [("th-d10-040nm", 0.5), ("th-d10-040nm-repeat", 0.5)]


def test_without_a_numeric_axis_inverse_distance_and_a_bad_method_is_refused(grid):
    req = Conditions(MATS)
    pool = grid.nearest("tool-holder", req, k=3)
    ij = grid.interpolate(pool, req)
    assert len(ij.neighbours) == 3 and all(w == pytest.approx(1 / 3) for _, _, w in ij.neighbours)
    with pytest.raises(InputError, match="interpolation method"):
        grid.interpolate(pool, req, method="nearest")


def test_on_a_grid_cell_with_no_unique_triangulation_the_weights_do_not_depend_on_the_order(repo):
    """Four catalogued corners of a rectangle (ln Ø × ln T) lie on one circle: either diagonal is a Delaunay
    triangulation. The weights must not pick one by the order of the candidates: at the centre, a quarter each."""
    corners = [(0.010, 40.0), (0.010, 160.0), (0.016, 40.0), (0.016, 160.0)]
    for d, t in corners:
        repo.catalogue(_name(d, t), "tool-holder", spring_joint(k=(_k(d, t), 8e4)),
                       Conditions(MATS, torque_nm=t, geometry={"shank_diameter_m": d}), "spring-damper-planar")
    centre = _request(math.sqrt(0.010 * 0.016), 80.0)  # the middle of the cell on the log axes
    pool = repo.nearest("tool-holder", centre, k=4)
    weights = []
    for order in (pool, pool[::-1], pool[1:] + pool[:1]):
        ij = repo.interpolate(order, centre)
        weights.append({n: w for n, _, w in ij.neighbours})
        assert np.allclose(_k_of(ij), _k(*[math.sqrt(0.010 * 0.016), 80.0]), rtol=1e-9)  # a power law: exact
    for w in weights:
        assert len(w) == 4 and all(v == pytest.approx(0.25, abs=1e-9) for v in w.values())
    # off-centre in the same cell: still independent of the order
    off = _request(0.011, 60.0)
    pool = repo.nearest("tool-holder", off, k=4)
    a = {n: w for n, _, w in repo.interpolate(pool, off).neighbours}
    b = {n: w for n, _, w in repo.interpolate(pool[::-1], off).neighbours}
    assert a.keys() == b.keys() and all(a[k] == pytest.approx(b[k], abs=1e-9) for k in a)
