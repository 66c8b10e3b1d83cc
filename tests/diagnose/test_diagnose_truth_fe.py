"""The benchmark's own truth FE against known answers."""

import numpy as np
import pytest

from jointdb.diagnose_bench._truth_fe import TruthBeam

E, NU, RHO = 210e9, 0.3, 7800.0


def _timoshenko_ss(L, D, m):
    """Exact pinned-pinned Timoshenko frequency of mode m (quadratic in ω²)."""
    G = E / (2 * (1 + NU))
    A, I = np.pi * D**2 / 4, np.pi * D**4 / 64
    kap = 6 * (1 + NU) / (7 + 6 * NU)
    k = m * np.pi / L
    a2 = RHO * A * RHO * I
    a1 = -(RHO * A * (E * I * k * k + kap * G * A) + kap * G * A * k * k * RHO * I)
    a0 = kap * G * A * k * k * (E * I * k * k + kap * G * A) - (kap * G * A * k) ** 2
    return np.sqrt(min(np.roots([a2, a1, a0]).real)) / (2 * np.pi)


def test_truth_element_matches_exact_timoshenko_pinned_beam():
    L, D = 0.1, 0.02   # stubby: shear matters
    b = TruthBeam.cylinder(0, L, D, E, NU, RHO, h=0.001)
    K, M, _ = b.matrices()
    n = K.shape[0]
    free = [i for i in range(n) if i not in (0, n - 2)]
    import scipy.linalg

    w2 = scipy.linalg.eigh(K[np.ix_(free, free)], M[np.ix_(free, free)], eigvals_only=True)[:3]
    exact = np.array([_timoshenko_ss(L, D, m) for m in (1, 2, 3)])
    assert np.allclose(np.sqrt(w2) / (2 * np.pi), exact, rtol=2e-4)


def test_truth_cantilever_euler_bernoulli_limit():
    L, D = 0.5, 0.01   # slender: Euler-Bernoulli 1.8751
    b = TruthBeam.cylinder(0, L, D, E, NU, RHO, h=0.005)
    b.clamped_nodes = [0]
    w2, _, _ = b._modes()
    A, I = np.pi * D**2 / 4, np.pi * D**4 / 64
    f1 = 1.875104**2 / (2 * np.pi) * np.sqrt(E * I / (RHO * A * L**4))
    assert np.sqrt(w2[0]) / (2 * np.pi) == pytest.approx(f1, rel=1e-3)


def test_receptance_modal_sum_and_bed_correction_equal_direct_solution():
    b = TruthBeam.cylinder(-0.03, 0.12, 0.016, E, NU, RHO, h=0.003, breaks=(0.0,))
    b.add_winkler_bed(-0.03, 0.0, 5e11)
    b.bed_loss = 0.4
    b.structural_loss = 0.01
    b.rayleigh = (30.0, 2e-7)
    tip = 2 * b.node_at(0.12)
    mid = 2 * b.node_at(0.0)
    f = np.array([300.0, 1500.0, 6000.0])
    H = b.receptance(f, [tip, mid], [tip])
    K, M, Kb = b.matrices()
    for k, fk in enumerate(f):
        w = 2 * np.pi * fk
        D = K * (1 + 0.01j) + Kb * (1 + 0.4j) + 1j * w * (30.0 * M + 2e-7 * (K + Kb)) - w * w * M
        e = np.zeros(K.shape[0])
        e[tip] = 1.0
        x = np.linalg.solve(D, e)
        assert np.allclose(H[k, :, 0], x[[tip, mid]], rtol=1e-8)


def test_amplitude_dependent_bed_with_a_constant_law_is_the_linear_bed():
    b = TruthBeam.cylinder(-0.03, 0.12, 0.016, E, NU, RHO, h=0.003, breaks=(0.0,))
    b.add_winkler_bed(-0.03, 0.0, 5e11)
    b.bed_loss = 0.05
    tip = 2 * b.node_at(0.12)
    f = np.linspace(200, 3000, 30)
    lin = b.receptance(f, [tip], [tip])
    same = b.receptance_amplitude_dependent(f, [tip], [tip], 10.0, lambda a: (np.ones_like(a), np.full(a.shape, 0.05)))
    assert np.allclose(lin, same, rtol=1e-10)
    soft = b.receptance_amplitude_dependent(f, [tip], [tip], 10.0,
                                            lambda a: (np.full(a.shape, 0.5), np.full(a.shape, 0.05)))
    # half the bed stiffness everywhere = the linear model with a softer bed
    b2 = TruthBeam.cylinder(-0.03, 0.12, 0.016, E, NU, RHO, h=0.003, breaks=(0.0,))
    b2.add_winkler_bed(-0.03, 0.0, 2.5e11)
    b2.bed_loss = 0.05
    assert np.allclose(soft, b2.receptance(f, [tip], [tip]), rtol=1e-8)


def _plain_balance(b, f, outs, ins, force, law, n_iter=60, relax=0.5):
    """The harmonic balance as first written: every line iterated n_iter times, one input at a time."""
    nodes = sorted(b.bed)
    bd = [2 * n for n in nodes]
    k0 = np.array([b.bed[n] for n in nodes])
    cols = []
    for i in ins:
        H = b.receptance(f, bd + outs, bd + [i])
        nb = len(bd)
        Hbb, Hbi, Hob, Hoi = H[:, :nb, :nb], H[:, :nb, nb:], H[:, nb:, :nb], H[:, nb:, nb:]
        dk = np.zeros((f.size, nb), dtype=complex)
        for _ in range(n_iter):
            xb = np.linalg.solve(np.eye(nb)[None] + Hbb * dk[:, None, :], Hbi[:, :, :1])[:, :, 0]
            sigma, eta = law(np.abs(xb) * force)
            dk = (1 - relax) * dk + relax * k0[None] * (sigma * (1 + 1j * eta) - (1 + 1j * b.bed_loss))
        corr = np.linalg.solve(np.eye(nb)[None] + Hbb * dk[:, None, :], Hbi)
        cols.append(Hoi - np.einsum("fob,fb,fbi->foi", Hob, dk, corr))
    return np.concatenate(cols, axis=2)


def test_converged_lines_leave_the_balance_without_changing_the_result():
    """Lines whose fixed-point step is round-off stop early (and both inputs, all levels share one linear
    receptance): equal to the plain 60-step iteration to round-off, at a softening strong enough that
    lines near the resonance need most of the 60 steps."""
    b = TruthBeam.cylinder(-0.03, 0.12, 0.016, E, NU, RHO, h=0.003, breaks=(0.0,))
    b.add_winkler_bed(-0.03, 0.0, 5e11)
    b.bed_loss = 0.05
    b.rayleigh = (20.0, 1e-6)
    tip, mid = 2 * b.node_at(0.12), 2 * b.node_at(0.06)
    f = np.linspace(200, 3000, 120)
    ref = np.abs(b.receptance(f, [2 * b.node_at(0.0)], [tip])).max()

    def law(a, a_c=ref * 5.0):
        r = a / a_c
        return 1.0 - 0.6 * r / (1.0 + r), 0.05 + 0.3 * r / (1.0 + r)

    got = b.amplitude_dependent_levels(f, [tip, mid], [tip, mid], [1.0, 10.0], law)
    for force, H in zip([1.0, 10.0], got):
        want = _plain_balance(b, f, [tip, mid], [tip, mid], force, law)
        assert np.max(np.abs(H - want)) <= 1e-12 * np.max(np.abs(want))
        assert np.max(np.abs(H - b.receptance(f, [tip, mid], [tip, mid]))) > 1e-3 * np.max(np.abs(want))  # not linear
