"""Semi-discretization against ZOA where ZOA is exact, flip lobes, convergence, time-domain simulation."""

import sys
from pathlib import Path

import numpy as np
import pytest

from jointdb.errors import InputError
from jointdb.modal import ModalModel
from jointdb.stability import (
    MillingCut,
    critical_depth,
    interval_directional_matrices,
    mean_directional_matrix,
    milling_lobes_sd,
    milling_lobes_sd_grid,
    milling_lobes_zoa,
    sd_system,
    spectral_radius,
)

sys.path.insert(0, str(Path(__file__).parent))
from dde_sim import simulate_growth  # noqa: E402

M, FN, ZETA = 0.03993, 922.0, 0.011
WN = 2 * np.pi * FN
K, C = M * WN**2, 2 * ZETA * M * WN
BENCH = ModalModel.from_modal_parameters([FN], [ZETA], [K], "1x")


def test_interval_matrices_average_to_the_zoa_mean():
    for cut in (MillingCut(2, 6e8, 2e8, 0.1, True), MillingCut(3, 6e8, 2e8, 0.4, False), MillingCut(2, 6e8, 2e8, 1.0)):
        h = interval_directional_matrices(cut, 37)
        np.testing.assert_allclose(h.mean(axis=0), mean_directional_matrix(cut), rtol=1e-10, atol=1e-2)


def test_sd_equals_zoa_when_the_directional_matrix_is_constant():
    # Four teeth in slotting: Σ over the teeth in cut of sin 2φ, cos 2φ cancels, H(t) ≡ H̄,
    # so the zero-order approximation is exact and SD must converge to it.
    cut = MillingCut(4, 6e8, 2e8, 1.0, True)
    h = interval_directional_matrices(cut, 16)
    np.testing.assert_allclose(h, np.broadcast_to(mean_directional_matrix(cut), h.shape), rtol=1e-9, atol=1.0)
    speeds = np.array([5000.0, 6000.0, 8000.0, 9000.0, 10000.0])
    zoa = milling_lobes_zoa(BENCH.synthesize(np.arange(500, 2000, 0.01)), cut, spindle_speed_rpm=speeds)
    sd = milling_lobes_sd(BENCH, cut, speeds, n_intervals=60)
    np.testing.assert_allclose(sd.depth_m, zoa.depth_m, rtol=0.02)
    np.testing.assert_allclose(sd.chatter_freq_hz, zoa.chatter_freq_hz, rtol=2e-3)
    assert set(sd.kind) == {"hopf"}


def altintas_model():
    mx = ModalModel([452.77, 1448.53], [0.1237, 0.0165], np.array([9.203e-5 - 1.862e-4j, -4.182e-5 - 3.044e-4j]).reshape(2, 1, 1), ("1x",), ("1x",))
    my = ModalModel([516.17, 1407.64], [0.0243, 0.0324], np.array([-2.393e-6 - 1.722e-4j, 4.055e-5 - 3.619e-4j]).reshape(2, 1, 1), ("1y",), ("1y",))
    return ModalModel.block_diagonal([mx, my])


def test_two_direction_multi_mode_sd_equals_zoa_for_constant_directional_matrix():
    model = altintas_model()
    cut = MillingCut(4, 1319.4e6, 788.8e6, 1.0, True)
    speeds = np.array([4500.0, 7000.0])
    zoa = milling_lobes_zoa(model.synthesize(np.arange(1, 4000, 0.1)), cut, spindle_speed_rpm=speeds)
    sd = milling_lobes_sd(model, cut, speeds, n_intervals=40)
    np.testing.assert_allclose(sd.depth_m, zoa.depth_m, rtol=0.03)


def test_two_tooth_slotting_sd_is_close_to_zoa_near_the_floor():
    # With two teeth H(t) varies within the period, so ZOA is only an approximation;
    # near the lobe minima both methods agree within a few per cent.
    cut = MillingCut(2, 6e8, 2e8, 1.0, True)
    speeds = np.array([10400.0, 15800.0])
    zoa = milling_lobes_zoa(BENCH.synthesize(np.arange(800, 1100, 0.01)), cut, spindle_speed_rpm=speeds)
    sd = milling_lobes_sd(BENCH, cut, speeds, n_intervals=60)
    np.testing.assert_allclose(sd.depth_m, zoa.depth_m, rtol=0.12)
    assert np.all(sd.depth_m > 0.298e-3 * 0.95)


@pytest.mark.parametrize("immersion", [0.05, 0.1])
def test_low_immersion_down_milling_shows_flip_lobes(immersion):
    cut = MillingCut(2, 6e8, 2e8, immersion, True)
    speeds = np.linspace(14000, 22000, 9)
    res = milling_lobes_sd(BENCH, cut, speeds, n_intervals=30)
    flip = res.kind == "flip"
    assert flip.any() and (res.kind == "hopf").any()
    # period doubling: the chatter frequency is an odd multiple of half the tooth frequency
    tau = 60.0 / (2 * res.spindle_speed_rpm[flip])
    np.testing.assert_allclose(np.mod(res.chatter_freq_hz[flip] * tau, 1.0), 0.5, atol=1e-6)
    # ZOA sees no flip lobe: there it predicts a much larger (or no) limit
    zoa = milling_lobes_zoa(BENCH.synthesize(np.arange(600, 1300, 0.02)), cut, spindle_speed_rpm=res.spindle_speed_rpm)
    z = np.where(np.isfinite(zoa.depth_m[flip]), zoa.depth_m[flip], np.inf)
    assert np.any(z > 1.5 * res.depth_m[flip])


def test_convergence_with_number_of_intervals():
    cut = MillingCut(2, 6e8, 2e8, 0.1, True)
    sysm = sd_system(BENCH, cut)
    for speed in (8000.0, 17000.0):
        ref = critical_depth(sysm, speed, 160, rtol=1e-7)[0]
        errs = [abs(critical_depth(sysm, speed, m, rtol=1e-7)[0] - ref) / ref for m in (10, 20, 40, 80)]
        assert all(a > b for a, b in zip(errs, errs[1:])), errs
        assert errs[2] < 0.05
        assert errs[2] / errs[3] > 2.5  # about second order in Δt


@pytest.mark.parametrize(
    "immersion,speed",
    [(1.0, 5000.0), (1.0, 10400.0), (0.1, 17000.0), (0.05, 12000.0)],
)
def test_time_domain_simulation_grows_above_and_decays_below_the_sd_boundary(immersion, speed):
    cut = MillingCut(2, 6e8, 2e8, immersion, True)
    sysm = sd_system(BENCH, cut)
    a_crit, _, kind, _, _ = critical_depth(sysm, speed, 80, rtol=1e-6)
    st, ex = cut.angles
    below, _ = simulate_growth(M, C, K, 6e8, 2e8, 2, st, ex, speed, 0.85 * a_crit)
    above, _ = simulate_growth(M, C, K, 6e8, 2e8, 2, st, ex, speed, 1.15 * a_crit)
    assert below < 0.995 < 1.005 < above, (kind, below, above)


def test_direct_search_matches_the_dense_grid():
    cut = MillingCut(2, 6e8, 2e8, 0.1, True)
    speeds = np.array([9000.0, 17000.0, 21000.0])
    depths = np.linspace(0.2e-3, 4e-3, 96)
    direct = milling_lobes_sd(BENCH, cut, speeds, n_intervals=20)
    grid = milling_lobes_sd_grid(BENCH, cut, speeds, depths, n_intervals=20)
    step = depths[1] - depths[0]
    assert np.all(grid.depth_m - step <= direct.depth_m + 1e-12)
    assert np.all(direct.depth_m <= grid.depth_m + 1e-12)
    assert direct.info["evaluations"] < grid.info["evaluations"] / 3


def test_sd_from_a_fitted_modal_model_matches_the_exact_model():
    from jointdb.modal import fit_modes

    frf = BENCH.synthesize(np.arange(600, 1300, 0.5))
    fit = fit_modes(frf, n_modes=1, max_order=10)
    cut = MillingCut(2, 6e8, 2e8, 0.5, True)
    speeds = np.array([9000.0, 15000.0])
    a = milling_lobes_sd(BENCH, cut, speeds, n_intervals=20)
    b = milling_lobes_sd(fit.model, cut, speeds, n_intervals=20)
    np.testing.assert_allclose(b.depth_m, a.depth_m, rtol=1e-3)


def test_sd_rejects_models_without_tool_tip_directions():
    model = ModalModel.from_modal_parameters([900], [0.01], [1e6], "3z")
    with pytest.raises(InputError, match="x or y"):
        milling_lobes_sd(model, MillingCut(2, 6e8, 2e8), [10000])
    with pytest.raises(InputError, match="n_intervals"):
        spectral_radius(sd_system(BENCH, MillingCut(2, 6e8, 2e8)), 10000, 1e-4, 1)


def test_sd_input_errors_are_actionable():
    cut = MillingCut(2, 6e8, 2e8)
    with pytest.raises(InputError, match="spindle speeds"):
        milling_lobes_sd(BENCH, cut, [np.nan])
    with pytest.raises(InputError, match="needs a ModalModel"):
        milling_lobes_sd(BENCH.synthesize([900.0, 950.0]), cut, [10000])
