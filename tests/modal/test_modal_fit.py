"""Modal parameter estimation (pLSCF + LSFD) on synthetic FRFs with known modes and on a real file."""

from pathlib import Path

import numpy as np
import pytest

from jointdb.errors import InputError, NumericalError
from jointdb.frf import FRF
from jointdb.modal import ModalModel, fit_modes, single_dof_residue

# Noise-free data from an exact modal model: pLSCF + LSFD recover it to ~1e-8 (freq)
# and ~1e-6 (zeta, residues); the tolerances leave two decades of margin, no more, so
# that a systematic bias (e.g. zeta from omega_d instead of omega_n, ~zeta^2/2) fails.
FREQ_TOL_NOISE_FREE = 1e-6
ZETA_TOL_NOISE_FREE = 1e-4
RESIDUE_TOL_NOISE_FREE = 1e-4
FREQ_TOL_NOISY = 5e-3  # 0.5 % with 1 % (of peak) complex Gaussian noise
ZETA_TOL_NOISY = 0.15  # 15 %
REAL_FILE = Path(__file__).resolve().parents[1] / "data" / "measured-accelerance-3refs.uff"


def three_dof_system():
    """Chain of three masses (proportional damping): exact modes and rank-one residues."""
    m = np.diag([1.0, 1.5, 0.8])
    k = 1e6 * np.array([[2.0, -1.0, 0.0], [-1.0, 2.2, -1.2], [0.0, -1.2, 1.2]])
    w2, phi = np.linalg.eigh(np.linalg.solve(np.sqrt(m), np.linalg.solve(np.sqrt(m), k).T))
    phi = np.linalg.solve(np.sqrt(m), phi)  # mass-normalised
    wn = np.sqrt(w2)
    zeta = np.array([0.02, 0.015, 0.01])
    wd = wn * np.sqrt(1 - zeta**2)
    res = np.einsum("ir,jr->rij", phi, phi) * (-1j / (2 * wd))[:, None, None]
    dofs = ("1x", "2x", "3x")
    return ModalModel(wn / (2 * np.pi), zeta, res, dofs, dofs)


@pytest.mark.parametrize("quantity", ["receptance", "mobility", "accelerance"])
def test_driving_point_modes_recovered_noise_free(quantity):
    true = ModalModel.from_modal_parameters([150, 250, 410], [0.01, 0.012, 0.03], [2e7, 5e7, 8e7])
    frf = true.synthesize(np.linspace(50, 600, 1101), quantity)
    fit = fit_modes(frf, n_modes=3, max_order=20)
    np.testing.assert_allclose(fit.freq_hz, true.freq_hz, rtol=FREQ_TOL_NOISE_FREE)
    np.testing.assert_allclose(fit.zeta, true.zeta, rtol=ZETA_TOL_NOISE_FREE)
    np.testing.assert_allclose(fit.residues, true.residues, rtol=RESIDUE_TOL_NOISE_FREE)
    np.testing.assert_allclose(fit.model.modal_mass_stiffness()["stiffness"], [2e7, 5e7, 8e7],
                               rtol=RESIDUE_TOL_NOISE_FREE)
    assert fit.quality.nmse_total < 1e-8 and fit.quality.frac_min > 1 - 1e-8
    assert fit.quantity.value == quantity


def test_mimo_modes_and_residue_matrices_recovered():
    true = three_dof_system()
    frf = true.synthesize(np.linspace(20, 400, 800), "accelerance").select(inputs=["1x", "3x"])
    fit = fit_modes(frf, n_modes=3, max_order=12)
    np.testing.assert_allclose(fit.freq_hz, true.freq_hz, rtol=FREQ_TOL_NOISE_FREE)
    np.testing.assert_allclose(fit.zeta, true.zeta, rtol=ZETA_TOL_NOISE_FREE)
    np.testing.assert_allclose(fit.residues, true.residues[:, :, [0, 2]], rtol=RESIDUE_TOL_NOISE_FREE, atol=1e-12)
    # vector stability is checked on multi-input data: the chosen poles are stable in all three senses
    assert (fit.diagram.status == "s").sum() >= 3 * 5


def test_out_of_band_modes_need_residual_terms():
    true = ModalModel.from_modal_parameters([40, 150, 250, 900], [0.02, 0.01, 0.012, 0.02], [5e6, 2e7, 5e7, 3e7])
    frf = true.synthesize(np.linspace(100, 400, 601))
    with_res = fit_modes(frf, n_modes=2, max_order=24)
    without = fit_modes(frf, n_modes=2, max_order=24, residuals=False)
    np.testing.assert_allclose(with_res.freq_hz, [150, 250], rtol=FREQ_TOL_NOISE_FREE)
    np.testing.assert_allclose(with_res.zeta, [0.01, 0.012], rtol=ZETA_TOL_NOISE_FREE)
    assert with_res.quality.nmse_total < 1e-3
    assert without.quality.nmse_total > 10 * with_res.quality.nmse_total
    assert with_res.model.upper[0, 0] > 0  # stiffness line of the 900 Hz mode
    assert with_res.model.lower[0, 0] > 0  # mass line of the 40 Hz mode: H ≈ −L/ω²


def test_seeded_noise_within_named_tolerances():
    rng = np.random.default_rng(20261121)
    true = ModalModel.from_modal_parameters([150, 250, 410], [0.01, 0.012, 0.03], [2e7, 5e7, 8e7])
    frf = true.synthesize(np.linspace(50, 600, 1101))
    scale = 0.01 * np.abs(frf.values).max()
    noisy = frf.replace(values=frf.values + scale * (rng.standard_normal(frf.shape) + 1j * rng.standard_normal(frf.shape)) / np.sqrt(2))
    fit = fit_modes(noisy, n_modes=3, max_order=30)
    np.testing.assert_allclose(fit.freq_hz, true.freq_hz, rtol=FREQ_TOL_NOISY)
    np.testing.assert_allclose(fit.zeta, true.zeta, rtol=ZETA_TOL_NOISY)
    np.testing.assert_allclose(np.abs(fit.residues), np.abs(true.residues), rtol=0.1)
    assert fit.quality.frac_min > 0.99


def test_state_space_realisation_reproduces_the_modal_part():
    true = three_dof_system()
    a, b, c = true.state_space()
    f = np.array([30.0, 87.0, 190.0])
    w = 2 * np.pi * f
    h = c[None] @ np.linalg.solve(1j * w[:, None, None] * np.eye(a.shape[0]) - a[None], np.broadcast_to(b, (3,) + b.shape))
    np.testing.assert_allclose(h, true.synthesize(f, residuals=False).values, rtol=1e-10)
    assert np.all(np.linalg.eigvals(a).real < 0)


def test_single_dof_residue_is_the_sdof_receptance():
    k, zeta, fn = 3e6, 0.05, 700.0
    f = np.linspace(100, 1500, 50)
    wn, w = 2 * np.pi * fn, 2 * np.pi * f
    direct = 1.0 / (k * (1 - (w / wn) ** 2 + 2j * zeta * w / wn))
    model = ModalModel(fn, zeta, single_dof_residue(fn, zeta, k), ("1x",), ("1x",))
    np.testing.assert_allclose(model.synthesize(f).values[:, 0, 0], direct, rtol=1e-12)


def read_real_file() -> FRF:
    from jointdb.io import read_frf_uff58

    return read_frf_uff58(REAL_FILE)


@pytest.mark.skipif(not REAL_FILE.exists(), reason="shared real data file not present")
def test_real_measured_accelerance_three_references():
    frf = read_real_file()
    assert frf.shape[1:] == (1, 3) and frf.quantity.value == "accelerance"
    fit = fit_modes(frf, n_modes=6, band=(5, 1000), max_order=40)
    # the six clear peaks of the driving-point magnitude (52, 142, 279, 460, 687, 959 Hz)
    mag = np.abs(frf.values[:, 0, :]).sum(axis=1)
    peaks = [frf.freq[np.argmax(np.where(np.abs(frf.freq - p) < 10, mag, 0))] for p in (52, 142, 279, 460, 687, 959)]
    np.testing.assert_allclose(fit.freq_hz, peaks, atol=2.0)
    assert np.all((fit.zeta > 0) & (fit.zeta < 0.05))
    # quality of the fit on the real data (reported): NMSE ≈ 0.4–0.6 %, FRAC ≈ 0.995 per entry
    assert fit.quality.nmse_total < 0.02
    assert fit.quality.frac_min > 0.98


def test_errors_are_actionable():
    frf = ModalModel.from_modal_parameters([150], [0.01], [2e7]).synthesize(np.linspace(50, 300, 501))
    with pytest.raises(NumericalError, match="stable pole"):
        fit_modes(frf, n_modes=4, max_order=6)
    with pytest.raises(InputError, match="band"):
        fit_modes(frf, n_modes=1, band=(300, 100))
    with pytest.raises(InputError, match="too few"):
        fit_modes(frf.band(100, 110), n_modes=1, max_order=40)


def test_fit_tool_tip_combines_x_and_y_driving_points():
    from jointdb.modal import fit_tool_tip

    x = ModalModel.from_modal_parameters([450, 1400], [0.03, 0.02], [8e6, 3e7], "1x")
    y = ModalModel.from_modal_parameters([520], [0.025], [1e7], "1y")
    f = np.linspace(200, 2000, 1801)
    model, fits = fit_tool_tip(x.synthesize(f), y.synthesize(f), n_modes=None)
    assert [str(d) for d in model.outputs] == ["1x", "1y"] and len(fits) == 2
    np.testing.assert_allclose(model.freq_hz, [450, 1400, 520], rtol=FREQ_TOL_NOISE_FREE)
    np.testing.assert_allclose(model.synthesize(f).values[:, 1, 1], y.synthesize(f).values[:, 0, 0], rtol=1e-5)
    assert np.all(model.synthesize(f).values[:, 0, 1] == 0)
    with pytest.raises(InputError, match="driving-point"):
        fit_tool_tip(x.synthesize(f).replace(outputs=("2z",), inputs=("2z",)))
