"""Truth family C (bench/_stack_truth_c.py) has the physics its docstring states.

- The contact laws at points where their value is known in closed form: the tool–holder contact is its reference
  value at 60 N·m and Ø10, and scales by 2^0.3 per doubled torque and 2^1.5 per doubled diameter; the taper
  contact is half its saturated value at 10 kN and three quarters at 30 kN.
- The spindle (bearings, overhung rotor, stepped hollow shaft) against an independent solution: the natural
  frequencies of the Euler–Bernoulli shaft by the transfer-matrix method (the exact solution of each uniform
  section, jumps at the bearings and the rotor), built from the module's constants, against the FE model the
  generator builds (switched to Euler–Bernoulli theory for the comparison). Cubic Euler–Bernoulli elements of 3 mm
  give the first modes to about 1e-6 (βh < 0.05), so 1e-4 is the tolerance: a misplaced bearing, rotor or
  section (millimetres) moves them by more. The generator's own (Timoshenko)
  FRF then peaks at most a few per cent below, never above, each of those frequencies (shear and rotary inertia
  only soften; 10 Hz lines, damping η 0.003).
- The truth stack's tip FRF at low frequency is the static compliance of the stack (passive: Im H ≤ 0).
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla


@pytest.fixture(scope="module")
def tc(load_script):
    load_script("bench/_stack_validation.py")
    load_script("bench/_stack_family.py")
    return load_script("bench/_stack_truth_c.py")


def test_tool_holder_contact_law(tc):
    ref = tc.th_contact(60.0, 0.010)
    assert ref == {"x": pytest.approx(tc.TH_KREF[0], rel=1e-12), "ry": pytest.approx(tc.TH_KREF[1], rel=1e-12)}
    for dof in ("x", "ry"):
        assert tc.th_contact(120.0, 0.010)[dof] / ref[dof] == pytest.approx(2 ** 0.3, rel=1e-12)
        assert tc.th_contact(60.0, 0.020)[dof] / ref[dof] == pytest.approx(2 ** 1.5, rel=1e-12)
        assert tc.th_contact(25.0, 0.006)[dof] / ref[dof] == pytest.approx((25 / 60) ** 0.3 * 0.6 ** 1.5, rel=1e-12)


def test_taper_contact_law(tc):
    assert tc.HS_FHALF == 10e3
    for dof, kinf in zip(("x", "ry"), tc.HS_KINF):
        assert tc.hs_contact(10e3)[dof] == pytest.approx(kinf / 2, rel=1e-12)
        assert tc.hs_contact(30e3)[dof] == pytest.approx(0.75 * kinf, rel=1e-12)
        assert tc.hs_contact(8e3)[dof] < tc.hs_contact(20e3)[dof] < kinf


def _tmm_det(omega: float, sections, points, E: float, rho: float) -> float:
    """det of the 2×2 free-end conditions of the Euler–Bernoulli shaft at ``omega`` (zero at a natural frequency).

    State ``[w, w', EI w'', EI w''']`` from the free nose (EI w'' = EI w''' = 0) along the shaft; in a uniform
    section ``y = [w, w', w'', w''']`` obeys ``y' = A y`` with ``w'''' = β⁴ w``, β⁴ = ρAω² / EI; at a point
    with spring k, mass m, rotational spring k_θ, rotary inertia J: [EI w'''] = −(k − mω²) w and
    [EI w''] = (k_θ − Jω²) w' (from the weak form)."""
    cols = np.eye(4)[:, :2].copy()  # two unknowns at the nose: w, w'
    ends = np.cumsum([s[0] for s in sections])
    marks = sorted({0.0, *ends.tolist(), *(p[0] for p in points)})
    for a, b in zip(marks[:-1], marks[1:]):
        for _, k, m, kt, j in (p for p in points if abs(p[0] - a) < 1e-12):
            cols[3] -= (k - m * omega ** 2) * cols[0]
            cols[2] += (kt - j * omega ** 2) * cols[1]
        _, do, di = sections[int(np.searchsorted(ends, a, side="right"))]
        area, inertia = np.pi / 4 * (do ** 2 - di ** 2), np.pi / 64 * (do ** 4 - di ** 4)
        ei = E * inertia
        beta4 = rho * area * omega ** 2 / ei
        amat = np.array([[0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1], [beta4, 0, 0, 0]], dtype=float)
        scale = np.diag([1.0, 1.0, ei, ei])
        cols = scale @ sla.expm(amat * (b - a)) @ np.linalg.inv(scale) @ cols
    return float(np.linalg.det(cols[2:]))


def _tmm_frequencies(tc, n: int) -> np.ndarray:
    from jointdb.fe import get_material

    steel = get_material("steel")
    (l1, d1, i1), (l2, d2, i2) = tc.SPINDLE
    sections = [(tc.TAPER[2], d1, tc.TAPER[1]), (l1 - tc.TAPER[2], d1, i1), (l2, d2, i2)]
    points = [(p, k["x"], 0.0, k.get("ry", 0.0), 0.0) for p, k, _ in tc.BEARINGS]
    points.append((tc.ROTOR[0], 0.0, tc.ROTOR[1], 0.0, tc.ROTOR[2]))
    f = np.arange(20.0, 6000.0, 5.0)
    det = np.array([_tmm_det(2 * np.pi * x, sections, points, steel.E, steel.rho) for x in f])
    roots = []
    for k in np.flatnonzero(np.sign(det[:-1]) != np.sign(det[1:]))[:n]:
        roots.append(_bisect(lambda x: _tmm_det(2 * np.pi * x, sections, points, steel.E, steel.rho), f[k], f[k + 1]))
    return np.array(roots)


def _bisect(fun, a: float, b: float) -> float:
    fa = fun(a)
    for _ in range(60):
        m = 0.5 * (a + b)
        fm = fun(m)
        if np.sign(fm) == np.sign(fa):
            a, fa = m, fm
        else:
            b = m
    return 0.5 * (a + b)


def test_spindle_modes_match_the_transfer_matrix_solution(tc):
    tmm = _tmm_frequencies(tc, 3)
    assert tmm.size == 3 and 200.0 < tmm[0] < 5000.0
    fe = tc.spindle_model().replace(theory="euler-bernoulli").modes(3).freq_hz
    np.testing.assert_allclose(fe, tmm, rtol=1e-4)
    # the generator's spindle receptance (Timoshenko, damped): a resonance at or a little below each
    h = np.abs(tc.spindle_frf().values[:, 0, 0])
    peaks = tc.FREQ[np.flatnonzero((h[1:-1] > h[:-2]) & (h[1:-1] >= h[2:])) + 1]
    for f in tmm[tmm < tc.FREQ[-1]]:
        near = peaks[np.argmin(np.abs(peaks - f))]
        assert 0.90 * f <= near <= f + 10.0, (f, peaks)


def test_truth_stack_is_passive_and_statically_right(tc):
    import _stack_validation as sv

    case = sv.Case("Ø10 blank", 0.010, 0.050, 0.040, 60.0, "BT40", 12e3)
    model, th, hs = tc.truth_model(case)
    assert th.contact.stiffness_per_length == tc.th_contact(60.0, 0.010)
    assert hs.contact.stiffness_per_length == tc.hs_contact(12e3)
    assert hs.end - hs.start == pytest.approx(tc.TAPER[2]) and th.end - th.start == pytest.approx(0.040)
    h = tc.truth_tip(case).values[:, 0, 0]
    assert np.all(h.imag <= 0)
    # the static tip compliance of the same model (K⁻¹ on the tip DOF) bounds the 100 Hz line from below
    m = model.assemble()
    keep = np.flatnonzero(~m.fixed)
    mesh = model.mesh()
    tip = list(keep).index(mesh.dof(mesh.node_at(0.0), "x"))
    static = np.linalg.solve(m.K[np.ix_(keep, keep)], np.eye(keep.size)[:, tip])[tip]
    assert static > 0 and abs(h[0]) > static * 0.999 and abs(h[0]) < 1.2 * static
