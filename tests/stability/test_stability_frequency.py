"""Turning (Tlusty) and milling zero-order (Altintas–Budak) lobes against known answers (docs/theory.md §5)."""

import numpy as np
import pytest

from jointdb.errors import InputError
from jointdb.frf import FRF
from jointdb.modal import ModalModel
from jointdb.stability import (
    MillingCut,
    mean_directional_matrix,
    milling_lobes_zoa,
    tlusty_limit,
    turning_lobes,
)

IS_M, IS_FN, IS_ZETA = 0.03993, 922.0, 0.011
IS_K = IS_M * (2 * np.pi * IS_FN) ** 2


def sdof(fn, zeta, k, dof="1x"):
    return ModalModel.from_modal_parameters([fn], [zeta], [k], dof)


def test_turning_single_mode_minimum_is_2k_zeta_1_plus_zeta_over_kf():
    k, zeta, fn, kf = 2.26e8, 0.012, 250.0, 1e9
    frf = sdof(fn, zeta, k).synthesize(np.arange(200, 300, 0.01))
    depth, fc = tlusty_limit(frf, kf)
    assert depth == pytest.approx(2 * k * zeta * (1 + zeta) / kf, rel=1e-6)
    assert fc == pytest.approx(fn * np.sqrt(1 + 2 * zeta), rel=1e-5)


def test_turning_two_modes_theory_case_gives_7_185_mm_at_252_98_hz():
    model = ModalModel.block_diagonal([sdof(250, 0.012, 2.26e8, "1x"), sdof(150, 0.010, 2.13e8, "1y")])
    frf = model.synthesize(np.arange(100, 400, 0.005))
    mu = [np.cos(np.radians(30)) ** 2, np.cos(np.radians(-45)) ** 2]
    depth, fc = tlusty_limit(frf, 1e9, mu)
    assert depth * 1e3 == pytest.approx(7.185, abs=5e-4)
    assert fc == pytest.approx(252.98, abs=5e-3)
    lobes = turning_lobes(frf, 1e9, mu, spindle_speed_rpm=np.linspace(500, 20000, 2000))
    # the envelope never dips below the absolute limit and touches it at lobe minima
    assert np.nanmin(lobes.depth_m) >= depth * (1 - 1e-6)
    assert np.nanmin(lobes.depth_m) == pytest.approx(depth, rel=2e-3)
    assert set(lobes.kind[np.isfinite(lobes.depth_m)]) == {"hopf"}


def test_turning_lobes_satisfy_the_characteristic_equation():
    k, zeta, fn, kf = 2e7, 0.03, 600.0, 2e9
    frf = sdof(fn, zeta, k).synthesize(np.arange(400, 900, 0.05))
    res = turning_lobes(frf, kf, spindle_speed_rpm=np.linspace(3000, 30000, 50))
    h = frf.values[:, 0, 0]
    for row in res.table():
        t = 60.0 / row["spindle_speed_rpm"]
        w = 2 * np.pi * row["chatter_freq_hz"]
        g = np.interp(row["chatter_freq_hz"], frf.freq, h.real) + 1j * np.interp(row["chatter_freq_hz"], frf.freq, h.imag)
        resid = 1 + kf * row["depth_m"] * (1 - np.exp(-1j * w * t)) * g
        assert abs(resid) < 2e-3
        assert row["lobe"] == int(np.floor(row["chatter_freq_hz"] * t))


def altintas_alpha0(kr_ratio, st, ex):
    """Altintas & Budak (1995) directional coefficients, written out from the paper."""

    def prim(p):
        return 0.5 * np.array(
            [
                [np.cos(2 * p) - 2 * kr_ratio * p + kr_ratio * np.sin(2 * p), -np.sin(2 * p) - 2 * p + kr_ratio * np.cos(2 * p)],
                [-np.sin(2 * p) + 2 * p + kr_ratio * np.cos(2 * p), -np.cos(2 * p) - 2 * kr_ratio * p - kr_ratio * np.sin(2 * p)],
            ]
        )

    return prim(ex) - prim(st)


@pytest.mark.parametrize("immersion,down", [(1.0, True), (0.5, True), (0.3, False), (0.1, True)])
def test_mean_directional_matrix_equals_altintas_alpha0(immersion, down):
    cut = MillingCut(3, 6e8, 2e8, immersion, down)
    st, ex = cut.angles
    expected = -(cut.n_teeth * cut.kt / (4 * np.pi)) * altintas_alpha0(cut.kr / cut.kt, st, ex)
    np.testing.assert_allclose(mean_directional_matrix(cut), expected, rtol=1e-12, atol=1e-3)


def test_zoa_insperger_stepan_slotting_floor_is_0_298_mm():
    cut = MillingCut(2, 6e8, 2e8, 1.0, True)
    frf = sdof(IS_FN, IS_ZETA, IS_K).synthesize(np.arange(800, 1100, 0.02))
    res = milling_lobes_zoa(frf, cut, spindle_speed_rpm=np.linspace(5000, 25000, 600))
    floor = 2 * IS_K * IS_ZETA * (1 + IS_ZETA) / 1e8
    assert floor * 1e3 == pytest.approx(0.298, abs=5e-4)
    assert res.min_depth_m == pytest.approx(floor, rel=2e-3)
    assert np.nanmin(res.depth_m) >= floor * (1 - 1e-6)
    # the mean directional factor of slotting is N K_n / 4
    assert mean_directional_matrix(cut)[0, 0] == pytest.approx(2 * 2e8 / 4)


def altintas_example_frf(f):
    fx, zx = [452.77, 1448.53], [0.1237, 0.0165]
    rx = [9.203e-5 - 1.862e-4j, -4.182e-5 - 3.044e-4j]
    fy, zy = [516.17, 1407.64], [0.0243, 0.0324]
    ry = [-2.393e-6 - 1.722e-4j, 4.055e-5 - 3.619e-4j]
    mx = ModalModel(fx, zx, np.array(rx).reshape(2, 1, 1), ("1x",), ("1x",))
    my = ModalModel(fy, zy, np.array(ry).reshape(2, 1, 1), ("1y",), ("1y",))
    return ModalModel.block_diagonal([mx, my]).synthesize(f)


def test_altintas_half_immersion_example_runs_and_matches_the_book_formula(tmp_path):
    # Units: the residues are read as (m/N)·(rad/s) (the source labels them m/N): this gives a
    # static compliance of ~2e-7 m/N (k ≈ 5 MN/m, an end mill) and lobes inside the source's
    # 0–6 mm window; reading them per Hz would put the whole diagram below 1 mm.
    # K_r = 788.8 MPa is a pressure, i.e. the force ratio K_r/K_t = 0.598.
    f = np.arange(1, 3000, 0.5)
    frf = altintas_example_frf(f)
    assert abs(frf.values[0, 0, 0]) == pytest.approx(2.05e-7, rel=0.01)
    cut = MillingCut(2, 1319.4e6, 788.8e6, 0.5, True)
    speeds = np.linspace(1000, 16000, 400)
    res = milling_lobes_zoa(frf, cut, spindle_speed_rpm=speeds)
    assert np.all(np.isfinite(res.depth_m))
    assert 0 < res.min_depth_m < 6e-3 and np.nanmax(res.depth_m) < 8e-3
    # independent: Altintas's eigenvalue form  Λ = −1/eig([α0][Φ]),  a = −2πΛ_R(1+κ²)/(N K_t)
    st, ex = cut.angles
    a0 = altintas_alpha0(cut.kr / cut.kt, st, ex)
    eig = np.linalg.eigvals(a0[None] @ frf.values)
    lam = -1 / eig
    with np.errstate(divide="ignore", invalid="ignore"):
        kappa = lam.imag / lam.real
        alim = -2 * np.pi * lam.real * (1 + kappa**2) / (cut.n_teeth * cut.kt)
    book_floor = np.min(alim[alim > 0])
    assert res.min_depth_m == pytest.approx(book_floor, rel=5e-3)
    from jointdb.plots import plot_lobes

    out = plot_lobes(res, tmp_path / "altintas.png", title="Altintas half immersion (ZOA)", depth_unit="mm")
    assert out.exists() and out.stat().st_size > 5000


def test_zoa_up_and_down_milling_differ_at_partial_immersion():
    frf = altintas_example_frf(np.arange(1, 3000, 0.5))
    speeds = np.linspace(2000, 16000, 100)
    down = milling_lobes_zoa(frf, MillingCut(2, 1319.4e6, 788.8e6, 0.5, True), spindle_speed_rpm=speeds)
    up = milling_lobes_zoa(frf, MillingCut(2, 1319.4e6, 788.8e6, 0.5, False), spindle_speed_rpm=speeds)
    assert not np.allclose(down.depth_m, up.depth_m, rtol=0.05)


def test_zoa_x_only_frf_equals_a_rigid_y_direction():
    frf = sdof(IS_FN, IS_ZETA, IS_K).synthesize(np.arange(800, 1100, 0.05))
    both = ModalModel.block_diagonal([sdof(IS_FN, IS_ZETA, IS_K, "1x"), sdof(IS_FN, IS_ZETA, 1e15, "1y")])
    cut = MillingCut(2, 6e8, 2e8, 0.5, True)
    speeds = np.linspace(6000, 20000, 50)
    a = milling_lobes_zoa(frf, cut, spindle_speed_rpm=speeds)
    b = milling_lobes_zoa(both.synthesize(frf.freq), cut, spindle_speed_rpm=speeds)
    np.testing.assert_allclose(a.depth_m, b.depth_m, rtol=1e-5)


def test_bad_inputs_raise_input_error():
    with pytest.raises(InputError, match="radial_immersion"):
        MillingCut(2, 6e8, 2e8, 1.5)
    with pytest.raises(InputError, match="n_teeth"):
        MillingCut(0, 6e8, 2e8)
    frf = FRF(np.arange(1, 10.0), np.ones(9) * (1 + 0j), ("1z",), ("1z",))
    with pytest.raises(InputError, match="no x or y"):
        milling_lobes_zoa(frf, MillingCut(2, 6e8, 2e8))
    with pytest.raises(InputError, match="orientation"):
        tlusty_limit(sdof(100, 0.01, 1e6).synthesize(np.arange(50, 150.0)), 1e9, [1, 2])


def test_bad_speeds_lobe_counts_and_cut_values_raise_input_error():
    frf = sdof(IS_FN, IS_ZETA, IS_K).synthesize(np.arange(800, 1100, 0.5))
    cut = MillingCut(2, 6e8, 2e8, 0.5, True)
    for speeds in ([-100.0, 1000.0], [np.nan, 1000.0], []):
        with pytest.raises(InputError, match="spindle speeds"):
            turning_lobes(frf, 1e9, spindle_speed_rpm=speeds)
        with pytest.raises(InputError, match="spindle speeds"):
            milling_lobes_zoa(frf, cut, spindle_speed_rpm=speeds)
    with pytest.raises(InputError, match="max_lobes"):
        turning_lobes(frf, 1e9, max_lobes=0)
    with pytest.raises(InputError, match="kt must be a number"):
        MillingCut(2, "6e8", 2e8)
    with pytest.raises(InputError, match="n_teeth must be finite"):
        MillingCut(float("nan"), 6e8, 2e8)


def test_oriented_frf_refuses_to_mix_rotations_into_translations():
    from jointdb.errors import InputError
    from jointdb.frf import FRF
    from jointdb.stability import oriented_frf

    freq = np.linspace(10.0, 1000.0, 50)
    h = np.zeros((50, 2, 2), complex)
    h[:, 0, 0] = 1e-6 / (1 - (freq / 500) ** 2 + 0.02j * freq / 500)
    h[:, 1, 1] = 1e-3 * h[:, 0, 0]
    frf = FRF(freq, h, ["1x", "1ry"], ["1x", "1ry"])
    with pytest.raises(InputError, match="rotational terms"):
        oriented_frf(frf)
    # weighting only the translational driving point is fine and equals H_xx
    assert np.allclose(oriented_frf(frf, np.array([[1.0, 0.0], [0.0, 0.0]])), h[:, 0, 0])
