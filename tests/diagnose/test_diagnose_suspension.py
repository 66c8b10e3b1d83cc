"""Free-free test piece on a soft suspension (truth: the benchmark's own FE)."""

import numpy as np

from jointdb.diagnose import Measurement, diagnose
from jointdb.diagnose_bench._truth_fe import TruthBeam
from jointdb.fe import BeamModel, NamedPoint, RayleighDamping, Segment, Support
from jointdb.frf import FRF, Dof


def test_soft_suspension_is_named_for_a_free_free_bar():
    L, d = 0.2, 0.02
    alpha, beta = 2.0, 1e-6
    truth = TruthBeam.cylinder(0.0, L, d, 210e9, 0.3, 7800.0, h=0.002, breaks=(0.1,))
    k = 2.0e4                                   # N/m at each end: ~ 24 Hz bounce mode for 0.49 kg
    truth.bed = {0: k, truth.node_at(L): k}
    truth.rayleigh = (alpha, beta)
    f = np.arange(4.0, 3000.0, 2.0)
    nodes = [truth.node_at(z) for z in (L, 0.1)]
    H = truth.receptance(f, [2 * n for n in nodes], [2 * nodes[0]])
    rng = np.random.default_rng(5)
    H = H * (1 + 0.01 * (rng.standard_normal(H.shape) + 1j * rng.standard_normal(H.shape)) / np.sqrt(2))
    frf = FRF(f, H, (Dof(1, "x"), Dof(2, "x")), (Dof(1, "x"),), "receptance")
    model = BeamModel(segments=(Segment(L, d),), points=(NamedPoint("end", L, 1), NamedPoint("middle", 0.1, 2)),
                      ingredients=(RayleighDamping(alpha, beta),), max_element_length=0.01)
    result = diagnose(model, [Measurement(frf)], combinations=False)
    assert result.explained, result.verdict
    assert result.best.family == "soft_suspension", [f.name for f in result.ranking[:3]]
    assert 0.5 * k < result.best.values["k_suspension"] < 2 * k
    assert sum(isinstance(i, Support) for i in result.augmented[0].ingredients) == 2
