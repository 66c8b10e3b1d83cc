"""Forward coupling of jointdb.fe beam models against monolithic FE models (docs/theory.md §1)."""

import numpy as np
import pytest

from jointdb.coupling import Interface, JointSubstructure, couple, spring_damper_joint
from jointdb.coupling._matrices import add_spring, merge_matrices, model_matrices, receptance_from_matrices
from jointdb.fe import BeamModel, Clamp, HystereticDamping, NamedPoint, Segment

FREQ = np.linspace(10.0, 4000.0, 200)
ETA = HystereticDamping(0.01)


def model(length, d, points, clamp=None, theory="timoshenko"):
    ingredients = (ETA,) + ((Clamp(clamp),) if clamp is not None else ())
    return BeamModel(segments=(Segment(length, d),), points=tuple(NamedPoint(*p) for p in points),
                     ingredients=ingredients, theory=theory, max_element_length=0.01)


def rel(a, b):
    return np.max(np.abs(a - b)) / np.max(np.abs(b))


@pytest.mark.parametrize("theory", ["timoshenko", "euler-bernoulli"])
def test_rigid_joint_equals_single_fe_model(theory):
    A = model(0.20, 0.03, [("mid", 0.1, 4), ("end", 0.2, 3)], clamp=0.0, theory=theory)
    B = model(0.10, 0.03, [("start", 0.0, 2), ("tip", 0.1, 1)], theory=theory)
    joined = BeamModel(segments=(Segment(0.20, 0.03), Segment(0.10, 0.03)),
                       points=(NamedPoint("mid", 0.1, 4), NamedPoint("joint", 0.2, 3), NamedPoint("tip", 0.3, 1)),
                       ingredients=(ETA, Clamp(0.0)), theory=theory, max_element_length=0.01)
    fa, fb = A.frf(FREQ), B.frf(FREQ)
    g = couple({"A": fa, "B": fb}, [Interface("A", ["3x", "3ry"], "B", ["2x", "2ry"])],
               outputs=[("B", "1x"), ("B", "1ry"), ("A", "4x")], inputs=[("B", "1x"), ("A", "4x"), ("A", "3ry")])
    ref = joined.frf(FREQ).select(["1x", "1ry", "4x"], ["1x", "4x", "3ry"])
    assert rel(g.values, ref.values) < 1e-8  # round-off amplified by the free-free tool at low frequency (cond ~1e6)


def test_spring_joint_equals_fe_model_with_springs():
    A = model(0.20, 0.03, [("end", 0.2, 3)], clamp=0.0)
    B = model(0.12, 0.02, [("start", 0.0, 2), ("tip", 0.12, 1)])
    kx, cx, kr, cr = 2e6, 100.0, 8e4, 80.0
    K, M, C, labels = merge_matrices(model_matrices(A, 1000), model_matrices(B, 2000))
    idx = {d: i for i, d in enumerate(labels)}
    from jointdb.frf import Dof
    add_spring(K, C, idx[Dof(3, "x")], idx[Dof(2, "x")], kx, cx)
    add_spring(K, C, idx[Dof(3, "ry")], idx[Dof(2, "ry")], kr, cr)
    ref = receptance_from_matrices(FREQ, K, M, labels, C, outputs=["1x", "3x"], inputs=["1x", "3x"])
    joint = spring_damper_joint(FREQ, [kx, kr], [cx, cr], ["3x", "3ry"])
    g = couple({"A": A.frf(FREQ), "B": B.frf(FREQ)}, [Interface("A", ["3x", "3ry"], "B", ["2x", "2ry"], joint)],
               outputs=[("B", "1x"), ("A", "3x")])
    assert rel(g.values, ref.values) < 1e-8  # round-off amplified by the free-free tool at low frequency (cond ~1e6)


def test_three_bodies_two_joints_equal_fe_model():
    # A clamped shank, B holder extension (rigid to A), C tool (springs to B)
    A = model(0.15, 0.04, [("end", 0.15, 3)], clamp=0.0)
    B = model(0.08, 0.03, [("start", 0.0, 4), ("end", 0.08, 5)])
    Cm = model(0.06, 0.012, [("start", 0.0, 6), ("tip", 0.06, 1)])
    K, M, C, labels = merge_matrices(model_matrices(A, 1000), model_matrices(B, 2000), model_matrices(Cm, 3000))
    from jointdb.frf import Dof
    idx = {d: i for i, d in enumerate(labels)}
    # rigid A-B: enforce with a transformation that merges 4 into 3
    keep = [d for d in labels if d.node != 4]
    T = np.zeros((len(labels), len(keep)))
    pos = {d: i for i, d in enumerate(keep)}
    for i, d in enumerate(labels):
        T[i, pos[Dof(3, d.direction) if d.node == 4 else d]] = 1.0
    add_spring(K, C, idx[Dof(5, "x")], idx[Dof(6, "x")], 5e6, 60.0)
    add_spring(K, C, idx[Dof(5, "ry")], idx[Dof(6, "ry")], 2e5, 20.0)
    Kr, Mr, Cr = T.T @ K @ T, T.T @ M @ T, T.T @ C @ T
    ref = receptance_from_matrices(FREQ, Kr, Mr, keep, Cr, outputs=["1x", "3x"], inputs=["1x", "3x"])
    subs = {"A": A.frf(FREQ), "B": B.frf(FREQ), "C": Cm.frf(FREQ)}
    ifaces = [Interface("A", ["3x", "3ry"], "B", ["4x", "4ry"]),
              Interface("B", ["5x", "5ry"], "C", ["6x", "6ry"],
                        spring_damper_joint(FREQ, [5e6, 2e5], [60.0, 20.0], ["5x", "5ry"]))]
    g = couple(subs, ifaces, outputs=[("C", "1x"), ("A", "3x")])
    assert rel(g.values, ref.values) < 1e-8  # round-off amplified by the free-free tool at low frequency (cond ~1e6)


def test_joint_segment_as_substructure_equals_single_model():
    # §1b: a joint body (short segment) between A and B, as in thesis §4.3 second simulation
    A = model(0.20, 0.03, [("end", 0.2, 3)], clamp=0.0)
    J = model(0.05, 0.02, [("a", 0.0, 7), ("b", 0.05, 8)])
    B = model(0.10, 0.03, [("start", 0.0, 2), ("tip", 0.1, 1)])
    joined = BeamModel(segments=(Segment(0.20, 0.03), Segment(0.05, 0.02), Segment(0.10, 0.03)),
                       points=(NamedPoint("tip", 0.35, 1),), ingredients=(ETA, Clamp(0.0)), max_element_length=0.01)
    g = couple({"A": A.frf(FREQ), "B": B.frf(FREQ)},
               [Interface("A", ["3x", "3ry"], "B", ["2x", "2ry"],
                          JointSubstructure(J.frf(FREQ), ["7x", "7ry"], ["8x", "8ry"]))],
               outputs=[("B", "1x")])
    ref = joined.frf(FREQ).select(["1x"], ["1x"])
    assert rel(g.values, ref.values) < 1e-8  # round-off amplified by the free-free tool at low frequency (cond ~1e6)
