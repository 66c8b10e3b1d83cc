"""FRF synthesis: direct vs modal, reciprocity, passivity, damping models, rigid-body modes."""

import os

import numpy as np
import scipy.linalg
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from jointdb.errors import InputError
from jointdb.fe import (
    BeamModel,
    Clamp,
    HystereticDamping,
    Material,
    ModalDamping,
    NamedPoint,
    PointMass,
    RayleighDamping,
    Segment,
    Support,
    frf_direct,
    frf_modal,
)

STEEL = Material("test-steel", 210e9, 0.3, 7800.0)


def shaft(ingredients=(), kind="planar", theory="timoshenko", n_el=24):
    """A 3-step shaft, 150 mm, with three named points."""
    segs = (Segment(0.05, 0.02, 0.0, STEEL), Segment(0.06, 0.016, 0.006, STEEL), Segment(0.04, 0.012, 0.0, "carbide"))
    pts = (NamedPoint("tip", 0.15, 1), NamedPoint("mid", 0.08, 2), NamedPoint("root", 0.0, 3))
    return BeamModel(segs, pts, tuple(ingredients), theory=theory, kind=kind, max_element_length=0.15 / n_el)


def rel(a, b):
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


@pytest.mark.parametrize(
    "ingredients",
    [
        (Clamp(0.0), ModalDamping(0.02)),
        (Clamp(0.0), RayleighDamping(50.0, 2e-7)),
        (Clamp(0.0), HystereticDamping(0.01)),
        (ModalDamping((0.01, 0.02, 0.03)),),  # free-free: rigid-body modes
        (Support(0.0, {"x": 1e7, "ry": 1e4}, {"x": 200.0}), PointMass(0.15, 0.01, 1e-6), ModalDamping(0.01)),
    ],
    ids=["clamped-modal", "clamped-rayleigh", "clamped-hysteretic", "free-free", "support-with-damper"],
)
def test_direct_and_modal_superposition_agree(ingredients):
    model = shaft(ingredients)
    freq = np.linspace(10.0, 12000.0, 300)
    direct = model.frf(freq, algorithm="lu")  # batched LU: independent of the eigen-solution
    n_dof = model.assemble().K.shape[0]
    # all modes: modal superposition is exact (up to round-off)
    full = model.frf(freq, method="modal", n_modes=n_dof)
    assert rel(full.values, direct.values) < 1e-8
    assert full.outputs == direct.outputs
    # the default direct algorithm (spectral for classical damping) is exact too
    assert rel(model.frf(freq).values, direct.values) < 1e-8
    # truncated: the static residual makes up for most of the missing modes
    trunc = model.frf(freq, method="modal")
    mats = model.assemble()
    idx = [model.mesh().dof(model.mesh().node_at(0.15), "x")]
    kept = int(np.sum(model.modes().freq_hz < 2 * freq[-1]))
    plain = frf_modal(mats, freq, idx, n_modes=kept, residual=False)
    tip = direct.block(["1x"], ["1x"])
    err_res = rel(trunc.block(["1x"], ["1x"]), tip)
    err_plain = rel(plain, tip)
    assert err_res < 1e-2
    if not any(isinstance(i, Support) and i.damping for i in ingredients):  # proportional damping
        assert err_res < 0.2 * err_plain


def test_direct_solution_is_the_same_in_any_chunk_size_and_algorithm():
    model = shaft((Clamp(0.0), ModalDamping(0.02)))
    mats = model.assemble()
    freq = np.linspace(1.0, 8000.0, 97)
    idx = [0, 1, 10, 11]
    whole = frf_direct(mats, freq, idx, algorithm="lu")
    tiny = frf_direct(mats, freq, idx, chunk_bytes=1, algorithm="lu")  # one line per chunk
    np.testing.assert_allclose(tiny, whole, rtol=1e-12, atol=0)
    spectral = frf_direct(mats, freq, idx, algorithm="spectral")
    # the spectral sum inherits the eigen-solver's backward error n·eps·λmax (relative to the
    # largest, lowest-mode term: n·eps·λmax/λmin ~ 6e-9 here; seen 1.2e-10); dropping even the
    # highest mode would change the static part by λmin/λmax ~ 2e-6, far above this
    free = ~mats.fixed
    lam = scipy.linalg.eigh(mats.K[np.ix_(free, free)], mats.M[np.ix_(free, free)], eigvals_only=True)
    tol = lam.size * np.finfo(float).eps * lam[-1] / lam[0]
    np.testing.assert_allclose(spectral, whole, rtol=tol, atol=tol * np.abs(whole).max())
    damped_support = shaft((Clamp(0.0), Support(0.1, {"x": 1e6}, {"x": 100.0}))).assemble()
    with pytest.raises(InputError, match="classical damping"):
        frf_direct(damped_support, freq, idx, algorithm="spectral")
    np.testing.assert_allclose(frf_direct(damped_support, freq, idx), frf_direct(damped_support, freq, idx, algorithm="lu"))


def test_clamped_dofs_have_zero_receptance_and_zero_hz_is_static():
    model = shaft((Clamp(0.0), ModalDamping(0.02)))
    frf = model.frf([0.0, 100.0], points=["root", "tip"])
    assert np.all(frf.block(["3x", "3ry"], ["3x", "3ry", "1x", "1ry"]) == 0)
    assert np.all(frf.values[0].imag == 0)  # viscous damping does nothing at 0 Hz
    mats = model.assemble()
    free = ~mats.fixed
    static = np.linalg.inv(mats.K[np.ix_(free, free)])
    tip = model.mesh().dof(model.mesh().node_at(0.15), "x")
    pos = int(np.sum(free[:tip]))
    k_free = mats.K[np.ix_(free, free)]
    # two solves with K (LU in the FRF, inv here): each relative error <= n·eps·cond(K)
    tol = 2 * k_free.shape[0] * np.finfo(float).eps * np.linalg.cond(k_free)
    assert frf.entry("1x", "1x")[0].real == pytest.approx(static[pos, pos], rel=tol)


@pytest.mark.parametrize("kind, n_rigid", [("planar", 2), ("frame3d", 6)])
def test_free_free_models_have_rigid_body_modes_and_refuse_zero_hz(kind, n_rigid):
    model = shaft(kind=kind, n_el=8)
    modes = model.modes(n_rigid + 2)
    assert modes.n_rigid == n_rigid
    assert np.all(modes.freq_hz[:n_rigid] == 0) and np.all(modes.freq_hz[n_rigid:] > 1000)
    for method in ("direct", "modal"):
        with pytest.raises(InputError, match="rigid-body modes"):
            model.frf([0.0, 10.0], method=method)
    # well above 0 Hz the free-free tip receptance is mass-like: Re H < 0 at low frequency
    h = model.frf([1.0], points=["tip"], directions=["x"]).values[0, 0, 0]
    assert h.real < 0


def test_rigid_body_mass_line_of_a_free_free_beam():
    # at low frequency a free rigid body: H = -(1/m + e²/J)/ω² at a point e from the centre of mass
    L, D = 0.1, 0.02
    model = BeamModel((Segment(L, D, 0.0, STEEL),), (NamedPoint("end", L, 1),), theory="euler-bernoulli",
                      max_element_length=L / 10)
    m = STEEL.rho * np.pi * D**2 / 4 * L
    J = m * L**2 / 12  # Euler–Bernoulli: no rotary inertia of the sections
    w = 2 * np.pi * 5.0
    h = model.frf([5.0], points=["end"], directions=["x"]).values[0, 0, 0]
    expected = -(1 / m + (L / 2) ** 2 / J) / w**2
    assert h.real == pytest.approx(expected, rel=1e-5)  # elastic modes add ~ (ω/ω1)² ≈ 1e-7


def half_power_loss_factor(model, f_r, width=0.03):
    """Loss factor of the mode near f_r from the half-power points of the tip receptance.

    For one hysteretic mode |H|² ∝ 1/((ω_r² − ω²)² + η²ω_r⁴): half power at
    ω² = ω_r²(1 ∓ η), so η = (ω₂² − ω₁²)/(ω₂² + ω₁²).
    """
    f = np.linspace((1 - width) * f_r, (1 + width) * f_r, 1501)
    h2 = np.abs(model.frf(f, points=["tip"], directions=["x"]).values[:, 0, 0]) ** 2
    k = int(np.argmax(h2))
    half = h2[k] / 2
    lo = np.interp(half, h2[: k + 1], f[: k + 1])
    hi = np.interp(half, h2[k:][::-1], f[k:][::-1])
    return (hi**2 - lo**2) / (hi**2 + lo**2)


def test_hysteretic_damping_gives_frequency_independent_loss():
    eta = 0.02
    L, D = 0.4, 0.01
    base = BeamModel((Segment(L, D, 0.0, STEEL),), (NamedPoint("tip", L, 1),), (Clamp(0.0),), max_element_length=L / 30)
    hyst = base.with_ingredient(HystereticDamping(eta))
    f_modes = base.modes(3).freq_hz
    losses = np.array([half_power_loss_factor(hyst, fr) for fr in f_modes])
    np.testing.assert_allclose(losses, eta, rtol=0.02)  # every mode: loss factor η
    # viscous stiffness-proportional damping tuned to η at mode 1 loses more at higher modes (2ζ = βω)
    eta_v = 0.004
    visc = base.with_ingredient(RayleighDamping(0.0, eta_v / (2 * np.pi * f_modes[0])))
    losses_v = np.array([half_power_loss_factor(visc, fr, width=0.15) for fr in f_modes])
    np.testing.assert_allclose(losses_v, eta_v * f_modes / f_modes[0], rtol=0.03)
    # quasi-statically the hysteretic receptance lags the force by the constant angle atan(η)
    f_low = np.geomspace(1e-3, 1e-2, 5) * f_modes[0]
    phase = np.angle(hyst.frf(f_low, points=["tip"], directions=["x"]).values[:, 0, 0])
    np.testing.assert_allclose(phase, -np.arctan(eta), rtol=1e-3)
    phase_v = np.angle(visc.frf(f_low, points=["tip"], directions=["x"]).values[:, 0, 0])
    assert abs(phase_v[-1] / phase_v[0] - 10) < 0.1  # viscous: phase grows with ω


def test_modal_damping_gives_the_prescribed_ratio_per_mode():
    # independent of the synthesis code: eigenvalues of the first-order system [[0, I], [-M⁻¹K, -M⁻¹C]]
    # have |λ| = ω_r and -Re λ/|λ| = ζ_r; the last ratio applies to the higher modes
    L, D = 0.4, 0.01
    base = BeamModel((Segment(L, D, 0.0, STEEL),), (NamedPoint("tip", L, 1),), (Clamp(0.0),), max_element_length=L / 30)
    f_modes = base.modes(4).freq_hz
    mats = base.with_ingredient(ModalDamping((0.01, 0.02, 0.005))).assemble()
    free = ~mats.fixed
    K, M, C = (x[np.ix_(free, free)] for x in (mats.K, mats.M, mats.C))
    n = K.shape[0]
    a = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(M, K), -np.linalg.solve(M, C)]])
    lam, left, right = scipy.linalg.eig(a, left=True, right=True)
    keep = lam.imag > 0
    order = np.argsort(np.abs(lam[keep]))[:4]
    # round-off of the non-symmetric eigen-solve: |δλ_i| <= n·eps·‖A_balanced‖·κ_i, κ_i the
    # eigenvalue's condition number from its left and right eigenvectors (seen: 7e-10 on mode 1)
    kappa = (np.linalg.norm(left, axis=0) * np.linalg.norm(right, axis=0)
             / np.abs(np.sum(left.conj() * right, axis=0)))[keep][order]
    lam = lam[keep][order]
    balanced, _ = scipy.linalg.matrix_balance(a)
    rel = a.shape[0] * np.finfo(float).eps * np.linalg.norm(balanced, 2) * kappa / np.abs(lam)
    zeta = np.array([0.01, 0.02, 0.005, 0.005])
    # f_modes (symmetric eigh of the undamped pencil): 0.5·n·eps·λmax/λ_i relative
    lam_max = scipy.linalg.eigh(K, M, eigvals_only=True)[-1]
    rel_undamped = 0.5 * n * np.finfo(float).eps * lam_max / (2 * np.pi * f_modes) ** 2
    # modal damping shifts |λ| from ω_r by nothing (|λ| = ω_r exactly), so only round-off remains
    assert np.all(np.abs(np.abs(lam) / (2 * np.pi) / f_modes - 1) <= rel + rel_undamped)
    # ζ = -Re λ/|λ|: an error δ|λ| in λ is δ/ζ relative to ζ
    assert np.all(np.abs(-lam.real / np.abs(lam) / zeta - 1) <= rel / zeta)


# ---------------------------------------------------------------- properties
_material = st.sampled_from([STEEL, "carbide", "aluminium"])


@st.composite
def random_models(draw):
    n_seg = draw(st.integers(1, 3))
    segs = []
    for _ in range(n_seg):
        do = draw(st.floats(0.006, 0.05))
        segs.append(Segment(draw(st.floats(0.01, 0.12)), do, draw(st.floats(0.0, 0.7)) * do, draw(_material)))
    length = sum(s.length for s in segs)
    positions = st.floats(0.0, 1.0).map(lambda u: float(np.floor(u * length * 1e6) / 1e6))
    ingredients = []
    support = draw(st.sampled_from(["free", "clamp", "springs"]))
    if support == "clamp":
        ingredients.append(Clamp(draw(positions)))
    elif support == "springs":
        ingredients.append(
            Support(draw(positions), {"x": draw(st.floats(1e5, 1e9)), "ry": draw(st.floats(1e2, 1e6))},
                    {"x": draw(st.floats(0.0, 500.0))})
        )
    if draw(st.booleans()):
        ingredients.append(PointMass(draw(positions), draw(st.floats(0.0, 0.05)), draw(st.floats(0.0, 1e-5))))
    # always some damping: an undamped FRF is infinite at its resonances, and the
    # solve is arbitrarily ill-conditioned next to them
    damping = draw(st.sampled_from(["modal", "rayleigh", "hysteretic"]))
    if damping == "modal":
        ingredients.append(ModalDamping(draw(st.floats(0.001, 0.1))))
    elif damping == "rayleigh":
        ingredients.append(RayleighDamping(draw(st.floats(0.0, 100.0)), draw(st.floats(1e-8, 1e-6))))
    else:
        ingredients.append(HystereticDamping(draw(st.floats(0.002, 0.05))))
    points = (NamedPoint("a", draw(positions), 1), NamedPoint("b", draw(positions), 2))
    model = BeamModel(tuple(segs), points, tuple(ingredients), theory=draw(st.sampled_from(["timoshenko", "euler-bernoulli"])),
                      kind=draw(st.sampled_from(["planar", "planar", "frame3d"])), max_element_length=length / 6)
    return model


@settings(max_examples=int(os.environ.get("JOINTDB_FE_EXAMPLES", "30")), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    model=random_models(),
    freq=st.lists(st.floats(10.0, 2e4), min_size=1, max_size=6, unique=True),
    method=st.sampled_from(["lu", "spectral", "modal"]),
)
def test_receptances_are_reciprocal_and_passive(model, freq, method):
    freq = np.sort(np.asarray(freq))
    if model.points[0].position == model.points[1].position:
        model = model.replace(points=(model.points[0],))
    # Skip lines where the (deflated) solve is too ill-conditioned for the tolerances below:
    # its condition number is about λ_max / min_r |λ_r − ω²| over the elastic modes.
    modes = model.modes()
    lam = (2 * np.pi * modes.freq_hz[modes.n_rigid :]) ** 2
    w2 = (2 * np.pi * freq) ** 2
    cond = lam.max() / np.min(np.abs(lam[None, :] - w2[:, None]))
    assume(cond < 1e7)
    if method == "spectral" and any(isinstance(i, Support) and any(i.damping.values()) for i in model.ingredients):
        method = "lu"  # the spectral sum needs classical damping
    if method == "modal":
        frf = model.frf(freq, method="modal")
    else:
        frf = model.frf(freq, method="direct", algorithm=method)
    h = frf.values
    scale = np.abs(h).max(axis=(1, 2), keepdims=True)
    scale = np.where(scale > 0, scale, 1.0)
    # reciprocity: H = Hᵀ (to the round-off of a solve with condition number < 1e7)
    assert np.max(np.abs(h - np.swapaxes(h, 1, 2)) / scale) < 1e-6
    # passivity: the dissipative part −Im H is positive semi-definite; driving points have Im H ≤ 0
    diag_imag = np.diagonal(h, axis1=1, axis2=2).imag
    assert np.all(diag_imag <= 1e-8 * scale[:, :, 0])
    eig = np.linalg.eigvalsh(0.5 * (h.imag + np.swapaxes(h.imag, 1, 2)))
    assert np.all(eig <= 1e-8 * scale[:, 0])


@pytest.mark.parametrize(
    "ingredients",
    [(Clamp(0.0), ModalDamping(0.02)), (Clamp(0.0), HystereticDamping(0.01), RayleighDamping(20.0, 0.0)),
     (ModalDamping(0.01),)],
    ids=["clamped-modal", "clamped-hysteretic-mass-proportional", "free-free"],
)
def test_spectral_sum_equals_the_plain_modal_sum(ingredients):
    """The spectral path (one product of 1/den with the mode-shape pair products, symmetric pairs
    only) against Σ_r φ_ir φ_jr / (ω_r² + iκ_r + iωc_r − ω²) written with einsum on the same
    eigen-solution: the same terms summed in another order, so equal to m_modes·eps·Σ_r|term|."""
    from jointdb.fe._synthesis import eigen_free

    model = shaft(ingredients)
    mats = model.assemble()
    freq = np.linspace(5.0, 9000.0, 211)
    idx = [0, 1, 10, 11, 24, 25]  # includes the clamped root DOFs (zero rows) for the clamped models
    got = frf_direct(mats, freq, idx, algorithm="spectral")
    lam, phi, n_rb = eigen_free(mats, None)
    free = ~mats.fixed
    c = np.diag(phi.T @ mats.C[np.ix_(free, free)] @ phi).clip(0.0)
    kappa = np.diag(phi.T @ mats.K_loss[np.ix_(free, free)] @ phi).clip(0.0)
    kappa[:n_rb] = 0.0
    pos = np.cumsum(free)[idx] - 1
    phi_io = np.where(free[idx][:, None], phi[pos], 0.0)
    w = 2 * np.pi * freq[:, None]
    terms = 1.0 / (lam[None, :] + 1j * kappa[None, :] + 1j * w * c[None, :] - w**2)
    want = np.einsum("ir,fr,jr->fij", phi_io, terms, phi_io)
    bound = lam.size * np.finfo(float).eps * np.einsum("ir,fr,jr->fij", np.abs(phi_io), np.abs(terms), np.abs(phi_io))
    assert np.all(np.abs(got - want) <= 4 * bound + 1e-300)
    assert np.array_equal(got, np.swapaxes(got, 1, 2))  # filled from the pairs i <= j


def test_spectral_sum_refuses_a_line_exactly_on_an_undamped_resonance():
    from jointdb.fe import FEMatrices
    from jointdb.frf import Dof

    lam = (2 * np.pi * 50.0) ** 2  # two 1 kg masses on springs to ground: 50 Hz twice, no damping
    mats = FEMatrices(K=lam * np.eye(2), M=np.eye(2), C=np.zeros((2, 2)), K_loss=np.zeros((2, 2)),
                      dof_labels=(Dof(0, "x"), Dof(1, "x")), node_positions=np.array([0.0, 1.0]),
                      fixed=np.zeros(2, bool))
    from jointdb.errors import NumericalError

    with pytest.raises(NumericalError, match="exactly on the line 50 Hz"):
        frf_direct(mats, np.array([10.0, 50.0, 90.0]), [0], algorithm="spectral")
    ok = frf_direct(mats, np.array([10.0, 49.0]), [0], algorithm="spectral")
    assert np.allclose(ok[:, 0, 0], 1.0 / (lam - (2 * np.pi * np.array([10.0, 49.0])) ** 2), rtol=1e-14)


def test_modal_damping_eigen_solution_is_reused_only_for_the_same_matrices():
    """Modal damping solves K φ = λ M φ; the spectral synthesis reuses it (no second eigh) only
    while K, M and the constraints are the very arrays it was computed for."""
    import dataclasses

    from jointdb.fe._synthesis import eigen_free

    mats = shaft((Clamp(0.0), ModalDamping(0.02))).assemble()
    assert mats.eigen_solution is not None
    freq = np.linspace(50.0, 20000.0, 400)
    idx = [0, 1, mats.K.shape[0] - 2]
    fresh = dataclasses.replace(mats, eigen_solution=None)
    assert np.array_equal(frf_direct(mats, freq, idx, algorithm="spectral"),
                          frf_direct(fresh, freq, idx, algorithm="spectral"))  # the same eigh, bit for bit
    lam_cached = eigen_free(mats, None)[0]
    assert lam_cached is mats.eigen_solution[3]
    # a stiffer K carried with the stale solution: it is not reused
    stiff = dataclasses.replace(mats, K=1.21 * mats.K)
    lam_stiff = eigen_free(stiff, None)[0]
    assert lam_stiff is not lam_cached
    elastic = lam_cached > 0
    assert np.allclose(lam_stiff[elastic], 1.21 * lam_cached[elastic], rtol=1e-9)


@pytest.mark.parametrize(
    "ingredients",
    [(Clamp(0.0), ModalDamping(0.02)), (ModalDamping(0.01),), (Clamp(0.0), HystereticDamping(0.01))],
    ids=["clamped", "free-free", "clamped-hysteretic"],
)
def test_natural_frequencies_alone_equal_those_of_natural_modes(ingredients):
    """The eigenvalues-only solve (same LAPACK driver, no shapes) gives bit-identical frequencies,
    rigid-body modes at 0 Hz included; and the rigid-body count from singular values alone agrees with
    the null space the shapes path builds."""
    from jointdb.fe import natural_frequencies, natural_modes, rigid_body_count
    from jointdb.fe._rigid import _rigid_null_space

    mats = shaft(ingredients).assemble()
    for n in (1, 4, 9):
        assert np.array_equal(natural_frequencies(mats, n), natural_modes(mats, n).freq_hz)
    assert rigid_body_count(mats) == _rigid_null_space(mats).shape[1] == (0 if isinstance(ingredients[0], Clamp) else 2)
    with pytest.raises(InputError, match="number of modes"):
        natural_frequencies(mats, 0)
