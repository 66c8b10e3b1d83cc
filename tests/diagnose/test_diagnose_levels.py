"""Local modal fit and level tracking (jointdb.diagnose._levels) on synthetic FRFs with known poles.

The synthetic sets are sums of modes ``φ φᵀ / (ω_r² − ω² + 2iζω_rω)`` on three
outputs and two inputs; noisy sets multiply every line by ``exp(ε)``, ``ε``
complex normal with ``E|ε|² = σ²``, and pass ``weight = 1/σ`` as the
preparation step does.
"""

import numpy as np
import pytest

from jointdb.diagnose import find_peaks, local_modal_fit, track_modes
from jointdb.diagnose._levels import FREQ_FLOOR, ZETA_FLOOR
from jointdb.errors import InputError

#: mode shapes (rows: modes) at three output DOFs; inputs are the first two DOFs
PHI = np.array([[1.0, 0.5, 0.2], [-0.6, 0.8, 0.3], [0.3, -0.4, 1.0]])
FREQ = np.arange(200.0, 4000.0, 1.0)


def synth(modes, freq=FREQ, shapes=PHI):
    w = 2 * np.pi * freq
    H = np.zeros((freq.size, 3, 2), complex)
    for (fr, z), phi in zip(modes, shapes):
        wr = 2 * np.pi * fr
        H += (phi[:, None] * phi[None, :2])[None] / (wr**2 - w**2 + 2j * z * wr * w)[:, None, None]
    return H


def noisy(H, sigma, rng):
    eps = sigma / np.sqrt(2) * (rng.standard_normal(H.shape) + 1j * rng.standard_normal(H.shape))
    return H * np.exp(eps), np.full(H.shape, 1.0 / sigma)


def unmodelled_fraction(modes, k, band):
    """How much of the other modes' contribution in ``band`` the local model cannot absorb.

    The out-of-band terms of the local model span {(ω_c/ω)², 1, ω/ω_c − 1}; the
    other modes' sum is projected on them per FRF entry (independent of the
    code under test) and the largest left-over, relative to mode ``k``'s peak
    ``|φφᵀ|/(2ζω_r²)``, is returned. A perturbation of relative size ε at the
    peak moves the pole by ≲ ε·ζ·ω_r and the damping by ≲ ε·ζ relative.
    """
    sel = (FREQ >= band[0]) & (FREQ <= band[1])
    fr, z = modes[k]
    others = synth([m for j, m in enumerate(modes) if j != k], FREQ[sel],
                   np.delete(PHI[: len(modes)], k, axis=0)).reshape(sel.sum(), -1)
    r = FREQ[sel] / fr
    basis = np.column_stack([r**-2, np.ones_like(r), r - 1])
    coef, *_ = np.linalg.lstsq(basis, others, rcond=None)
    left = np.abs(others - basis @ coef).max(axis=0)
    peak = np.abs(PHI[k][:, None] * PHI[k][None, :2]).ravel() / (2 * z * (2 * np.pi * fr) ** 2)
    return float((left / peak).max())


# --------------------------------------------------------------------- clean data

def test_exact_recovery_when_the_data_are_in_the_local_model_class():
    """One mode plus exactly the out-of-band terms of the local model: the pole to round-off."""
    w = 2 * np.pi * FREQ
    fr, z = 2305.0, 0.011
    wr = 2 * np.pi * fr
    A = np.array([[1.0, 0.4], [0.6 - 0.1j, 0.2], [-0.3, 0.1j]])
    H = A[None] / (wr**2 - w**2 + 2j * z * wr * w)[:, None, None]
    H = H + 1e-9 * (wr / w)[:, None, None] ** 2 * np.arange(1, 7).reshape(3, 2) + 3e-10 * (1 + 0.2j)
    fit = local_modal_fit(FREQ, H, None, 2300.0)
    # conditioning of the pole from the projected residual is ~1e4; round-off ~1e-16 → 1e-10 is generous
    assert abs(fit.freq_hz / fr - 1) < 1e-10
    assert abs(fit.zeta / z - 1) < 1e-8
    np.testing.assert_allclose(fit.residues, A, rtol=1e-7)
    assert fit.chi2_red < 1e-20


@pytest.mark.parametrize("modes", [
    [(800.0, 0.012), (2305.0, 0.011), (3300.0, 0.015)],
    [(800.0, 0.02), (1200.0, 0.02), (1700.0, 0.02)],
])
def test_multi_mode_recovery_within_the_unmodelled_neighbour_bound(modes):
    for k, (fr, z) in enumerate(modes):
        fit = local_modal_fit(FREQ, synth(modes), None, fr * 1.003)
        eps = unmodelled_fraction(modes, k, fit.band)
        assert abs(fit.freq_hz / fr - 1) <= 2 * eps * z + 1e-12, (k, eps)
        assert abs(fit.zeta / z - 1) <= 2 * eps + 1e-10, (k, eps)


def test_close_modes_are_fitted_together():
    """Two modes 4 % apart (ζ = 1 %: their half-power bands nearly touch): each fit takes the other along."""
    modes = [(1000.0, 0.01), (1040.0, 0.01), (3000.0, 0.01)]
    H = synth(modes)
    for k in (0, 1):
        fit = local_modal_fit(FREQ, H, None, modes[k][0])
        assert len(fit.neighbours) == 1
        assert fit.neighbours[0][0] == pytest.approx(modes[1 - k][0], rel=1e-6)
        eps = unmodelled_fraction([modes[k], modes[1 - k], modes[2]], 0, fit.band)  # only mode 3 is unmodelled
        assert abs(fit.freq_hz / modes[k][0] - 1) <= 2 * eps * 0.01 + 1e-9
        assert abs(fit.zeta / 0.01 - 1) <= 2 * eps + 1e-6
    # a single well-separated mode earns no extra pole
    assert local_modal_fit(FREQ, H, None, 3000.0).neighbours == ()


def test_mode_near_the_edge_of_the_recorded_band():
    modes = [(205.0, 0.01), (1500.0, 0.01)]
    fit = local_modal_fit(FREQ, synth(modes), None, 205.0)
    assert fit.band[0] == FREQ[0]            # the band is cut by the recording
    eps = unmodelled_fraction(modes, 0, fit.band)
    assert abs(fit.freq_hz / 205 - 1) <= 2 * eps * 0.01 + 1e-10
    assert abs(fit.zeta / 0.01 - 1) <= 2 * eps + 1e-8


def test_lightly_damped_mode_agrees_with_the_half_power_estimate():
    """ζ = 0.3 % on a 0.25 Hz grid: half-power bandwidth 6 Hz = 24 lines, so its interpolation error is
    ≲ (line spacing / bandwidth)² ≈ 0.2 %; both must agree with the truth and each other to 1 %."""
    f = np.arange(500.0, 1500.0, 0.25)
    H = synth([(1000.0, 0.003), (1400.0, 0.01)], f)
    fit = local_modal_fit(f, H, None, 1000.0)
    hp = find_peaks(f, H, np.ones(H.shape))[0]
    assert fit.zeta == pytest.approx(0.003, rel=1e-4)
    assert hp.zeta == pytest.approx(0.003, rel=0.01)
    assert fit.zeta == pytest.approx(hp.zeta, rel=0.01)
    assert fit.freq_hz == pytest.approx(1000.0, rel=1e-7)


def test_too_few_lines_and_bad_shapes_are_refused():
    f = np.arange(1000.0, 1100.0, 20.0)
    H = synth([(1050.0, 0.01)], f)
    with pytest.raises(InputError, match="fewer than 8 usable lines"):
        local_modal_fit(f, H, None, 1050.0)
    with pytest.raises(InputError, match="outside the recorded"):
        local_modal_fit(FREQ, synth([(1000.0, 0.01)]), None, 5000.0)
    with pytest.raises(InputError, match="expected"):
        track_modes(FREQ, synth([(1000.0, 0.01)]), None, [1.0])
    # a peak that cannot be fitted at some level is not followed, and the analysis says so
    f = np.concatenate([np.arange(200.0, 2000.0, 2.0), np.arange(2000.0, 4000.0, 200.0)])  # coarse above 2 kHz
    a = track_modes(f, np.stack([synth([(1000.0, 0.01)], f)] * 2), None, [1.0, 2.0], centres=[1000.0, 3800.0])
    assert [t.mode for t in a.tracks] == [1] and a.skipped == (3800.0,)
    assert a.summary().splitlines()[-1] == "not followed (too few recorded lines around the peak at some level): " \
                                           "3800 Hz"


# --------------------------------------------------------------------- noisy data

def test_noisy_recovery_and_sigma_coverage_over_seeds():
    """2 % noise, 60 seeds: the reported 1-σ must describe the actual error.

    For a correct σ, |error| < 2σ holds with probability 0.954; over 60 seeds
    the count has a binomial sd of 1.6, so ≥ 52 (mean − 3 sd) is required, and
    the RMS of error/σ must lie in 1 ± 0.3 (its sampling sd with 60 seeds is ~0.09).
    """
    modes = [(800.0, 0.012), (2305.0, 0.011), (3300.0, 0.015)]
    H = synth(modes)
    rng = np.random.default_rng(20260)
    zf, zz = [], []
    for _ in range(60):
        Hn, w = noisy(H, 0.02, rng)
        fit = local_modal_fit(FREQ, Hn, w, 2305.0)
        zf.append((fit.freq_hz - 2305.0) / fit.sigma_freq_hz)
        zz.append((fit.zeta - 0.011) / fit.sigma_zeta)
        # noise-derived size of σ: σ_f ≈ σ·ζ·f/√(2 × 6 entries × ~50 lines in the half-power band)
        # ≈ 0.02 Hz and σ_ζ/ζ ≈ the same relative; the local model's extra terms cost a factor ~2–3:
        # allow 10×
        assert fit.sigma_freq_hz < 10 * 0.02 * 0.011 * 2305 / np.sqrt(600)
        assert fit.sigma_zeta < 10 * 0.02 * 0.011 / np.sqrt(600)
    zf, zz = np.abs(zf), np.abs(zz)
    assert (zf < 2).sum() >= 52 and (zz < 2).sum() >= 52, ((zf < 2).sum(), (zz < 2).sum())
    assert 0.7 < np.sqrt(np.mean(zf**2)) < 1.3 and 0.7 < np.sqrt(np.mean(zz**2)) < 1.3
    assert zf.max() < 5 and zz.max() < 5


# --------------------------------------------------------------------- levels

def level_set(per_level, sigmas, rng, freq=FREQ):
    vals, wts = [], []
    for modes, s in zip(per_level, sigmas):
        Hn, w = noisy(synth(modes, freq), s, rng)
        vals.append(Hn)
        wts.append(w)
    return np.stack(vals), np.stack(wts)


def test_level_dependent_set_is_flagged_with_the_right_signs():
    """Mode 1 softens 2305 → 2260 → 2185 Hz with ζ 1.1 → 1.4 → 2.0 %; modes 2, 3 do not change."""
    truth = [[(1200.0, 0.012), (2305.0, 0.011), (3500.0, 0.015)],
             [(1200.0, 0.012), (2260.0, 0.014), (3500.0, 0.015)],
             [(1200.0, 0.012), (2185.0, 0.020), (3500.0, 0.015)]]
    levels = [0.5, 5.0, 25.0]
    rng = np.random.default_rng(7)
    vals, wts = level_set(truth, [0.015, 0.012, 0.02], rng)
    a = track_modes(FREQ, vals, wts, levels)
    assert [round(t.freq_hz[0]) for t in a.tracks] == [1200, 2305, 3500]
    m1, m2, m3 = a.tracks
    assert a.differs and m2.differs and not m1.differs and not m3.differs
    assert m2.differs_freq and m2.differs_zeta
    assert m2.freq_change == pytest.approx(2185 / 2305 - 1, rel=0.02)
    assert m2.zeta_ratio == pytest.approx(2.0 / 1.1, rel=0.05)
    for lv in range(3):
        fr, z = truth[lv][1]
        assert abs(m2.freq_hz[lv] - fr) < 5 * m2.sigma_freq_hz[lv]
        assert abs(m2.zeta[lv] - z) < 5 * m2.sigma_zeta[lv]
    # amplitude = peak receptance × force at the DOF with the largest peak, rising with level
    assert m2.amplitude_unit == "m" and np.all(np.diff(m2.amplitude) > 0)
    assert m2.amplitude[0] == pytest.approx(m2.peak[0] * 0.5)
    line = a.summary().splitlines()[1]
    assert line.startswith("the 2305 Hz mode: 2305") and "→" in line and "changes with level" in line
    assert "ζ 1.1 → 1.4 → 2.0 %" in line
    d = a.to_dict()
    assert d["differs"] is True and d["modes"][1]["differs_freq"] is True and len(d["modes"][1]["freq_hz"]) == 3


def test_levels_given_out_of_order_are_tracked_from_the_lowest():
    truth = [[(2185.0, 0.020)], [(2305.0, 0.011)], [(2260.0, 0.014)]]
    rng = np.random.default_rng(8)
    vals, wts = level_set(truth, [0.01, 0.01, 0.01], rng)
    a = track_modes(FREQ, vals, wts, [25.0, 0.5, 5.0])
    t = a.tracks[0]
    assert a.order == (1, 2, 0)
    assert t.freq_hz[0] == pytest.approx(2185, rel=1e-3) and t.freq_change < 0 and t.zeta_ratio > 1
    assert a.summary().startswith("the 2305 Hz mode: 2305")


def test_level_independent_sets_with_different_noise_are_not_flagged():
    """False alarms: the same structure at three levels with noise 0.5 %, 2 % and 4 %, 25 seeds, 3 modes.

    Without the practical floor the χ² test alone would flag ~2 × 3 × 25 × 1e-3 = 0.15 mode-levels by
    chance; with it, none may be flagged."""
    modes = [(800.0, 0.012), (2305.0, 0.011), (3300.0, 0.015)]
    flagged = 0
    for seed in range(25):
        rng = np.random.default_rng(1000 + seed)
        vals, wts = level_set([modes] * 3, [0.005, 0.02, 0.04], rng)
        a = track_modes(FREQ, vals, wts, [1.0, 5.0, 20.0])
        assert len(a.tracks) == 3
        flagged += sum(t.differs for t in a.tracks)
    assert flagged == 0


def test_the_practical_floor_separates_significant_from_relevant():
    """A 0.05 % shift is far beyond 0.1 %-noise σ (χ² flags it) but below FREQ_FLOOR: not a level dependence;
    a 0.3 % shift is."""
    rng = np.random.default_rng(11)
    f = np.arange(1800.0, 2800.0, 0.5)
    small = [[(2305.0, 0.011)], [(2305.0 * (1 - FREQ_FLOOR / 2), 0.011)]]
    vals, wts = level_set(small, [0.001, 0.001], rng, f)
    t = track_modes(f, vals, wts, [1.0, 10.0]).tracks[0]
    assert t.p_freq < 1e-6 and not t.differs_freq
    big = [[(2305.0, 0.011)], [(2305.0 * (1 - 3 * FREQ_FLOOR), 0.011 * ZETA_FLOOR * 1.2)]]
    vals, wts = level_set(big, [0.01, 0.01], rng, f)
    t = track_modes(f, vals, wts, [1.0, 10.0]).tracks[0]
    assert t.differs_freq and t.differs_zeta and t.freq_change < 0 and t.zeta_ratio > 1


def test_six_level_trend_agrees_with_half_power_estimates():
    """A bolted-beam-like set: 98.1 → 97.5 Hz and damping +30 % over six levels, lightly damped, 0.05 Hz lines.

    The frequency and damping trends (highest vs lowest level) must agree in sign and within 20 % in size
    with half-power estimates of the same recordings (find_peaks), and with the truth."""
    f = np.arange(80.0, 120.0, 0.05)
    fr = np.linspace(98.1, 97.5, 6)
    zr = 0.004 * np.linspace(1.0, 1.3, 6)
    rng = np.random.default_rng(3)
    vals, wts = level_set([[(a, b), (300.0, 0.01)] for a, b in zip(fr, zr)], [0.01] * 6, rng, f)
    a = track_modes(f, vals, wts, [0.2, 0.5, 1.0, 2.0, 4.0, 8.0])
    t = a.tracks[0]
    assert t.differs_freq and t.differs_zeta
    hp = [find_peaks(f, vals[k], wts[k])[0] for k in range(6)]
    hp_df = hp[-1].freq_hz / hp[0].freq_hz - 1
    hp_zr = hp[-1].zeta / hp[0].zeta
    assert np.sign(t.freq_change) == np.sign(hp_df) == -1
    assert t.freq_change == pytest.approx(hp_df, rel=0.2)
    assert t.freq_change == pytest.approx(97.5 / 98.1 - 1, rel=0.05)
    assert (t.zeta_ratio - 1) == pytest.approx(hp_zr - 1, rel=0.2)
    assert t.zeta_ratio == pytest.approx(1.3, rel=0.05)


def test_single_level_never_differs():
    rng = np.random.default_rng(2)
    vals, wts = level_set([[(1000.0, 0.01)]], [0.02], rng)
    a = track_modes(FREQ, vals, wts, [None])
    assert not a.differs and a.tracks[0].amplitude_unit == "m/N" and "within noise" not in a.summary()


def test_backbone_plot_of_data_and_model(tmp_path):
    from jointdb.diagnose import LevelAnalysis
    from jointdb.plots import plot_backbone

    truth = [[(1200.0, 0.012), (2305.0, 0.011)], [(1200.0, 0.012), (2260.0, 0.014)],
             [(1200.0, 0.012), (2185.0, 0.020)]]
    rng = np.random.default_rng(5)
    vals, wts = level_set(truth, [0.01] * 3, rng)
    a = track_modes(FREQ, vals, wts, [0.5, 5.0, 25.0])
    model = track_modes(FREQ, np.stack([synth(t) for t in truth]), None, [0.5, 5.0, 25.0],
                        centres=[t.freq_hz[0] for t in a.tracks])
    assert [t.mode for t in model.tracks] == [t.mode for t in a.tracks]
    path = plot_backbone(a, tmp_path / "backbone.png", model)
    assert path.stat().st_size > 10_000 and path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(InputError, match="no mode could be followed"):
        plot_backbone(LevelAnalysis((), (1.0, 2.0), (0, 1)), tmp_path / "none.png")
    assert not (tmp_path / "none.png").exists()
