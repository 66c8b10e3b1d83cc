"""Output-error joint identification: accuracy and standard errors under 1 % noise (issue 13).

Seeds here (100.., 200..) differ from the ones used while developing (1000.., 2000..)
and from the bench's reported ones (5000..)."""

import numpy as np
import pytest
from coupling_cases import TABLE_5_1_C, TABLE_5_1_K, add_noise, blocks, plate_frfs, plates
from test_coupling_planar import CR, CX, KR, KX, build_case

from jointdb.coupling import (
    fit_joint_matrix,
    fit_n_point_joints,
    fit_planar_joint,
    mean_and_sigma_of_repeats,
    sigma_from_coherence,
)
from jointdb.coupling._oe_core import SpringDamperModel, coupled_blocks
from jointdb.errors import InputError
from jointdb.frf import Dof

# With 12 seeds × 4 parameters, 2σ misses follow Binomial(48, ~0.05); ≥ 80 % covered fails
# with probability < 1e-3 when the standard errors are right, and fails surely when they
# are too small by a factor 2 (then ~68 % of |error| ≤ 2σ).
COVER_MIN = 0.8


def z(nodes):
    return [Dof(n, "z") for n in nodes]


@pytest.fixture(scope="module")
def planar_fits():
    A, B, G = build_case()
    return [fit_planar_joint(add_noise(G, 0.01, seed), A, 3, B, 2, 1) for seed in range(100, 112)]


def test_planar_joint_at_one_percent_noise_meets_the_tolerances(planar_fits):
    true = np.array([KX, CX, KR, CR])
    err = np.array([r.values / true - 1 for r in planar_fits])
    # issue 13: k, c within 0.5 %; k_θ within 3 %; c_θ within 10 % (no smoothing)
    assert np.all(np.abs(err[:, :2]) < 0.005), np.abs(err).max(0)
    assert np.all(np.abs(err[:, 2]) < 0.03) and np.all(np.abs(err[:, 3]) < 0.10), np.abs(err).max(0)
    sd = np.array([r.std_error for r in planar_fits])
    covered = np.abs(err * true) <= 2 * sd
    assert covered.mean() >= COVER_MIN, covered.mean(0)
    # residual scale: 1 % complex noise is 0.71 % per real/imaginary part
    rms = np.array([r.residual_rms for r in planar_fits])
    assert np.all(np.abs(rms / (0.01 / np.sqrt(2)) - 1) < 0.15)
    r = planar_fits[0]
    assert r.names == ["k 3x", "c 3x", "k 3ry", "c 3ry"]
    assert r.correlation.shape == (4, 4) and np.allclose(np.diag(r.correlation), 1)
    assert r.cost < r.cost_start


def test_n_point_springs_at_one_percent_noise():
    F = np.linspace(20.0, 2000.0, 100)
    case = plates(F)
    fa, fb, g = plate_frfs(F, case)
    true = np.ravel(np.column_stack([TABLE_5_1_K, TABLE_5_1_C]))
    errs, cov = [], []
    for seed in range(200, 206):
        r = fit_n_point_joints(add_noise(g, 0.01, seed), fa, z(case["internal"]), z(case["a_bolts"]), fb,
                               z(case["b_bolts"]))
        errs.append(r.values / true - 1)
        cov.append(np.abs(r.values - true) <= 2 * r.std_error)
    errs = np.array(errs)
    assert np.all(np.abs(errs[:, 1::2]) < 0.03), np.abs(errs).max(0)  # every c within 3 %
    assert np.all(np.abs(errs[:, 0::2]) < 0.01), np.abs(errs).max(0)
    assert np.mean(cov) >= COVER_MIN


def test_jacobian_matches_finite_differences_with_frequency_dependent_kc():
    A, B, _ = build_case(freq=np.linspace(5.0, 3000.0, 40))
    bl = coupled_blocks({"A": A, "B": B}, "A", ["3x", "3ry"], "B", ["2x", "2ry"], [("B", "1x")],
                        [("B", "1x"), ("B", "2x")])
    m = SpringDamperModel((Dof(3, "x"), Dof(3, "ry")), order=2)
    th = m.start(np.array([KX, KR]), np.array([CX, CR])) + 0.1 * np.random.default_rng(0).standard_normal(12)
    g, jac = m.evaluate(th, bl, jac=True)
    h = 1e-4  # central differences: O(h²) ≈ 1e-8 truncation; smaller h loses digits to the G = H − UXV cancellation
    for p in range(th.size):
        e = np.eye(th.size)[p] * h
        fd = (m.evaluate(th + e, bl, False)[0] - m.evaluate(th - e, bl, False)[0]) / (2 * h)
        assert np.max(np.abs(fd - jac[..., p])) <= 1e-6 * np.max(np.abs(jac[..., p])) + 1e-30


def test_weights_from_repeats_and_coherence():
    A, B, G = build_case()
    taps = [add_noise(G, 0.02, s) for s in range(300, 305)]
    mean, sigma = mean_and_sigma_of_repeats(taps)
    assert sigma.shape == G.values.shape
    # the spread of 5 taps of 2 % noise: σ of the mean ≈ 0.02 |G| / √5
    ratio = np.median(sigma / np.abs(G.values))
    assert 0.6 * 0.02 / np.sqrt(5) < ratio < 1.4 * 0.02 / np.sqrt(5)
    r = fit_planar_joint(mean, A, 3, B, 2, 1, sigma=sigma[:, :1, :])
    assert abs(r.values[0] / KX - 1) < 0.005
    assert 0.5 < r.residual_rms < 2.0  # σ from the repeats is the right scale
    with pytest.raises(InputError, match="γ²"):
        sigma_from_coherence(G, np.full(G.values.shape, 95.0), 5)
    s = sigma_from_coherence(G, np.full(G.values.shape, 0.99), 10)
    assert np.allclose(s / np.abs(G.values), np.sqrt(0.01 / 0.99) / np.sqrt(20))
    with pytest.raises(InputError, match="at least 2"):
        mean_and_sigma_of_repeats(taps[:1])
    with pytest.raises(InputError, match="sigma has shape"):
        fit_planar_joint(G, A, 3, B, 2, 1, sigma=np.ones((3, 1, 2)))


def test_joint_body_with_inertia_refits_from_the_irc_start():
    F = np.linspace(150.0, 3000.0, 24)
    b = blocks(F)
    r = fit_joint_matrix(add_noise(b["G"], 0.01, 400), b["subs"], b["m15"], "A", b["a_dofs"], "B", b["b_dofs"])
    assert r.cost < r.cost_start
    n = len(r.names) // 3
    k_diag = [i for i, name in enumerate(r.names[:n]) if name.split("[")[1].split(",")[0] == name.split(",")[1][:-1]]
    assert len(k_diag) == 12 and np.all(np.isfinite(r.std_error))
