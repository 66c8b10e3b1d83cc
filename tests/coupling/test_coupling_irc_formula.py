"""identify_joint_matrix / identify_n_point_joints (block-wise, in passes of lines, normal equations where
well conditioned, one SVD elsewhere, condition numbers from the extreme Gram eigenvalues by the batched
kernels, P⁻¹ by checked 2 × 2 block elimination or LU) against the straightforward
formulas on the whole matrices: SVD pseudo-inverses of the equilibrated H_IC and H_CI,
``H^J = pinv(P) − H_CC``, ``cond = cond₂(H_IC,s)·cond₂(H_CI,s)`` by SVD, and the residual of the
re-coupled measurement by a solve with ``H_CC + H^J``.

Tolerances from conditioning, per line, with κ_l, κ_r the condition numbers of the equilibrated
H_IC, H_CI and κ_P that of P:
- joint: the normal equations perturb P by ~eps·(κ_l² + κ_r²) relative, and P⁻¹ amplifies by κ_P,
  so ``‖ΔH^J‖ ≤ 100·eps·(κ_l² + κ_r²)·κ_P·‖P⁻¹‖`` (100 for the dimensions and products);
- condition number: eigenvalues of the Gram matrices, relative error ≤ 100·eps·(κ_l² + κ_r²);
- residual: the re-coupled FRFs differ by ≤ 100·eps·(κ_l² + κ_r²)·κ_P·‖D‖ (absolute, relative to ‖G‖).
"""

import numpy as np
import pytest

from jointdb.coupling import _matrix, identify_joint_matrix, identify_n_point_joints
from jointdb.coupling._linalg import NORMAL_EQUATIONS_MAX_COND
from jointdb.frf import DIRECTIONS, FRF, Dof

EPS = np.finfo(float).eps
FREQ = np.linspace(20.0, 3000.0, 240)


def modal(freq, n, seed, skew=0.0):
    """Receptance of a random damped n-DOF modal model; ``skew`` adds a non-reciprocal part."""
    rng = np.random.default_rng(seed)
    fn = np.sort(rng.uniform(50, 3500, n))
    zeta = rng.uniform(0.005, 0.03, n)
    phi = rng.standard_normal((n, n)) / np.sqrt(n)
    w, wn = 2 * np.pi * freq[:, None], 2 * np.pi * fn[None, :]
    h = np.einsum("im,fm,jm->fij", phi, 1.0 / (wn**2 - w**2 + 2j * zeta * wn * w), phi)
    if skew:
        h = h + skew * np.abs(h).max() * rng.standard_normal(h.shape)
    return h


def svd_pinv(a, method="none", rel=0.0):
    u, s, vh = np.linalg.svd(a, full_matrices=False)
    smax = s[:, :1]
    if method == "tikhonov":
        f = s / (s**2 + (rel * smax) ** 2)
    else:
        tol = np.maximum(rel * smax if method == "tsvd" else 0.0, EPS * max(a.shape[1:]) * smax)
        f = np.where(s > tol, 1.0 / s, 0.0)
    return np.conj(np.swapaxes(vh, 1, 2)) @ (f[:, :, None] * np.conj(np.swapaxes(u, 1, 2)))


def case(skew=0.0, seed=0, weak=False, na=8, freq=FREQ):
    """Two bodies: A with ``na`` measured + 6 contact DOFs, B with 15 − na + 6; measured DOFs interleaved."""
    a_meas = [Dof(i + 1, "x") for i in range(na)]
    b_meas = [Dof(i + 101, "x") for i in range(15 - na)]
    a_c = [Dof(50, d) for d in DIRECTIONS]
    b_c = [Dof(150, d) for d in DIRECTIONS]
    ha, hb = modal(freq, na + 6, seed + 1, skew), modal(freq, 21 - na, seed + 2, skew)
    if weak:  # at some lines two contact columns of A nearly repeat: ill-conditioned H_IC there
        lines = slice(40, 80)
        near = ha[lines, :na, na] + 1e-5 * np.abs(ha[lines, :na, na]) * np.random.default_rng(seed).standard_normal((40, na))
        ha[lines, :na, na + 1] = ha[lines, na + 1, :na] = near
    rng = np.random.default_rng(seed + 3)
    g = modal(freq, 15, seed + 4) + 0.01 * (rng.standard_normal((freq.size, 15, 15)))
    g = 0.5 * (g + np.swapaxes(g, 1, 2))
    order = list(np.random.default_rng(seed + 5).permutation(15))  # a and b measured DOFs interleaved
    meas_all = a_meas + b_meas
    labels = [meas_all[i] for i in order]
    measured = [("A" if i < na else "B", meas_all[i]) for i in order]
    assembly = FRF(freq, g[:, order][:, :, order], labels, labels)
    subs = {"A": FRF(freq, ha, a_meas + a_c, a_meas + a_c), "B": FRF(freq, hb, b_meas + b_c, b_meas + b_c)}
    return dict(assembly=assembly, subs=subs, measured=measured, a_c=a_c, b_c=b_c, ha=ha, hb=hb,
                g=g[:, order][:, :, order], order=order, na=na, freq=freq)


def straightforward(c, method="none", rel=0.0, symmetrize=True):
    """The formula on whole, zero-padded matrices in the measured order (before this rewrite)."""
    nf, L, nc, na = c["freq"].size, 15, 12, c["na"]
    order = c["order"]
    h_ii = np.zeros((nf, L, L), complex)
    h_ic = np.zeros((nf, L, nc), complex)
    h_ci = np.zeros((nf, nc, L), complex)
    h_cc = np.zeros((nf, nc, nc), complex)
    for k, i in enumerate(order):
        for kk, j in enumerate(order):
            if (i < na) == (j < na):
                h_ii[:, k, kk] = c["ha"][:, i, j] if i < na else c["hb"][:, i - na, j - na]
        for q in range(6):
            if i < na:
                h_ic[:, k, q], h_ci[:, q, k] = c["ha"][:, i, na + q], c["ha"][:, na + q, i]
            else:
                h_ic[:, k, 6 + q], h_ci[:, 6 + q, k] = c["hb"][:, i - na, 15 - na + q], c["hb"][:, 15 - na + q, i - na]
    h_cc[:, :6, :6], h_cc[:, 6:, 6:] = c["ha"][:, na:, na:], c["hb"][:, 15 - na :, 15 - na :]
    g = c["g"]
    if symmetrize:
        g = 0.5 * (g + np.swapaxes(g, 1, 2))
    d = h_ii - g
    sl, sr = np.linalg.norm(h_ic, axis=1), np.linalg.norm(h_ci, axis=2)
    al, br = h_ic / sl[:, None, :], h_ci / sr[:, :, None]
    p = svd_pinv(al, method, rel) @ d @ svd_pinv(br, method, rel) / sl[:, :, None] / sr[:, None, :]
    if symmetrize:
        p = 0.5 * (p + np.swapaxes(p, 1, 2))
    hj = svd_pinv(p) - h_cc
    if symmetrize:
        hj = 0.5 * (hj + np.swapaxes(hj, 1, 2))
    rec = h_ii - h_ic @ np.linalg.solve(h_cc + hj, h_ci)
    residual = np.linalg.norm(rec - g, axis=(1, 2)) / np.linalg.norm(g, axis=(1, 2))
    return dict(hj=hj, kl=np.linalg.cond(al), kr=np.linalg.cond(br), kp=np.linalg.cond(p), residual=residual,
                pinv_norm=np.linalg.norm(hj + h_cc, axis=(1, 2)), d_norm=np.linalg.norm(d, axis=(1, 2)),
                g_norm=np.linalg.norm(g, axis=(1, 2)))


def compare(res, ref, only=None):
    sel = np.ones(ref["hj"].shape[0], bool) if only is None else only
    k2 = ref["kl"] ** 2 + ref["kr"] ** 2
    err = np.linalg.norm(res.joint.values - ref["hj"], axis=(1, 2))
    bound = 100 * EPS * k2 * ref["kp"] * ref["pinv_norm"]
    assert np.all(err[sel] <= bound[sel]), f"joint: worst error/bound {np.max(err[sel] / bound[sel]):.2g}"
    cond_ref = ref["kl"] * ref["kr"]
    rel_c = np.abs(res.condition - cond_ref) / cond_ref
    assert np.all(rel_c[sel] <= 100 * EPS * k2[sel]), f"condition: worst {np.max(rel_c[sel] / (EPS * k2[sel])):.2g} eps·κ²"
    err_r = np.abs(res.residual - ref["residual"])
    bound_r = 100 * EPS * k2 * ref["kp"] * ref["d_norm"] / ref["g_norm"]
    assert np.all(err_r[sel] <= bound_r[sel]), f"residual: worst error/bound {np.max(err_r[sel] / bound_r[sel]):.2g}"


@pytest.mark.parametrize("skew", [0.0, 1e-3], ids=["reciprocal", "non-reciprocal"])
@pytest.mark.parametrize("symmetrize", [True, False])
def test_joint_matrix_equals_straightforward_formula(skew, symmetrize):
    c = case(skew)
    res = identify_joint_matrix(c["assembly"], c["subs"], c["measured"], "A", c["a_c"], "B", c["b_c"],
                                symmetrize=symmetrize)
    ref = straightforward(c, symmetrize=symmetrize)
    fast = np.maximum(ref["kl"], ref["kr"]) < NORMAL_EQUATIONS_MAX_COND
    assert fast.mean() > 0.9  # nearly all lines on the normal equations, a few on the SVD
    compare(res, ref)
    kp = res.extra["condition_p"]  # computed on first read, the same formula as before
    assert np.allclose(kp, ref["kp"], rtol=1e-6)


@pytest.mark.parametrize("reg", ["tikhonov:1e-2", "tsvd:1e-3", "tsvd:0.05"])
def test_regularised_joint_matrix_equals_straightforward_formula(reg):
    c = case(1e-3, seed=5)
    method, rel = reg.split(":")
    res = identify_joint_matrix(c["assembly"], c["subs"], c["measured"], "A", c["a_c"], "B", c["b_c"],
                                regularisation=reg)
    ref = straightforward(c, method, float(rel))
    compare(res, ref)


def test_ill_conditioned_lines_take_the_svd_and_agree():
    c = case(seed=9, weak=True)
    res = identify_joint_matrix(c["assembly"], c["subs"], c["measured"], "A", c["a_c"], "B", c["b_c"])
    ref = straightforward(c)
    slow = np.maximum(ref["kl"], ref["kr"]) >= NORMAL_EQUATIONS_MAX_COND
    assert slow[40:80].all() and slow.mean() < 0.3  # the weak lines are beyond the limit
    compare(res, ref, ~slow)
    # on the SVD lines: the same SVD formula, so the same numbers to a few eps·κ (not κ²)
    k = ref["kl"] * ref["kr"]
    assert np.allclose(res.condition[slow], k[slow], rtol=1e-9)
    err = np.linalg.norm(res.joint.values - ref["hj"], axis=(1, 2)) / ref["pinv_norm"]
    assert np.all(err[slow] <= 100 * EPS * k[slow] * ref["kp"][slow])


@pytest.mark.parametrize("skew", [0.0, 1e-3], ids=["reciprocal", "non-reciprocal"])
@pytest.mark.parametrize("symmetrize", [True, False])
def test_joint_matrix_in_several_passes_equals_straightforward_formula(monkeypatch, skew, symmetrize):
    """Lines are processed in passes (and P recomputed for condition_p): passes of 50 lines, the last
    one short, ill-conditioned lines (SVD) straddling a pass boundary."""
    monkeypatch.setattr(_matrix, "_LINES", 50)
    c = case(skew, seed=9, weak=True)
    res = identify_joint_matrix(c["assembly"], c["subs"], c["measured"], "A", c["a_c"], "B", c["b_c"],
                                symmetrize=symmetrize)
    ref = straightforward(c, symmetrize=symmetrize)
    slow = np.maximum(ref["kl"], ref["kr"]) >= NORMAL_EQUATIONS_MAX_COND
    assert slow[45:55].all()
    compare(res, ref, ~slow)
    assert np.allclose(res.condition[slow], (ref["kl"] * ref["kr"])[slow], rtol=1e-9)
    # cond(P) moves with P's relative error (as for the joint) times cond(P)
    rel_p = np.abs(res.extra["condition_p"] - ref["kp"]) / ref["kp"]
    k2 = np.where(slow, ref["kl"] * ref["kr"], ref["kl"] ** 2 + ref["kr"] ** 2)
    assert np.all(rel_p <= 100 * EPS * k2 * ref["kp"])


@pytest.mark.parametrize("reg", [None, "tikhonov:1e-2"])
def test_square_block_equals_straightforward_formula(reg):
    """Six measured DOFs on A: its block of H_IC is square (inverted, not through normal equations)."""
    c = case(1e-3, seed=3, na=6)
    res = identify_joint_matrix(c["assembly"], c["subs"], c["measured"], "A", c["a_c"], "B", c["b_c"],
                                regularisation=reg)
    ref = straightforward(c, *(reg.split(":")[0], float(reg.split(":")[1])) if reg else ())
    compare(res, ref)


@pytest.mark.parametrize("symmetrize", [True, False])
def test_joint_matrix_with_no_measured_dof_on_one_body_raises(monkeypatch, symmetrize):
    """All 15 measured DOFs on A: H_IC is singular at every line, in every pass (A's H_CC not exactly
    symmetric, so the symmetrised residual inverts H_CC + H^J, exactly singular here with B's block
    symmetric): the user's error, not a LinAlgError."""
    from jointdb.errors import NumericalError

    monkeypatch.setattr(_matrix, "_LINES", 100)
    a_meas = [Dof(i + 1, "x") for i in range(15)]
    a_c = [Dof(50, d) for d in DIRECTIONS]
    b_c = [Dof(150, d) for d in DIRECTIONS]
    ha, hb = modal(FREQ, 21, 1, skew=1e-9), modal(FREQ, 6, 2)
    hb = 0.5 * (hb + np.swapaxes(hb, 1, 2))
    subs = {"A": FRF(FREQ, ha, a_meas + a_c, a_meas + a_c), "B": FRF(FREQ, hb, b_c, b_c)}
    assembly = FRF(FREQ, modal(FREQ, 15, 3), a_meas, a_meas)
    with pytest.raises(NumericalError, match="singular at every line"):
        identify_joint_matrix(assembly, subs, [("A", d) for d in a_meas], "A", a_c, "B", b_c, symmetrize=symmetrize)


def test_n_point_equals_straightforward_formula():
    rng = np.random.default_rng(4)
    h = modal(FREQ, 9, 11)  # body A: 5 internal + 4 contact DOFs
    hb = modal(FREQ, 4, 12)
    g = modal(FREQ, 5, 13) + 0.01 * rng.standard_normal((FREQ.size, 5, 5))
    lab = [Dof(i + 1, "z") for i in range(9)]
    lb = [Dof(i + 21, "z") for i in range(4)]
    A, B = FRF(FREQ, h, lab, lab), FRF(FREQ, hb, lb, lb)
    G = FRF(FREQ, g, lab[:5], lab[:5])
    res = identify_n_point_joints(G, A, lab[:5], lab[5:], B, lb, diagonal=False, symmetrize=False)
    h_ia, h_ai = h[:, :5, 5:], h[:, 5:, :5]
    sl, sr = np.linalg.norm(h_ia, axis=1), np.linalg.norm(h_ai, axis=2)
    al, br = h_ia / sl[:, None, :], h_ai / sr[:, :, None]
    b_inv = svd_pinv(al) @ (h[:, :5, :5] - g) @ svd_pinv(br) / sl[:, :, None] / sr[:, None, :]
    hj = svd_pinv(b_inv) - h[:, 5:, 5:] - hb
    kl, kr, kb = np.linalg.cond(al), np.linalg.cond(br), np.linalg.cond(b_inv)
    err = np.linalg.norm(res.joint.values - hj, axis=(1, 2))
    bound = 100 * EPS * (kl**2 + kr**2) * kb * np.linalg.norm(hj + h[:, 5:, 5:] + hb, axis=(1, 2))
    assert np.all(err <= bound), f"worst error/bound {np.max(err / bound):.2g}"
    assert np.all(np.abs(res.condition - kl) <= 100 * EPS * kl**3)
