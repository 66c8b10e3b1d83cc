"""Interpolation takes no energy-generating loss of a neighbour where another neighbour is passive (issue 22:
the short end mills' 9–10 kHz peaks, docs/validation/stack-bands-family-c.md, *High modes*)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from jointdb.frf import FRF
from jointdb.store import Conditions
from jointdb.store._query import passive_line_weights

MATS = ("tungsten-carbide", "steel")
F = np.linspace(100.0, 12000.0, 120)
W = 2 * np.pi * F
#: lines where the Ø10 joint is non-passive (a stretch, as its IRC flags near an internal resonance)
STRETCH = (F > 9000.0) & (F < 10500.0)


def _z(k, eta, c, flip=None):
    """Diagonal dynamic stiffness ``k (1 + iη) + iωc`` on (x, ry); ``flip``: lines whose x term loses energy
    with the wrong sign (Im Z_xx negated)."""
    z = np.zeros((F.size, 2, 2), complex)
    z[:, 0, 0] = k[0] * (1 + 1j * eta) + 1j * W * c[0]
    z[:, 1, 1] = k[1] * (1 + 1j * eta) + 1j * W * c[1]
    if flip is not None:
        z[flip, 0, 0] = z[flip, 0, 0].conj()
    return z


Z6 = _z((2e7, 2e4), 0.06, (50.0, 0.01))
Z10 = _z((5e7, 4e4), 0.06, (120.0, 0.02), flip=STRETCH)


def _power_mix(t):
    """``Z6`` and ``Z10`` combined as documented where both parts are positive (jointdb.store._query.
    combine_stiffness): each diagonal entry's storage and loss as the weighted geometric mean (the off-diagonal
    entries are 0 in both). The loss is meaningful off ``STRETCH`` only."""
    return (Z6.real ** (1 - t) * Z10.real ** t
            + 1j * np.abs(Z6.imag) ** (1 - t) * np.abs(Z10.imag) ** t)


def _frf(z):
    return FRF(F, np.linalg.inv(z), ["3x", "3ry"], ["3x", "3ry"])


@pytest.fixture
def pair(repo):
    for name, d, z in (("th-d06", 0.006, Z6), ("th-d10", 0.010, Z10)):
        repo.catalogue(name, "tool-holder", _frf(z), Conditions(MATS, torque_nm=60.0, geometry={"shank_diameter_m": d}),
                       "spring-damper-planar")
    return repo


def test_weights_move_off_non_passive_lines_only_where_a_passive_neighbour_exists():
    z = np.stack([Z6, Z10, Z10])
    w, moved = passive_line_weights(np.array([0.5, 0.3, 0.2]), z)
    assert np.allclose(w.sum(axis=0), 1.0, atol=1e-15)
    assert np.allclose(w[:, ~STRETCH], np.array([[0.5], [0.3], [0.2]]), atol=1e-15)  # all passive: nominal
    assert np.allclose(w[:, STRETCH], np.array([[1.0], [0.0], [0.0]]), atol=1e-15)
    assert moved.tolist() == [0, int(STRETCH.sum()), int(STRETCH.sum())]
    # every neighbour non-passive on a line: nothing better to take, the nominal weights stay
    w2, moved2 = passive_line_weights(np.array([0.4, 0.6]), np.stack([Z10, Z10]))
    assert np.allclose(w2, np.array([[0.4], [0.6]]), atol=1e-15) and moved2.tolist() == [0, 0]


def test_where_the_plain_average_stays_passive_the_nominal_weights_stay():
    # 0.9 of the passive Ø6 joint outweighs 0.1 of Ø10's wrong-signed loss: the plain average is passive
    nominal = 0.9 * Z6 + 0.1 * Z10
    assert np.all(np.diagonal(nominal, axis1=1, axis2=2).imag > 0)
    w, moved = passive_line_weights(np.array([0.9, 0.1]), np.stack([Z6, Z10]))
    assert np.allclose(w, np.array([[0.9], [0.1]]), atol=1e-15) and moved.tolist() == [0, 0]
    # 0.5 / 0.5: the plain average loses energy on the stretch; there the loss is Ø6's alone
    w, moved = passive_line_weights(np.array([0.5, 0.5]), np.stack([Z6, Z10]))
    assert np.all(np.diagonal(0.5 * Z6 + 0.5 * Z10, axis1=1, axis2=2).imag[STRETCH].min(axis=1) < 0)
    assert np.allclose(w[:, STRETCH], np.array([[1.0], [0.0]])) and moved.tolist() == [0, int(STRETCH.sum())]


def test_a_zero_weight_neighbour_counts_no_moved_lines():
    w, moved = passive_line_weights(np.array([1.0, 0.0]), np.stack([Z6, Z10]))
    assert np.allclose(w, np.array([[1.0], [0.0]])) and moved.tolist() == [0, 0]


def test_interpolated_joint_is_the_passive_neighbour_on_the_stretch_and_the_mix_elsewhere(pair):
    req = Conditions(MATS, torque_nm=60.0, geometry={"shank_diameter_m": 0.007})
    ij = pair.interpolate(pair.nearest("tool-holder", req, k=2), req)
    w = {n: wt for n, _, wt in ij.neighbours}
    t = math.log(7 / 6) / math.log(10 / 6)  # barycentric in ln(diameter)
    assert w["th-d10"] == pytest.approx(t, rel=1e-9)
    z = np.linalg.inv(ij.frf.values)
    nominal = (1 - t) * Z6 + t * Z10
    mix = _power_mix(t)
    assert np.allclose(z[~STRETCH], mix[~STRETCH], rtol=1e-9)
    # on the stretch: the storage stiffness of both, averaged linearly (Ø10 is no contact there: the power law is
    # not used, jointdb.store._query.contact_lines), the loss of the passive Ø6 joint alone
    assert np.allclose(z[STRETCH].real, nominal[STRETCH].real, rtol=1e-9)
    assert not np.allclose(z[STRETCH].real, mix[STRETCH].real, rtol=1e-3)
    assert np.allclose(z[STRETCH].imag, Z6[STRETCH].imag, rtol=1e-9)
    assert np.all(np.diagonal(z, axis1=1, axis2=2).imag > 0)  # passive on every line
    # the plain average would have lost the x loss on the stretch (what the short end mills suffered)
    assert np.min(nominal[STRETCH, 0, 0].imag / Z6[STRETCH, 0, 0].imag) < 0.5
    assert ij.passivity_moved == (("th-d10", 1, int(STRETCH.sum())),)


def test_all_passive_neighbours_interpolate_as_before(pair):
    req = Conditions(MATS, torque_nm=60.0, geometry={"shank_diameter_m": 0.007})
    pool = [m for m in pair.nearest("tool-holder", req, k=2)]
    ij = pair.interpolate(pool, req)
    z = np.linalg.inv(ij.frf.values)
    t = math.log(7 / 6) / math.log(10 / 6)
    assert np.allclose(z[~STRETCH, 1, 1], _power_mix(t)[~STRETCH, 1, 1], rtol=1e-9)


def test_the_prediction_notes_the_left_out_lines_once(pair):
    from jointdb.usecases._stack import _passivity_notes

    req = Conditions(MATS, torque_nm=60.0, geometry={"shank_diameter_m": 0.007})
    notes = _passivity_notes(pair.interpolate(pair.nearest("tool-holder", req, k=2), req))
    assert notes == ("note: where the weighted average would be non-passive (Im Z < 0) the interpolation takes the "
                     f"loss from the passive neighbours only (th-d10@1 on {int(STRETCH.sum())} of {F.size} lines)",)
    req6 = Conditions(MATS, torque_nm=60.0, geometry={"shank_diameter_m": 0.006})
    assert _passivity_notes(pair.interpolate(pair.nearest("tool-holder", req6, k=2), req6)) == ()


def test_the_remote_store_reads_passivity_moved_and_an_older_server_without_it(monkeypatch):
    """The client keeps what the server's /query/interpolate says (and an older server, without the field, gives ())."""
    from types import SimpleNamespace

    from jointdb.client import RemoteRepository
    from jointdb.io._frfjson import frf_json

    body = {"frf": frf_json(_frf(Z6)), "joint_type": "tool-holder", "label": "interpolated",
            "neighbours": [{"name": "th-d06", "version": 1, "weight": 0.7},
                           {"name": "th-d10", "version": 1, "weight": 0.3}]}
    match = SimpleNamespace(version=SimpleNamespace(joint_type="tool-holder"))
    req = Conditions(MATS, torque_nm=60.0, geometry={"shank_diameter_m": 0.007})
    with RemoteRepository("http://127.0.0.1:9") as remote:
        moved = {"passivity_moved": [{"name": "th-d10", "version": 1, "lines": 12}]}
        for extra, want in ((moved, (("th-d10", 1, 12),)), ({}, ())):
            monkeypatch.setattr(remote, "_call", lambda method, path, **kw: {**body, **extra})
            assert remote.interpolate([match], req).passivity_moved == want
