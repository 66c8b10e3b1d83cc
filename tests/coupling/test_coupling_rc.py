"""Forward coupling (docs/theory.md §1) against monolithic spring–mass models."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from jointdb.coupling import Interface, JointSubstructure, couple, spring_damper_joint
from jointdb.coupling._matrices import add_spring, receptance_from_matrices
from jointdb.errors import InputError, NumericalError
from jointdb.frf import FRF

FREQ = np.linspace(1.0, 400.0, 157)


def chain(masses, springs, dampers, ground=None):
    """K, M, C of a mass chain; ground=(k, c) attaches the first mass to ground."""
    n = len(masses)
    K = np.zeros((n, n))
    C = np.zeros((n, n))
    M = np.diag(np.asarray(masses, float))
    for e, (k, c) in enumerate(zip(springs, dampers)):
        add_spring(K, C, e, e + 1, k, c)
    if ground:
        add_spring(K, C, 0, None, *ground)
    return K, M, C


def blockdiag(*mats):
    n = sum(m.shape[0] for m in mats)
    out = np.zeros((n, n), dtype=np.result_type(*mats))
    o = 0
    for m in mats:
        out[o : o + m.shape[0], o : o + m.shape[0]] = m
        o += m.shape[0]
    return out


@pytest.fixture
def two_bodies():
    Ka, Ma, Ca = chain([2.0, 1.5, 1.0], [4e5, 3e5], [20.0, 15.0], ground=(6e5, 30.0))
    Kb, Mb, Cb = chain([0.8, 1.2], [2e5], [10.0])
    la = ["1x", "2x", "3x"]
    lb = ["4x", "5x"]
    A = receptance_from_matrices(FREQ, Ka, Ma, la, Ca)
    B = receptance_from_matrices(FREQ, Kb, Mb, lb, Cb)
    return (Ka, Ma, Ca, la), (Kb, Mb, Cb, lb), A, B


def test_spring_joint_equals_monolithic_model(two_bodies):
    (Ka, Ma, Ca, la), (Kb, Mb, Cb, lb), A, B = two_bodies
    kj, cj = 1.5e5, 12.0
    K, M, C = blockdiag(Ka, Kb), blockdiag(Ma, Mb), blockdiag(Ca, Cb)
    add_spring(K, C, 2, 3, kj, cj)
    ref = receptance_from_matrices(FREQ, K, M, la + lb, C)
    joint = spring_damper_joint(FREQ, [kj], [cj], ["3x"])
    g = couple({"A": A, "B": B}, [Interface("A", ["3x"], "B", ["4x"], joint)],
               outputs=[("A", "1x"), ("B", "5x"), ("A", "3x")], inputs=[("B", "5x"), ("A", "1x")])
    want = ref.select(["1x", "5x", "3x"], ["5x", "1x"])
    assert np.max(np.abs(g.values - want.values)) <= 1e-10 * np.max(np.abs(want.values))


def test_rigid_joint_equals_merged_model(two_bodies):
    (Ka, Ma, Ca, la), (Kb, Mb, Cb, lb), A, B = two_bodies
    # merge node 3 of A with node 4 of B: 4 DOFs 1x 2x 3x 5x
    T = np.zeros((5, 4))
    T[0, 0] = T[1, 1] = T[2, 2] = T[3, 2] = T[4, 3] = 1.0
    K = T.T @ blockdiag(Ka, Kb) @ T
    M = T.T @ blockdiag(Ma, Mb) @ T
    C = T.T @ blockdiag(Ca, Cb) @ T
    ref = receptance_from_matrices(FREQ, K, M, ["1x", "2x", "3x", "5x"], C)
    g = couple({"A": A, "B": B}, [Interface("A", ["3x"], "B", ["4x"])],
               outputs=[("A", "1x"), ("A", "3x"), ("B", "5x"), ("B", "4x")])
    want = ref.select(["1x", "3x", "5x"], ["1x", "3x", "5x"])
    assert np.allclose(g.values[:, :3, :3], want.values, rtol=1e-10, atol=1e-12 * np.abs(want.values).max())
    # the two sides of a rigid joint move together
    assert np.allclose(g.values[:, 1], g.values[:, 3], rtol=1e-10, atol=1e-14)


def test_three_bodies_two_joints_full_joint_matrix():
    # three 2-DOF bodies, each DOF pair coupled by a full 2x2 joint stiffness
    bodies = []
    for s in range(3):
        K, M, C = chain([1.0 + s, 0.7], [3e5 + 1e5 * s], [8.0], ground=(2e5, 5.0) if s == 0 else None)
        bodies.append((K, M, C))
    # joint 1: between A.2 and B.3 ; joint 2 between B.4 and C.5 — one DOF each, plus
    # a coupled 2-DOF joint A.(1,2) to C.(5,6) for a full H_J
    Kj = np.array([[3e5, -5e4], [-5e4, 2e5]])
    Cj = np.array([[10.0, -2.0], [-2.0, 6.0]])
    labels = ["1x", "2x", "3x", "4x", "5x", "6x"]
    K = blockdiag(*(b[0] for b in bodies)).astype(float)
    M = blockdiag(*(b[1] for b in bodies))
    C = blockdiag(*(b[2] for b in bodies)).astype(float)
    add_spring(K, C, 1, 2, 4e5, 9.0)  # A.2x - B.3x
    # full joint between B.(3,4) and C.(5,6): force = Kj (u_B - u_C)
    idx_b, idx_c = [2, 3], [4, 5]
    for r in range(2):
        for s_ in range(2):
            K[idx_b[r], idx_b[s_]] += Kj[r, s_]
            K[idx_c[r], idx_c[s_]] += Kj[r, s_]
            K[idx_b[r], idx_c[s_]] -= Kj[r, s_]
            K[idx_c[r], idx_b[s_]] -= Kj[r, s_]
            C[idx_b[r], idx_b[s_]] += Cj[r, s_]
            C[idx_c[r], idx_c[s_]] += Cj[r, s_]
            C[idx_b[r], idx_c[s_]] -= Cj[r, s_]
            C[idx_c[r], idx_b[s_]] -= Cj[r, s_]
    ref = receptance_from_matrices(FREQ, K, M, labels, C)
    subs = {
        name: receptance_from_matrices(FREQ, *b[:2], labels[2 * s : 2 * s + 2], b[2])
        for s, (name, b) in enumerate(zip("ABC", bodies))
    }
    w = 2 * np.pi * FREQ
    hj_full = np.linalg.inv(Kj[None] + 1j * w[:, None, None] * Cj[None])
    ifaces = [
        Interface("A", ["2x"], "B", ["3x"], spring_damper_joint(FREQ, 4e5, 9.0, ["2x"])),
        Interface("B", ["3x", "4x"], "C", ["5x", "6x"], hj_full),
    ]
    outs = [("A", "1x"), ("C", "6x"), ("B", "4x")]
    g = couple(subs, ifaces, outs)
    want = ref.select(["1x", "6x", "4x"], ["1x", "6x", "4x"])
    assert np.max(np.abs(g.values - want.values)) <= 1e-10 * np.max(np.abs(want.values))
    assert g.reciprocity_error() < 1e-10


def test_joint_body_with_inertia_equals_monolithic(two_bodies):
    (Ka, Ma, Ca, la), (Kb, Mb, Cb, lb), A, B = two_bodies
    # joint body: two masses 0.1, 0.2 connected by spring 8e5 (nodes 7, 8), attached rigidly
    Kj, Mj, Cj = chain([0.1, 0.2], [8e5], [4.0])
    J = receptance_from_matrices(FREQ, Kj, Mj, ["7x", "8x"], Cj)
    # monolithic: A.3 == J.7, J.8 == B.4
    T = np.zeros((7, 5))  # dofs: 1 2 3(=7) 8(=4) 5
    T[0, 0] = T[1, 1] = T[2, 2] = 1.0
    T[3, 3] = 1.0  # B.4 -> merged with J.8
    T[4, 4] = 1.0  # B.5
    T[5, 2] = 1.0  # J.7 -> A.3
    T[6, 3] = 1.0  # J.8
    K = T.T @ blockdiag(Ka, Kb, Kj) @ T
    M = T.T @ blockdiag(Ma, Mb, Mj) @ T
    C = T.T @ blockdiag(Ca, Cb, Cj) @ T
    ref = receptance_from_matrices(FREQ, K, M, ["1x", "2x", "3x", "4x", "5x"], C)
    g = couple({"A": A, "B": B},
               [Interface("A", ["3x"], "B", ["4x"], JointSubstructure(J, ["7x"], ["8x"]))],
               outputs=[("A", "1x"), ("B", "5x")])
    want = ref.select(["1x", "5x"], ["1x", "5x"])
    assert np.max(np.abs(g.values - want.values)) <= 1e-10 * np.max(np.abs(want.values))


def test_subset_of_outputs_equals_slice_of_larger_request(two_bodies):
    *_, A, B = two_bodies
    iface = [Interface("A", ["3x"], "B", ["4x"], spring_damper_joint(FREQ, 1e5, 3.0, ["3x"]))]
    big = couple({"A": A, "B": B}, iface, [("A", d) for d in ["1x", "2x", "3x"]] + [("B", "4x"), ("B", "5x")])
    small = couple({"A": A, "B": B}, iface, [("B", "5x")], [("A", "2x")])
    assert np.allclose(small.values[:, 0, 0], big.entry("5x", "2x"), rtol=1e-12, atol=0)


def test_mobility_inputs_give_receptance(two_bodies):
    *_, A, B = two_bodies
    iface = [Interface("A", ["3x"], "B", ["4x"])]
    g1 = couple({"A": A, "B": B}, iface, [("A", "1x")])
    g2 = couple({"A": A.to("mobility"), "B": B.to("accelerance")}, iface, [("A", "1x")])
    assert g2.quantity.value == "receptance"
    assert np.allclose(g1.values, g2.values, rtol=1e-10, atol=0)


@settings(max_examples=25, deadline=None)
@given(k=st.floats(1e3, 1e8), c=st.floats(0.0, 500.0))
def test_coupled_driving_point_is_passive_and_reciprocal(k, c):
    Ka, Ma, Ca = chain([2.0, 1.0], [4e5], [20.0], ground=(6e5, 30.0))
    Kb, Mb, Cb = chain([0.8, 1.2], [2e5], [10.0])
    A = receptance_from_matrices(FREQ, Ka, Ma, ["1x", "2x"], Ca)
    B = receptance_from_matrices(FREQ, Kb, Mb, ["4x", "5x"], Cb)
    g = couple({"A": A, "B": B}, [Interface("A", ["2x"], "B", ["4x"], spring_damper_joint(FREQ, k, c, ["2x"]))],
               [("A", "1x"), ("B", "5x")])
    scale = np.abs(g.values).max()
    assert np.all(g.values[:, 0, 0].imag <= 1e-12 * scale)
    assert np.all(g.values[:, 1, 1].imag <= 1e-12 * scale)
    assert g.reciprocity_error() < 1e-9


def test_errors_name_the_problem(two_bodies):
    *_, A, B = two_bodies
    with pytest.raises(InputError, match="unknown substructure 'Q'"):
        couple({"A": A, "B": B}, [Interface("A", ["3x"], "Q", ["4x"])], [("A", "1x")])
    with pytest.raises(InputError, match="no FRF for DOF 9x"):
        couple({"A": A, "B": B}, [Interface("A", ["9x"], "B", ["4x"])], [("A", "1x")])
    with pytest.raises(InputError, match="paired one to one"):
        Interface("A", ["3x", "2x"], "B", ["4x"])
    with pytest.raises(InputError, match="resample"):
        couple({"A": A, "B": B.band(fmax=200)}, [Interface("A", ["3x"], "B", ["4x"])], [("A", "1x")])
    with pytest.raises(InputError, match="distinct"):
        C = FRF(A.freq, A.values, ["1x", "2x", "3x"], ["1x", "2x", "3x"])
        couple({"A": A, "C": C}, [Interface("A", ["3x"], "C", ["2x"])], [("A", "1x"), ("C", "1x")])
    with pytest.raises(InputError, match="shape"):
        couple({"A": A, "B": B}, [Interface("A", ["3x"], "B", ["4x"], np.ones((3, 2, 2)))], [("A", "1x")])
    with pytest.raises(InputError, match="stiffness must be"):
        spring_damper_joint(FREQ, -1.0, 0.0, ["1x"])


def test_singular_interface_raises_numerical_error():
    f = np.array([10.0, 20.0])
    zero = FRF(f, np.zeros((2, 1, 1)), ["1x"], ["1x"])
    with pytest.raises(NumericalError, match="singular"):
        couple({"A": zero, "B": FRF(f, np.zeros((2, 1, 1)), ["2x"], ["2x"])},
               [Interface("A", ["1x"], "B", ["2x"])], [("A", "1x")])


def test_reciprocity_used_for_missing_entries(two_bodies):
    *_, A, B = two_bodies
    # A given as one column only (inputs at 3x): outputs 1x..3x. Coupling for output 1x input 1x
    # needs H_13 (have) and H_31 (from reciprocity) and H_11 (missing entirely -> error)
    col = A.select(None, ["3x"])
    g = couple({"A": col, "B": B}, [Interface("A", ["3x"], "B", ["4x"])], [("B", "5x")], [("A", "1x")])
    ref = couple({"A": A, "B": B}, [Interface("A", ["3x"], "B", ["4x"])], [("B", "5x")], [("A", "1x")])
    assert np.allclose(g.values, ref.values, rtol=1e-12, atol=0)
    with pytest.raises(InputError, match="neither directly nor by reciprocity"):
        couple({"A": col, "B": B}, [Interface("A", ["3x"], "B", ["4x"])], [("A", "1x")])
