"""Thesis §4.3 second simulation: a continuous joint segment identified on one assembly predicts a
second assembly with a shorter substructure B (thesis: 5 % vs 109 % mean deviation)."""

import numpy as np

from jointdb.coupling import Interface, couple, identify_planar_joint
from jointdb.fe import BeamModel, Clamp, HystereticDamping, NamedPoint, Segment

FREQ = np.linspace(5.0, 3000.0, 300)
ETA = HystereticDamping(0.2)  # ≈ the thesis's proportional damping ratio 0.1 (η = 2ζ)


def assembly(lb):
    return BeamModel(segments=(Segment(0.30, 0.03), Segment(0.05, 0.02), Segment(lb, 0.03)),
                     points=(NamedPoint("tip", 0.35 + lb, 1), NamedPoint("c", 0.35, 2)),
                     ingredients=(ETA, Clamp(0.0)), max_element_length=0.01)


def tool(lb):
    return BeamModel(segments=(Segment(lb, 0.03),), points=(NamedPoint("c", 0.0, 2), NamedPoint("tip", lb, 1)),
                     ingredients=(ETA,), max_element_length=0.01)


def test_identified_joint_segment_predicts_shorter_assembly():
    A = BeamModel(segments=(Segment(0.30, 0.03),), points=(NamedPoint("end", 0.30, 3),),
                  ingredients=(ETA, Clamp(0.0)), max_element_length=0.01).frf(FREQ)
    res = identify_planar_joint(assembly(0.20).frf(FREQ), A, 3, tool(0.20).frf(FREQ), 2, 1)
    assert res.residual.max() < 1e-8  # two equations, two unknowns: the case-A measurement is reproduced
    truth = assembly(0.12).frf(FREQ).entry("1x", "1x")
    fb = tool(0.12).frf(FREQ)

    def predict(joint):
        g = couple({"A": A, "B": fb}, [Interface("A", ["3x", "3ry"], "B", ["2x", "2ry"], joint)], [("B", "1x")])
        return np.mean(np.abs(g.values[:, 0, 0] - truth) / np.abs(truth))

    identified, rigid = predict(res.joint), predict(None)
    assert identified < 0.05
    assert rigid > 0.5
