"""The benchmark's tool-in-holder truth (two concentric beams + contact layer) against known answers."""

import numpy as np
import pytest
import scipy.linalg

from jointdb.diagnose_bench._truth_stack import CARBIDE, STEEL, BeamPart, ToolInHolder

# a holder (body + bored nose) and a carbide tool inserted 30 mm, fluted near the tip
Z_FACE, INS, TIP = 0.09, 0.03, 0.15
HOLDER = [(0.0, 0.04, 0.045, 0.0, STEEL), (0.04, Z_FACE, 0.028, 0.014, STEEL)]
TOOL = [(Z_FACE - INS, 0.12, 0.014, 0.0, CARBIDE), (0.12, TIP, 0.0112, 0.0, CARBIDE)]


def _stack(kprime, **kw):
    return ToolInHolder.build(HOLDER, TOOL, Z_FACE, INS, TIP, kprime, extra_breaks=(0.085, 0.095), **kw)


def _composite(stack):
    """One beam on the same nodes with EI, κGA, ρA, ρI of holder and tool summed where they overlap."""
    z = np.unique(np.concatenate([stack.holder.z, stack.tool.z]))
    mid = 0.5 * (z[1:] + z[:-1])
    total = {k: np.zeros(mid.size) for k in ("EI", "kGA", "rhoA", "rhoI")}
    for part in (stack.holder, stack.tool):
        pm = 0.5 * (part.z[1:] + part.z[:-1])
        idx = np.searchsorted(mid, pm)
        assert np.allclose(mid[idx], pm)          # the two beams' nodes coincide
        for k in total:
            total[k][idx] += getattr(part, k)
    return BeamPart(z, **total)


def _clamped_modes(beam, n):
    K, M = beam.matrices()
    w2 = scipy.linalg.eigh(K[2:, 2:], M[2:, 2:], eigvals_only=True)[:n]
    return np.sqrt(w2) / (2 * np.pi)


def test_profile_is_normalised_to_the_mean_contact_stiffness():
    s = _stack(5e11, profile=lambda zeta: 1 + 0.5 * (2 * zeta - 1))
    assert s.contact_k.sum() == pytest.approx(5e11 * INS, rel=1e-12)
    zc = s.contact_z()
    trib = np.zeros(zc.size)
    trib[:-1] += np.diff(zc) / 2
    trib[1:] += np.diff(zc) / 2
    per_length = s.contact_k / trib
    assert np.all(np.diff(per_length) > 0)              # pressure rises towards the face
    assert per_length[-1] / per_length[0] == pytest.approx(1.5 / 0.5)
    r = 0.007
    assert np.allclose(s.contact_kt, s.contact_k * r**2 / 2)


def test_huge_contact_stiffness_gives_the_composite_beam():
    # With a practically rigid contact the two beams move as one section. What remains:
    # the contact's compliance at k' = 1e17 N/m² and the difference between summing two
    # Timoshenko elements with different shear parameters and one element with summed EI
    # and κGA (a discretisation error); both are ~5e-5 here, so 3e-4 is the tolerance.
    stiff = _stack(1e17).with_(base=None)
    f_two = stiff.natural_frequencies(4)
    f_one = _clamped_modes(_composite(stiff), 4)
    assert np.allclose(f_two, f_one, rtol=3e-4)
    # receptances too, away from resonances (tip and holder nose)
    f = np.array([500.0, 0.5 * (f_one[0] + f_one[1]), 0.5 * (f_one[1] + f_one[2])])
    H_two = stiff.receptance(f, [("tool", TIP), ("holder", 0.085)], [("tool", TIP)])
    comp = _composite(stiff)
    K, M = comp.matrices()
    tip, nose = 2 * (comp.z.size - 1), 2 * int(np.argmin(np.abs(comp.z - 0.085)))
    for k, fk in enumerate(f):
        w = 2 * np.pi * fk
        x = np.linalg.solve((K - w * w * M)[2:, 2:], np.eye(K.shape[0])[2:, tip])
        assert np.allclose(H_two[k, :, 0].real, x[[tip - 2, nose - 2]], rtol=2e-3)
    # and a realistic contact is clearly not rigid (the check above can fail)
    soft = _stack(1e11).with_(base=None).natural_frequencies(1)
    assert soft[0] < 0.95 * f_one[0]


def test_modal_sum_with_woodbury_equals_a_direct_complex_solve():
    s = _stack(4e11, profile=lambda zeta: 0.5 + zeta).with_(
        contact_loss=0.3, base=(2e10, 5e7), base_loss=0.05, rayleigh=(40.0, 3e-8))
    outs = [("tool", TIP), ("holder", 0.085), ("tool", 0.085, "t")]
    f = np.array([150.0, 1700.0, 2500.0, 9000.0])
    H = s.receptance(f, outs, [("tool", TIP)])
    K, M = s.matrices()                          # total stiffness: beams + contact + base
    B = s._contact_rows()
    Kc = B.T @ (s._contact_stiffness()[:, None] * B)
    Kb = np.zeros_like(K)
    Kb[0, 0], Kb[1, 1] = s.base
    rows = [s.dof(*o) for o in outs]
    e = np.zeros(K.shape[0])
    e[s.dof("tool", TIP)] = 1.0
    for k, fk in enumerate(f):
        w = 2 * np.pi * fk
        D = K + 1j * (0.3 * Kc + 0.05 * Kb) + 1j * w * (40.0 * M + 3e-8 * K) - w * w * M
        x = np.linalg.solve(D, e)
        assert np.allclose(H[k, :, 0], x[rows], rtol=1e-8)


def test_harmonic_balance_with_a_constant_law_is_the_linear_contact():
    s = _stack(4e11).with_(contact_loss=0.05, base=(2e10, 5e7), base_loss=0.03, rayleigh=(40.0, 0.0))
    f = np.linspace(300.0, 6000.0, 40)
    outs, ins = [("tool", TIP), ("holder", 0.085)], [("tool", TIP), ("tool", 0.095)]
    lin = s.receptance(f, outs, ins)
    same = s.receptance_amplitude_dependent(f, outs, ins, [10.0], lambda a: (np.ones_like(a), np.full(a.shape, 0.05)))
    assert np.allclose(same[0], lin, rtol=1e-10)
    # half the contact stiffness everywhere = the linear model with a contact half as stiff
    # (no stiffness-proportional damping here: it would follow the linear model's contact)
    half = s.receptance_amplitude_dependent(f, outs, ins, [10.0], lambda a: (np.full(a.shape, 0.5), np.full(a.shape, 0.05)))
    s2 = s.with_(contact_k=0.5 * s.contact_k, contact_kt=0.5 * s.contact_kt)
    assert np.allclose(half[0], s2.receptance(f, outs, ins), rtol=1e-8)


def test_harmonic_balance_solution_is_a_fixed_point_of_the_micro_slip_law():
    # check the converged balance with an independent direct solve: build the contact with
    # the stiffness the law gives for the solved amplitudes; its response must reproduce them
    s = _stack(3e11).with_(contact_loss=0.05, base=(2e10, 5e7), base_loss=0.03, rayleigh=(40.0, 1e-8))
    f1 = s.natural_frequencies(1)[0]
    a_c, force = 2e-7, 20.0

    def law(a):
        r = a / a_c
        return 1 - 0.6 * r / (1 + r), 0.05 + 0.3 * r / (1 + r)

    f = np.array([0.5, 0.95, 0.98, 1.0, 1.3]) * f1
    tip = ("tool", TIP)
    H = s.receptance_amplitude_dependent(f, [tip], [tip], [force], law)[0, :, 0, 0]
    K, M = s.matrices()
    B = s._contact_rows()
    k0 = s._contact_stiffness()
    Kc = B.T @ (k0[:, None] * B)
    Kb = np.zeros_like(K)
    Kb[0, 0], Kb[1, 1] = s.base
    e = np.zeros(K.shape[0])
    e[s.dof(*tip)] = force
    scale = s._slip_scale()
    for k, fk in enumerate(f):
        w = 2 * np.pi * fk
        D0 = K + 1j * 0.03 * Kb + 1j * w * (40.0 * M + 1e-8 * K) - w * w * M - Kc
        x = np.linalg.solve(D0 + Kc * (1 + 0.05j), e)        # start from the linear contact
        for _ in range(200):                                # plain fixed point with a direct solve
            sig, eta = law(np.abs(B @ x) * scale)
            x_new = np.linalg.solve(D0 + B.T @ ((k0 * sig * (1 + 1j * eta))[:, None] * B), e)
            if np.allclose(x_new, x, rtol=1e-12, atol=0):
                break
            x = 0.5 * (x + x_new)
        assert H[k] * force == pytest.approx(x[s.dof(*tip)], rel=1e-6)
    # and the contact did soften near mode 1 (the law is active, not a constant)
    sig, _ = law(np.abs(B @ x) * scale)
    assert sig.min() < 0.9


def test_rigidly_based_uniform_cantilever_is_euler_bernoulli():
    # a steel tube (12/6 mm) with a steel core (6 mm) over its whole length, tied by a stiff
    # contact, rigid base: a solid 12 mm rod, 1 m long. (k' = 1e13 N/m² is already rigid for
    # this rod; 1e17 would make the 9 Hz mode ill-conditioned against the contact springs.)
    L, D, d = 1.0, 0.012, 0.006
    s = ToolInHolder.build([(0.0, L, D, d, STEEL)], [(0.0, L, d, 0.0, STEEL)], L, L, L, 1e13, h=0.01)
    s = s.with_(base=None)
    A, I = np.pi * D**2 / 4, np.pi * D**4 / 64
    lam = np.array([1.875104, 4.694091])
    f_eb = lam**2 / (2 * np.pi) * np.sqrt(STEEL["E"] * I / (STEEL["rho"] * A * L**4))
    # without shear deformation only rotary inertia remains: (λ r_g / L)² ≤ 2e-4 for mode 2
    assert np.allclose(s.with_(shear=False).natural_frequencies(2), f_eb, rtol=3e-4)
    # with shear (L/D ≈ 83) the Timoshenko frequencies are slightly lower, within 1e-3
    f = s.natural_frequencies(2)
    assert np.all(f < f_eb) and np.allclose(f, f_eb, rtol=1e-3)


def test_rigid_clamp_shift_vanishes_for_a_rigid_base_and_grows_when_soft():
    s = _stack(5e11)
    assert np.all(np.abs(s.with_(base=(1e18, 1e16)).rigid_clamp_shift()) < 1e-6)
    soft = s.with_(base=(1e9, 1e6)).rigid_clamp_shift()
    assert np.all(soft > 0) and soft.max() > 0.01
