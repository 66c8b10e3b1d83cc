"""Time-domain milling simulation against semi-discretization, the mean cutting force and runout."""

import numpy as np
import pytest

from jointdb.errors import InputError
from jointdb.modal import ModalModel
from jointdb.stability import MillingCut, mean_directional_matrix, milling_lobes_sd
from jointdb.stability._timedomain import simulate_milling

# Single-DOF benchmark of Insperger, Mann, Stépán & Bayly, "Stability of up-milling and down-milling",
# Int. J. Mach. Tools Manuf. 43 (2003): m = 0.03993 kg, f_n = 922 Hz, ζ = 0.011, K_t = 6e8, K_r = 2e8 N/m², 2 teeth.
M, FN, ZETA = 0.03993, 922.0, 0.011
K = M * (2 * np.pi * FN) ** 2
BENCH = ModalModel.from_modal_parameters([FN], [ZETA], [K], "1x")


def agreement(model, cut, speeds, *, revolutions=200, steps=None, n_intervals=60):
    """SD limits at ``speeds``; the simulation at 0.9× and 1.1× of each."""
    sd = milling_lobes_sd(model, cut, speeds, n_intervals=n_intervals)
    depth = np.asarray(sd.depth_m)
    sims = simulate_milling(model, cut, np.concatenate([speeds, speeds]), np.concatenate([0.9 * depth, 1.1 * depth]),
                            feed_per_tooth_m=5e-5, revolutions=revolutions, steps_per_tooth=steps)
    below, above = sims[: speeds.size], sims[speeds.size:]
    return sd, below, above


@pytest.mark.parametrize("immersion", [0.05, 1.0])
def test_single_dof_benchmark_agrees_with_semi_discretization(immersion):
    cut = MillingCut(2, 6e8, 2e8, immersion, True)
    speeds = np.linspace(6000, 24000, 10)  # across Hopf and flip lobes
    sd, below, above = agreement(BENCH, cut, speeds, steps=100)
    stable = sum(not s.chatter for s in below)
    chatter = sum(s.chatter for s in above)
    assert stable >= 9 and chatter >= 9, [(s.statistic, s.growth) for s in below + above]
    for s, fc in zip(above, sd.chatter_freq_hz):
        if s.chatter:
            assert abs(s.chatter_freq_hz - fc) <= 0.02 * fc, (s.spindle_speed_rpm, s.chatter_freq_hz, fc)
    if immersion < 1:
        assert {"hopf", "flip"} <= set(sd.kind)  # both kinds of boundary were tested


def test_mean_force_of_a_rigid_tool_is_the_directional_matrix_times_the_feed():
    # Very stiff tip: the chip is f_z sin φ, the force over a tooth period averages to −a H̄ (f_z, 0).
    stiff = ModalModel.from_modal_parameters([5000.0], [0.05], [1e13], "1x")
    stiff = ModalModel.block_diagonal([stiff, ModalModel.from_modal_parameters([5000.0], [0.05], [1e13], "1y")])
    for cut in (MillingCut(3, 7e8, 2e8, 0.3, True), MillingCut(2, 7e8, 2e8, 0.5, False)):
        fz, depth = 1e-4, 2e-3
        (sim,) = simulate_milling(stiff, cut, 6000.0, depth, feed_per_tooth_m=fz, revolutions=8, steps_per_tooth=400)
        period = cut.n_teeth * 400
        mean = sim.force_n[-period:].mean(axis=0)
        expected = -depth * mean_directional_matrix(cut)[:, 0] * fz
        np.testing.assert_allclose(mean, expected, rtol=2e-3, atol=1e-3 * np.abs(expected).max())
        assert not sim.chatter


def test_runout_makes_the_short_tooth_leave_the_cut():
    # Tooth 1 sits 2 f_z lower than tooth 0: tooth 0 cuts the chip of both (2 f_z), tooth 1 never touches.
    stiff = ModalModel.from_modal_parameters([5000.0], [0.05], [1e13], "1x")
    cut = MillingCut(2, 7e8, 2e8, 1.0, True)
    fz = 5e-5
    (even,) = simulate_milling(stiff, cut, 6000.0, 1e-3, feed_per_tooth_m=fz, revolutions=8, steps_per_tooth=200)
    (runout,) = simulate_milling(stiff, cut, 6000.0, 1e-3, feed_per_tooth_m=fz, revolutions=8, steps_per_tooth=200,
                                 runout_m=[0.0, -2 * fz])
    rev = 2 * 200
    f_even = np.linalg.norm(even.force_n[-rev:], axis=1)
    f_run = np.linalg.norm(runout.force_n[-rev:], axis=1)
    np.testing.assert_allclose(f_run.max(), 2 * f_even.max(), rtol=1e-3)
    assert np.all(f_run[rev // 2 + 20: rev - 20] == 0)  # the second tooth's half revolution: no cut (edges aside)
    np.testing.assert_allclose(f_run.mean(), f_even.mean(), rtol=1e-3)  # the same material is removed


def test_chatter_is_bounded_when_the_tool_leaves_the_cut():
    cut = MillingCut(2, 6e8, 2e8, 1.0, True)
    sd = milling_lobes_sd(BENCH, cut, [10000.0], n_intervals=60)
    (sim,) = simulate_milling(BENCH, cut, 10000.0, 1.5 * sd.depth_m[0], feed_per_tooth_m=5e-5, revolutions=200,
                              steps_per_tooth=100)
    assert sim.chatter
    amp = np.abs(sim.displacement_m[:, 0])
    n = amp.size
    # amplitude saturates: the last quarter is no larger than the third (the linear model would grow without bound)
    assert amp[3 * n // 4:].max() <= 1.2 * amp[n // 2: 3 * n // 4].max()
    assert amp.max() < 1e-3


def test_bad_inputs_are_refused_with_a_message():
    cut = MillingCut(2, 6e8, 2e8, 0.5, True)
    with pytest.raises(InputError, match="one depth per speed"):
        simulate_milling(BENCH, cut, [5000.0, 6000.0], [1e-3])
    with pytest.raises(InputError, match="runout"):
        simulate_milling(BENCH, cut, 5000.0, 1e-3, runout_m=[0.0])
    with pytest.raises(InputError, match="> 0 rpm"):
        simulate_milling(BENCH, cut, -5.0, 1e-3)


def test_demo_tip_agrees_with_semi_discretization():
    # data/demo-tip.uff: the tool-tip FRF `jointdb demo` predicts (x and y planes, catalogued joints);
    # the demo's cut (4 teeth, half immersion, down-milling). The same pLSCF modal fit feeds SD and the simulation.
    from pathlib import Path

    from jointdb.io import read_frf_uff58
    from jointdb.modal import fit_tool_tip

    model, fits = fit_tool_tip(read_frf_uff58(Path(__file__).parent / "data" / "demo-tip.uff"))
    assert all(f.quality.nmse_total < 0.01 for f in fits)
    cut = MillingCut(4, 7.96e8, 0.212 * 7.96e8, 0.5, True)
    speeds = np.linspace(8000, 26000, 10)
    sd, below, above = agreement(model, cut, speeds, revolutions=150)
    assert sum(not s.chatter for s in below) >= 9
    assert sum(s.chatter for s in above) >= 9
    for s, fc in zip(above, sd.chatter_freq_hz):
        if s.chatter:
            assert abs(s.chatter_freq_hz - fc) <= 0.02 * fc, (s.spindle_speed_rpm, s.chatter_freq_hz, fc)
