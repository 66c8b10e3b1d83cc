"""Planar spring–damper joint identification (docs/theory.md §2a; thesis §4.3 first simulation, Table 4.1)."""

import numpy as np
import pytest
from coupling_beams import beam, clamp_first, labels_for

from jointdb.coupling import Interface, couple, fit_constant_kc, identify_planar_joint, spring_damper_joint
from jointdb.coupling._matrices import receptance_from_matrices
from jointdb.errors import InputError

FREQ = np.linspace(5.0, 3000.0, 600)
KX, CX, KR, CR = 2e6, 100.0, 8e4, 80.0  # thesis Table 4.1


def build_case(freq=FREQ, eta=0.01, joint=(KX, CX, KR, CR)):
    """A: clamped-free 0.30 m, Ø30 mm, contact node 3 at its free end (nodes 100.. then 3).
    B: free-free 0.15 m, Ø16 mm, contact node 2 at its start, tip node 1 at its end.
    Returns the substructure FRFs and the monolithic assembly with the spring joint."""
    na, nb = 6, 3
    Ka, Ma = beam(0.30, 0.030, na, eta=eta)
    la = labels_for([99] + [100 + i for i in range(1, na)] + [3])
    Ka, Ma, la = clamp_first(Ka, Ma, la)
    Kb, Mb = beam(0.15, 0.016, nb, eta=eta)
    lb = labels_for([2] + [200 + i for i in range(1, nb)] + [1])
    A = receptance_from_matrices(freq, Ka, Ma, la)
    B = receptance_from_matrices(freq, Kb, Mb, lb)
    kx, cx, kr, cr = joint
    n = len(la) + len(lb)
    K = np.zeros((n, n), complex)
    M = np.zeros((n, n))
    C = np.zeros((n, n))
    K[: len(la), : len(la)] = Ka
    K[len(la):, len(la):] = Kb
    M[: len(la), : len(la)] = Ma
    M[len(la):, len(la):] = Mb
    labels = la + lb
    for (dof_a, dof_b, k, c) in (("3x", "2x", kx, cx), ("3ry", "2ry", kr, cr)):
        i, j = labels.index(dof_a), labels.index(dof_b)
        for (p, q, s) in ((i, i, 1), (j, j, 1), (i, j, -1), (j, i, -1)):
            K[p, q] += s * k
            C[p, q] += s * c
    G = receptance_from_matrices(freq, K, M, labels, C, outputs=["1x", "2x"], inputs=["1x", "2x"])
    return A, B, G


def test_table_4_1_joint_recovered_exactly_at_every_line():
    A, B, G = build_case()
    res = identify_planar_joint(G, A, 3, B, 2, 1)
    ht, hr = res.joint.entry("3x", "3x"), res.joint.entry("3ry", "3ry")
    w = 2 * np.pi * FREQ
    ht_true, hr_true = 1 / (KX + 1j * w * CX), 1 / (KR + 1j * w * CR)
    err_t = np.abs(ht - ht_true) / np.abs(ht_true)
    err_r = np.abs(hr - hr_true) / np.abs(hr_true)
    assert err_t.max() <= 1e-8, err_t.max()
    assert err_r.max() <= 1e-8, err_r.max()
    assert not res.flags["degenerate"].any()
    assert res.residual.max() < 1e-8
    assert np.all(res.joint.values[:, 0, 1] == 0)


def test_the_other_root_is_non_passive_on_most_lines():
    A, B, G = build_case()
    res = identify_planar_joint(G, A, 3, B, 2, 1)
    other = 1 - res.extra["choice"]
    idx = np.arange(FREQ.size)
    xs, ys = res.extra["roots_x"], res.extra["roots_y"]
    HB = B.select(["2x", "2ry"], ["2x", "2ry"]).values
    HA = A.select(["3x", "3ry"], ["3x", "3ry"]).values
    ht_other = xs[idx, other] - HB[:, 0, 0] - HA[:, 0, 0]
    hr_other = ys[idx, other] - HB[:, 1, 1] - HA[:, 1, 1]
    non_passive = (ht_other.imag > 0) | (hr_other.imag > 0)
    assert non_passive.mean() > 0.9
    assert res.flags["ambiguous"].mean() < 0.1


def test_undamped_joint_recovered_where_passivity_cannot_decide():
    # No damping anywhere: both roots are real (passivity is silent); the spurious
    # root of the elimination fails to reproduce the measurement and is rejected.
    A, B, G = build_case(eta=0.0, joint=(KX, 0.0, KR, 0.0))
    res = identify_planar_joint(G, A, 3, B, 2, 1)
    assert np.max(np.abs(res.joint.entry("3x", "3x") * KX - 1)) < 1e-6  # undamped: resonances amplify round-off
    assert np.max(np.abs(res.joint.entry("3ry", "3ry") * KR - 1)) < 1e-6
    assert not res.unreliable.any()


def test_coupling_back_reproduces_the_measurement():
    A, B, G = build_case()
    res = identify_planar_joint(G, A, 3, B, 2, 1)
    g = couple({"A": A, "B": B}, [Interface("A", ["3x", "3ry"], "B", ["2x", "2ry"], res.joint)],
               outputs=[("B", "1x")], inputs=[("B", "1x"), ("B", "2x")])
    ref = G.select(["1x"], ["1x", "2x"])
    assert np.max(np.abs(g.values - ref.values) / np.abs(ref.values)) < 1e-8
    # and with the exact spring–damper joint
    exact = spring_damper_joint(FREQ, [KX, KR], [CX, CR], ["3x", "3ry"])
    g2 = couple({"A": A, "B": B}, [Interface("A", ["3x", "3ry"], "B", ["2x", "2ry"], exact)], [("B", "1x")])
    assert np.max(np.abs(g2.values[:, 0, 0] - ref.values[:, 0, 0]) / np.abs(ref.values[:, 0, 0])) < 1e-9


def test_noise_and_smoothing_reduce_error():
    A, B, G = build_case()
    rng = np.random.default_rng(7)
    noise = 0.01 * np.abs(G.values) * (rng.standard_normal(G.values.shape) + 1j * rng.standard_normal(G.values.shape)) / np.sqrt(2)
    noisy = G.replace(values=G.values + noise)
    w = 2 * np.pi * FREQ
    ht_true = 1 / (KX + 1j * w * CX)
    raw = identify_planar_joint(noisy, A, 3, B, 2, 1)
    smooth = identify_planar_joint(noisy, A, 3, B, 2, 1, smoothing=15)
    e_raw = np.median(np.abs(raw.joint.entry("3x", "3x") - ht_true) / np.abs(ht_true))
    e_smooth = np.median(np.abs(smooth.joint.entry("3x", "3x") - ht_true) / np.abs(ht_true))
    assert e_smooth < e_raw
    assert 0 < raw.summary()["residual_median"]
    # Named tolerances, 1 % noise (seeds 7-9 measured: h_t median 3.0-3.3 % raw, 1.6-1.8 % smoothed;
    # constant fit on the reliable smoothed lines: k_x 0.06 %, c_x 0.3 %, k_r 1 % off Table 4.1).
    # The rotational term per line is far noisier (~46 % median smoothed): the thesis's observation.
    H_T_TOL_RAW, H_T_TOL_SMOOTH, KX_TOL, CX_TOL, KR_TOL = 0.05, 0.025, 5e-3, 1e-2, 3e-2
    assert e_raw < H_T_TOL_RAW and e_smooth < H_T_TOL_SMOOTH
    fit = fit_constant_kc(smooth.joint, mask=~smooth.unreliable)
    assert abs(fit.k[0] / KX - 1) < KX_TOL and abs(fit.c[0] / CX - 1) < CX_TOL
    assert abs(fit.k[1] / KR - 1) < KR_TOL


def test_missing_rotations_fail_clearly():
    A, B, G = build_case()
    A_t = A.select(["3x"], ["3x"])
    with pytest.raises(InputError, match="substructure A has no FRF between 3x and 3ry"):
        identify_planar_joint(G, A_t, 3, B, 2, 1)
    with pytest.raises(InputError, match="assembly has no FRF between 1x and 2x"):
        identify_planar_joint(G.select(["1x"], ["1x"]), A, 3, B, 2, 1)
    with pytest.raises(InputError, match="resample"):
        identify_planar_joint(G.band(fmax=1000), A, 3, B, 2, 1)
    with pytest.raises(InputError, match="window"):
        identify_planar_joint(G, A, 3, B, 2, 1, smoothing=4)
