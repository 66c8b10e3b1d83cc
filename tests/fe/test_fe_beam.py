"""Beam elements against closed-form and independently solved beam theory."""

import numpy as np
import pytest

from jointdb.fe import BeamModel, Clamp, Material, PointMass, Segment, shear_coefficient

STEEL = Material("test-steel", 210e9, 0.3, 7800.0)

# Euler–Bernoulli eigenvalues βL (Blevins, Formulas for natural frequency and mode shape, table 8-1)
BL_CANTILEVER = np.array([1.87510406871, 4.69409113297, 7.85475743823, 10.9955407349])
BL_FREE_FREE = np.array([4.73004074486, 7.85320462410, 10.9956078380, 14.1371654913])


def eb_frequencies(beta_l, length, diameter, mat=STEEL):
    area = np.pi * diameter**2 / 4
    inertia = np.pi * diameter**4 / 64
    return beta_l**2 / length**2 * np.sqrt(mat.E * inertia / (mat.rho * area)) / (2 * np.pi)


def frequency_rtol(model, freq_hz):
    """Round-off bound on the relative error of natural frequencies ``freq_hz`` [Hz] of ``model``.

    ``scipy.linalg.eigh(K, M)`` reduces ``K φ = λ M φ`` to a standard symmetric
    problem ``A = L⁻¹ K L⁻ᵀ`` (``M = L Lᵀ``) and solves it backward stably: each
    computed eigenvalue is exact for a perturbation of norm ~ n·eps·‖A‖ with
    ‖A‖ = λ_max (Weyl). The relative error of λ_i is therefore n·eps·λ_max/λ_i;
    f ∝ √λ halves it. λ_max/λ_1 of a fine beam mesh is 1e5–1e8, so this is far
    above the last digits seen, yet far below any modelling difference (≥ 1e-4).
    """
    import scipy.linalg

    mats = model.assemble()
    free = ~mats.fixed
    lam = scipy.linalg.eigh(mats.K[np.ix_(free, free)], mats.M[np.ix_(free, free)], eigvals_only=True)
    return 0.5 * lam.size * np.finfo(float).eps * lam[-1] / (2 * np.pi * np.asarray(freq_hz)) ** 2


def uniform(length, diameter, *, n_el, theory="euler-bernoulli", kind="planar", ingredients=(), inner=0.0):
    return BeamModel(
        segments=(Segment(length, diameter, inner, STEEL),),
        ingredients=tuple(ingredients),
        theory=theory,
        kind=kind,
        max_element_length=length / n_el,
    )


def test_slender_cantilever_converges_to_euler_bernoulli():
    L, D = 0.5, 0.01  # L/D = 50
    exact = eb_frequencies(BL_CANTILEVER, L, D)
    errors = []
    for n_el in (4, 10, 40):
        f = uniform(L, D, n_el=n_el, ingredients=[Clamp(0.0)]).modes(4).freq_hz
        errors.append(np.abs(f / exact - 1))
    assert np.all(errors[-1] <= 1e-3), errors[-1]
    assert np.all(errors[2] < errors[1]) and np.all(errors[1] < errors[0])  # converges with the mesh
    assert np.all(errors[-1][:3] < 1e-5)


def test_free_free_beam_converges_to_euler_bernoulli_with_two_rigid_body_modes():
    L, D = 0.4, 0.008
    modes = uniform(L, D, n_el=40).modes(6)
    assert modes.n_rigid == 2
    np.testing.assert_array_equal(modes.freq_hz[:2], 0.0)
    exact = eb_frequencies(BL_FREE_FREE, L, D)
    assert np.all(np.abs(modes.freq_hz[2:6] / exact - 1) <= 1e-3)


def test_slender_timoshenko_approaches_euler_bernoulli():
    L, D = 1.0, 0.01  # L/D = 100: shear and rotary inertia negligible for mode 1
    f_t = uniform(L, D, n_el=50, theory="timoshenko", ingredients=[Clamp(0.0)]).modes(1).freq_hz[0]
    f_e = eb_frequencies(BL_CANTILEVER[:1], L, D)[0]
    assert abs(f_t / f_e - 1) < 1e-3
    assert f_t < f_e  # shear and rotary inertia only soften


def timoshenko_simply_supported(length, outer, inner, mat, n_max=6):
    """Lowest Timoshenko natural frequencies [Hz] of a simply supported beam, ascending.

    For each k = nπ/L, w = sin kz, ψ = cos kz is exact and
    det[[κGAk² − ρAω², −κGAk], [−κGAk, EIk² + κGA − ρIω²]] = 0 is a quadratic
    in ω² (Timoshenko 1921): both roots are modes (the upper one belongs to the
    "second spectrum"), and n = 0 adds the pure-rotation mode ω² = κGA/(ρI).
    Written here independently of the FE code.
    """
    area = np.pi * (outer**2 - inner**2) / 4
    inertia = np.pi * (outer**4 - inner**4) / 64
    G = mat.E / (2 * (1 + mat.nu))
    m2 = (inner / outer) ** 2
    kappa = 6 * (1 + mat.nu) * (1 + m2) ** 2 / ((7 + 6 * mat.nu) * (1 + m2) ** 2 + (20 + 12 * mat.nu) * m2)
    s = kappa * G * area
    roots = [s / (mat.rho * inertia)]
    for n in range(1, n_max + 1):
        k = n * np.pi / length
        a = mat.rho * area * mat.rho * inertia
        b = mat.rho * area * (mat.E * inertia * k**2 + s) + mat.rho * inertia * s * k**2
        c = s * mat.E * inertia * k**4
        disc = np.sqrt(b * b - 4 * a * c)
        roots += [(b - disc) / (2 * a), (b + disc) / (2 * a)]
    return np.sqrt(np.sort(roots)) / (2 * np.pi)


def eb_simply_supported(length, outer, inner, mat, n):
    area = np.pi * (outer**2 - inner**2) / 4
    inertia = np.pi * (outer**4 - inner**4) / 64
    return (np.arange(1, n + 1) * np.pi / length) ** 2 * np.sqrt(mat.E * inertia / (mat.rho * area)) / (2 * np.pi)


@pytest.mark.parametrize("slenderness, inner_ratio", [(2.0, 0.0), (3.0, 0.0), (5.0, 0.0), (4.0, 0.6)])
def test_stubby_simply_supported_timoshenko_matches_the_frequency_equation(slenderness, inner_ratio):
    D = 0.02
    L = slenderness * D
    pins = [Clamp(0.0, ("x",)), Clamp(L, ("x",))]
    ft = uniform(L, D, n_el=80, theory="timoshenko", ingredients=pins, inner=inner_ratio * D).modes(3).freq_hz
    fe = uniform(L, D, n_el=80, theory="euler-bernoulli", ingredients=pins, inner=inner_ratio * D).modes(3).freq_hz
    exact = timoshenko_simply_supported(L, D, inner_ratio * D, STEEL)[:3]
    assert np.all(np.abs(ft / exact - 1) <= 1e-3), ft / exact - 1
    # Euler–Bernoulli misses shear and rotary inertia: visibly stiffer for stubby beams
    assert fe[0] / ft[0] - 1 > 0.04
    np.testing.assert_allclose(fe, eb_simply_supported(L, D, inner_ratio * D, STEEL, 3), rtol=1e-3)


def test_timoshenko_cantilever_static_tip_deflection_includes_shear_exactly():
    # bending + shear flexibility P L^3/(3EI) + P L/(κGA): exact for the interdependent element
    L, D = 0.06, 0.02
    model = uniform(L, D, n_el=3, theory="timoshenko", ingredients=[Clamp(0.0)])
    from jointdb.fe import NamedPoint

    model = model.replace(points=(NamedPoint("tip", L, 1),))
    h = model.frf([0.0], points=["tip"], directions=["x"]).values[0, 0, 0]
    area, inertia = np.pi * D**2 / 4, np.pi * D**4 / 64
    kappa = 6 * (1 + STEEL.nu) / (7 + 6 * STEEL.nu)
    exact = L**3 / (3 * STEEL.E * inertia) + L / (kappa * STEEL.G * area)
    # one solve K x = F: relative error ≤ n·eps·cond(K) (cond ~1.5e5 here, so ~2e-10)
    mats = model.assemble()
    free = ~mats.fixed
    k_free = mats.K[np.ix_(free, free)]
    assert h.real == pytest.approx(exact, rel=k_free.shape[0] * np.finfo(float).eps * np.linalg.cond(k_free))
    assert h.imag == 0.0


def test_shear_coefficient_cowper_values():
    assert shear_coefficient(0.3, 1.0) == pytest.approx(6 * 1.3 / (7 + 1.8))
    assert float(shear_coefficient(0.3, 1.0, 0.999)) == pytest.approx(2 * 1.3 / (4 + 3 * 0.3), rel=2e-3)  # thin tube


def test_axial_and_torsional_frequencies_of_a_fixed_free_bar():
    L, D = 0.3, 0.02
    model = uniform(L, D, n_el=60, theory="timoshenko", kind="frame3d", ingredients=[Clamp(0.0)])
    modes = model.modes(40)
    dirs = np.array([d.direction for d in modes.dof_labels])
    share_axial = np.sum(modes.shapes[dirs == "z"] ** 2, axis=0) / np.sum(modes.shapes**2, axis=0)
    share_torsion = np.sum(modes.shapes[dirs == "rz"] ** 2, axis=0) / np.sum(modes.shapes**2, axis=0)
    axial = modes.freq_hz[share_axial > 0.99][:2]
    torsion = modes.freq_hz[share_torsion > 0.99][:2]
    n = np.array([1, 3])
    assert axial == pytest.approx(n / (4 * L) * np.sqrt(STEEL.E / STEEL.rho), rel=1e-3)
    assert torsion == pytest.approx(n / (4 * L) * np.sqrt(STEEL.G / STEEL.rho), rel=1e-3)


def test_frame3d_round_section_bends_identically_in_x_and_y_and_like_planar():
    L, D = 0.1, 0.012
    for theory in ("timoshenko", "euler-bernoulli"):
        model3 = uniform(L, D, n_el=20, theory=theory, kind="frame3d", ingredients=[Clamp(0.0)])
        f3 = model3.modes(40)
        dirs = np.array([d.direction for d in f3.dof_labels])
        sx = np.sum(f3.shapes[np.isin(dirs, ["x", "ry"])] ** 2, axis=0)
        sy = np.sum(f3.shapes[np.isin(dirs, ["y", "rx"])] ** 2, axis=0)
        total = np.sum(f3.shapes**2, axis=0)
        fx = f3.freq_hz[(sx + sy) / total > 0.99]
        model2 = uniform(L, D, n_el=20, theory=theory, ingredients=[Clamp(0.0)])
        planar = model2.modes(4).freq_hz
        # bending modes come in x/y pairs of equal frequency, equal to the planar model's;
        # the two members of a degenerate pair come from one solve but are mixed by round-off
        # of order the solver's bound (λ_max/λ of this 20-element frame is up to ~5e7, so the
        # bound on mode 1 is ~1e-6 while the modes are spaced by factors > 2)
        pairs = fx[: 2 * planar.size].reshape(-1, 2)
        tol3, tol2 = frequency_rtol(model3, planar), frequency_rtol(model2, planar)
        assert np.all(np.abs(pairs[:, 0] / pairs[:, 1] - 1) <= 2 * tol3)
        assert np.all(np.abs(pairs[:, 0] / planar - 1) <= tol3 + tol2)


def test_stepped_shaft_of_equal_segments_equals_the_uniform_shaft():
    L, D = 0.2, 0.015
    one = uniform(L, D, n_el=40, theory="timoshenko", ingredients=[Clamp(0.0)]).modes(5).freq_hz
    three = BeamModel(
        segments=(Segment(0.05, D, 0, STEEL), Segment(0.1, D, 0, STEEL), Segment(0.05, D, 0, STEEL)),
        ingredients=(Clamp(0.0),),
        max_element_length=L / 40,
    ).modes(5).freq_hz
    np.testing.assert_allclose(three, one, rtol=1e-8)


def test_point_mass_lowers_frequencies_as_the_rayleigh_quotient_says():
    L, D = 0.3, 0.01
    base = uniform(L, D, n_el=30, theory="timoshenko", ingredients=[Clamp(0.0)])
    modes = base.modes(3)
    tol_base = frequency_rtol(base, modes.freq_hz)
    tip_x = base.mesh().dof(base.mesh().node_at(L), "x")
    beam_mass = STEEL.rho * np.pi * D**2 / 4 * L
    for fraction in (0.001, 0.01, 0.05):
        m = fraction * beam_mass
        model = base.with_ingredient(PointMass(L, m))
        loaded = model.modes(3).freq_hz
        # round-off of both eigen-solves (≤ ~1.5e-7 here; the second-order gaps checked are ≥ 2.4e-7)
        tol = tol_base + frequency_rtol(model, loaded)
        phi = modes.shapes[tip_x]  # mass-normalised: φᵀMφ = 1
        rayleigh = modes.freq_hz / np.sqrt(1.0 + m * phi**2)  # Rayleigh quotient with the unloaded shape
        assert np.all(loaded < modes.freq_hz)
        # for the fundamental mode the quotient is an upper bound ...
        assert loaded[0] <= rayleigh[0] * (1 + tol[0])
        # ... and for every mode it is stationary: the error is second order in the added mass
        assert np.all(np.abs(loaded / rayleigh - 1) < 2 * (m * phi**2) ** 2 + tol)
        error, shift = np.abs(loaded / rayleigh - 1), np.abs(rayleigh / modes.freq_hz - 1)
        assert error[0] < 0.01 * shift[0]
        if fraction <= 0.01:
            assert np.all(error < 0.1 * shift)


def transfer_matrix_cantilever_frequencies(segments, mat, n_roots=3, f_max=5e4):
    """Natural frequencies [Hz] of a stepped Timoshenko cantilever by exact transfer matrices.

    Independent of the FE code: for each uniform segment the state
    y = (w, ψ, M, V) obeys y' = A(ω) y with w' = ψ + V/(κGA), ψ' = M/(EI),
    M' = −V − ρIω²ψ, V' = −ρAω²w, so y(L) = expm(A L) y(0). Clamped at z = 0
    (w = ψ = 0) and free at the end (M = V = 0): det T[2:, 2:](ω) = 0.
    """
    from scipy.linalg import expm
    from scipy.optimize import brentq

    G = mat.E / (2 * (1 + mat.nu))

    def det(f):
        w2 = (2 * np.pi * f) ** 2
        T = np.eye(4)
        for length, outer in segments:
            area, inertia = np.pi * outer**2 / 4, np.pi * outer**4 / 64
            kappa = 6 * (1 + mat.nu) / (7 + 6 * mat.nu)
            A = np.array([
                [0, 1, 0, 1 / (kappa * G * area)],
                [0, 0, 1 / (mat.E * inertia), 0],
                [0, -mat.rho * inertia * w2, 0, -1],
                [-mat.rho * area * w2, 0, 0, 0],
            ])
            T = expm(A * length) @ T
        return np.linalg.det(T[2:, 2:])

    grid = np.linspace(1.0, f_max, 1200)
    values = np.array([det(f) for f in grid])
    roots = []
    for a, b, va, vb in zip(grid[:-1], grid[1:], values[:-1], values[1:]):
        if np.sign(va) != np.sign(vb):
            roots.append(brentq(det, a, b, xtol=1e-10, rtol=1e-13))
        if len(roots) == n_roots:
            break
    return np.array(roots)


def test_stubby_stepped_timoshenko_cantilever_matches_exact_transfer_matrices():
    # a tool-like stepped cantilever: 20 mm of Ø20 clamped at z = 0, then 40 mm of Ø12 (L/D ≈ 3–5)
    segments = [(0.02, 0.02), (0.04, 0.012)]
    exact = transfer_matrix_cantilever_frequencies(segments, STEEL)
    model = BeamModel(
        segments=tuple(Segment(length, d, 0.0, STEEL) for length, d in segments),
        ingredients=(Clamp(0.0),),
        max_element_length=0.001,
    )
    ft = model.modes(3).freq_hz
    fe = model.replace(theory="euler-bernoulli").modes(3).freq_hz
    assert exact.size == 3
    np.testing.assert_allclose(ft, exact, rtol=1e-3)
    assert np.all(fe / ft - 1 > 0.03)  # Euler–Bernoulli visibly too stiff for a stubby tool
