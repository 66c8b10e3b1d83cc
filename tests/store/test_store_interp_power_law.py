"""The interpolation combines each diagonal entry's storage and loss as a power law where they are positive
(jointdb.store._query.combine_stiffness): contact stiffness and damping that are powers of torque and shank
diameter come back exactly; entries that change sign, and off-diagonal entries, are averaged linearly."""

from __future__ import annotations

import math

import numpy as np
import pytest
from store_helpers import spring_joint

import jointdb.store._query as query
from jointdb.store import Conditions
from jointdb.store._query import combine_stiffness

MATS = ("tungsten-carbide", "steel")
GRID = [(0.010, 40.0), (0.010, 120.0), (0.020, 40.0), (0.020, 120.0)]


def _kc(d, t):
    """A contact that is a power law in torque and diameter, as a distributed layer's (k ∝ T^0.5 d², c ∝ T^0.3 d)."""
    return 2e7 * (t / 40.0) ** 0.5 * (d / 0.010) ** 2, 60.0 * (t / 40.0) ** 0.3 * (d / 0.010)


@pytest.fixture
def grid(repo):
    for d, t in GRID:
        repo.catalogue(f"th-d{round(d * 1e3):02d}-{int(t):03d}nm", "tool-holder", spring_joint(k=(_kc(d, t)[0], 8e4),
                                                                                           c=(_kc(d, t)[1], 0.5)),
                       Conditions(MATS, torque_nm=t, geometry={"shank_diameter_m": d}), "spring-damper-planar")
    return repo


def _z(ij):
    return 1.0 / ij.frf.values[:, 0, 0]


@pytest.mark.parametrize("d, t", [(0.014, 70.0), (0.011, 100.0), (0.018, 45.0)])
def test_a_power_law_contact_is_reproduced_exactly_and_the_linear_average_misses_it(grid, d, t, monkeypatch):
    req = Conditions(MATS, torque_nm=t, geometry={"shank_diameter_m": d})
    pool = grid.nearest("tool-holder", req, k=len(GRID))
    ij = grid.interpolate(pool, req)
    w = 2 * np.pi * ij.frf.freq
    k, c = _kc(d, t)
    np.testing.assert_allclose(_z(ij).real, k, rtol=1e-9)
    np.testing.assert_allclose(_z(ij).imag, w * c, rtol=1e-9)
    monkeypatch.setattr(query, "INTERPOLATION_LAW", "linear")
    lin = grid.interpolate(pool, req)
    # Jensen: the weighted mean of a convex function of the log coordinates lies above it (≥ 1 % here)
    assert np.all(_z(lin).real > 1.01 * k)


def test_an_entry_that_changes_sign_is_averaged_linearly_on_those_lines_only():
    w = np.full((2, 4), 0.5)
    part = np.zeros((2, 4, 2, 2))
    part[0, :, 0, 0] = [4.0, 4.0, 4.0, 4.0]
    part[1, :, 0, 0] = [1.0, 1.0, -2.0, 1.0]  # mass-like on line 2
    part[:, :, 1, 1] = [[9.0] * 4, [1.0] * 4]
    part[:, :, 0, 1] = part[:, :, 1, 0] = [[3.0] * 4, [-1.0] * 4]
    out = combine_stiffness(w, part)
    np.testing.assert_allclose(out[:, 0, 0], [2.0, 2.0, 1.0, 2.0], rtol=1e-12)  # √(4·1); linear 1.0 on line 2
    np.testing.assert_allclose(out[:, 1, 1], 3.0, rtol=1e-12)
    np.testing.assert_allclose(out[:, 0, 1], 1.0, rtol=1e-12)  # off-diagonal: linear
    np.testing.assert_allclose(out[:, 1, 0], 1.0, rtol=1e-12)


def test_a_neighbour_without_weight_on_a_line_does_not_block_the_power_law():
    # the passive-first loss weights give a non-passive neighbour no weight on its lines (test_store_interp_passive)
    w = np.array([[0.5, 1.0], [0.5, 0.0]])
    part = np.zeros((2, 2, 1, 1))
    part[0, :, 0, 0] = [4.0, 4.0]
    part[1, :, 0, 0] = [1.0, -3.0]
    out = combine_stiffness(w, part)
    np.testing.assert_allclose(out[:, 0, 0], [2.0, 4.0], rtol=1e-12)


def test_positive_loss_stays_positive_and_lies_between_the_neighbours():
    rng = np.random.default_rng(7)
    part = rng.uniform(0.1, 10.0, size=(3, 50, 2, 2))
    w = rng.dirichlet(np.ones(3), size=50).T
    out = combine_stiffness(w, part)
    for i in range(2):
        d = part[:, :, i, i]
        assert np.all(out[:, i, i] > 0)
        assert np.all(out[:, i, i] <= d.max(axis=0) * (1 + 1e-12)) and np.all(out[:, i, i] >= d.min(axis=0) * (1 - 1e-12))
        assert np.all(out[:, i, i] <= np.einsum("kf,kf->f", w, d) * (1 + 1e-12))  # the geometric mean ≤ the mean
    assert math.isclose(float(combine_stiffness(np.ones((1, 1)), np.full((1, 1, 1, 1), 5.0))[0, 0, 0]), 5.0)


def test_off_the_contact_lines_both_parts_of_every_entry_are_averaged_linearly():
    """A line where a neighbour is mass-like in one entry (Re Z_θθ < 0) or active (Im Z_xx < 0) is not a contact
    line: there storage and loss of every entry are linear means, so one joint is not built from two laws; a
    neighbour with no weight on a line does not count (jointdb.store._query.contact_lines)."""
    from jointdb.store._query import contact_lines

    w = np.full((2, 4), 0.5)
    z = np.empty((2, 4, 2, 2), complex)
    z[0] = np.array([[4.0 + 4.0j, 0.5], [0.5, 9.0 + 9.0j]])
    z[1] = np.array([[1.0 + 1.0j, -0.5], [-0.5, 1.0 + 1.0j]])
    z[1, 1, 1, 1] = -2.0 + 1.0j  # line 1: mass-like in θ
    z[1, 2, 0, 0] = 1.0 - 1.0j   # line 2: active in x
    w_last = w.copy()
    w_last[:, 3] = [1.0, 0.0]
    z[1, 3, 0, 0] = -5.0 - 5.0j  # line 3: only the neighbour without weight there is not a contact
    contact = contact_lines(w_last, z)
    np.testing.assert_array_equal(contact, [True, False, False, True])
    re = combine_stiffness(w_last, z.real, contact)
    np.testing.assert_allclose(re[[0, 3], 0, 0], [2.0, 4.0], rtol=1e-12)  # √(4·1); line 3: the weighted one only
    np.testing.assert_allclose(re[1, 0, 0], 2.5, rtol=1e-12)  # x is positive in both, yet linear on line 1
    np.testing.assert_allclose(re[2, 1, 1], 5.0, rtol=1e-12)
    im = combine_stiffness(w_last, z.imag, contact)
    np.testing.assert_allclose(im[[0, 3], 1, 1], [3.0, 9.0], rtol=1e-12)
    np.testing.assert_allclose(im[1, 1, 1], 5.0, rtol=1e-12)
    np.testing.assert_allclose(combine_stiffness(w, z.real, None)[1, 0, 0], 2.0, rtol=1e-12)  # no guard given
