"""The batched small-matrix kernels of IRC against LAPACK (numpy.linalg), per line.

Tolerances from backward stability: eigenvalues of a Hermitian matrix are perturbed by at most
``‖ΔG‖₂``, and both LAPACK and the kernels have ``‖ΔG‖ <= c·n·eps·‖G‖`` (c = 4 here); an inverse
has relative error ``<= c·n·eps·cond(A)`` (c = 10).
"""

import numpy as np
import pytest

from jointdb.coupling import _smallmat
from jointdb.coupling._linalg import inverse, pinv
from jointdb.coupling._smallmat import hermitian_extremes, hpd_inverse, to_first, to_last

EPS = np.finfo(float).eps
RNG = np.random.default_rng(7)


def unitary(nf, n):
    q, _ = np.linalg.qr(RNG.standard_normal((nf, n, n)) + 1j * RNG.standard_normal((nf, n, n)))
    return q


def with_spectrum(lam):
    q = unitary(*lam.shape)
    return (q * lam[:, None, :]) @ np.conj(np.swapaxes(q, 1, 2))


def gram(nf, m, n):
    a = RNG.standard_normal((nf, m, n)) + 1j * RNG.standard_normal((nf, m, n))
    a /= np.linalg.norm(a, axis=1)[:, None, :]
    return np.conj(np.swapaxes(a, 1, 2)) @ a


CASES = {
    "equilibrated Gram 6x6": lambda: gram(3000, 8, 6),
    "Gram 3x3": lambda: gram(500, 5, 3),
    "Gram 12x12": lambda: gram(300, 14, 12),
    "clustered extremes": lambda: with_spectrum(
        np.array([0.3, 0.3 * (1 + 1e-9), 0.5, 0.9, 2.0, 2.0])[None].repeat(500, 0)),
    "graded to 1e-12": lambda: with_spectrum(np.logspace(-12, 0, 6)[None].repeat(500, 0)),
    "indefinite": lambda: (lambda b: b + np.conj(np.swapaxes(b, 1, 2)))(
        RNG.standard_normal((500, 6, 6)) + 1j * RNG.standard_normal((500, 6, 6))),
    "diagonal": lambda: np.einsum("fi,ij->fij", RNG.standard_normal((500, 6)), np.eye(6)).astype(complex),
    "rank 3": lambda: with_spectrum(np.array([0, 0, 0, 1, 2, 3.0])[None].repeat(200, 0)),
}


@pytest.mark.parametrize("psd", [False, True], ids=["any", "claimed psd"])
@pytest.mark.parametrize("name", list(CASES))
def test_hermitian_extremes_equal_eigvalsh(name, psd):
    """Also with the positive semi-definite start claimed for every case (wrongly for "indefinite")."""
    g = CASES[name]()
    ref = np.linalg.eigvalsh(g)
    lam_min, lam_max = hermitian_extremes(to_last(g), psd=psd)
    n = g.shape[-1]
    tol = 4 * n * EPS * np.abs(ref).max(axis=1)
    assert np.all(np.abs(lam_min - ref[:, 0]) <= tol)
    assert np.all(np.abs(lam_max - ref[:, -1]) <= tol)


def test_hermitian_extremes_uncertified_lines_go_to_lapack(monkeypatch):
    g = gram(400, 8, 6)
    monkeypatch.setattr(_smallmat, "_MAX_LAGUERRE", 1)  # one step: nothing has converged, nothing is certified
    lam_min, lam_max = hermitian_extremes(to_last(g))
    ref = np.linalg.eigvalsh(g)
    assert np.array_equal(lam_min, ref[:, 0]) and np.array_equal(lam_max, ref[:, -1])


def test_extremes_and_inverse_in_several_chunks(monkeypatch):
    monkeypatch.setattr(_smallmat, "CHUNK", 64)
    g = gram(1000, 8, 6)
    ref = np.linalg.eigvalsh(g)
    lam_min, lam_max = hermitian_extremes(to_last(g))
    assert np.allclose(lam_min, ref[:, 0], rtol=0, atol=24 * EPS * 6)
    gi = to_first(hpd_inverse(to_last(g)))
    ref_i = np.linalg.inv(g)
    err = np.linalg.norm(gi - ref_i, axis=(1, 2)) / np.linalg.norm(ref_i, axis=(1, 2))
    assert np.all(err <= 10 * 6 * EPS * np.linalg.cond(g))


def test_hpd_inverse_equals_lapack_inverse():
    g = with_spectrum(np.logspace(-6, 0, 6)[None].repeat(1000, 0))
    gi = to_first(hpd_inverse(to_last(g)))
    ref = np.linalg.inv(g)
    err = np.linalg.norm(gi - ref, axis=(1, 2)) / np.linalg.norm(ref, axis=(1, 2))
    assert np.all(err <= 10 * 6 * EPS * np.linalg.cond(g))


@pytest.mark.parametrize("dtype", [complex, float])
def test_inverse_block_elimination_equals_lapack(dtype):
    """Random lines, lines whose leading block is singular (no pivot: the residual check sends them
    to LAPACK), an exactly singular line and a numerically singular one (pseudo-inverse)."""
    n, nf = 12, 400
    p = RNG.standard_normal((nf, n, n)).astype(dtype)
    if dtype is complex:
        p = p + 1j * RNG.standard_normal((nf, n, n))
    p[10:20, :6, :6] = 0.0  # leading block zero: block elimination breaks down
    p[20:30, :6, :6] = p[20:30, :6, :1] * RNG.standard_normal(6)  # leading block of rank one
    p[30] = 0.0
    p[30, np.arange(n - 1), np.arange(n - 1)] = 1.0  # exactly singular
    p[31, :, -1] = p[31, :, 0] * (1 + 1e-17)  # numerically singular
    x = inverse(p)
    assert x.dtype == p.dtype
    good = np.setdiff1d(np.arange(nf), [30, 31])
    ref = np.linalg.inv(p[good])
    err = np.linalg.norm(x[good] - ref, axis=(1, 2)) / np.linalg.norm(ref, axis=(1, 2))
    assert np.all(err <= 10 * n * EPS * np.linalg.cond(p[good]))
    assert np.allclose(x[30:32], pinv(p[30:32]), rtol=0, atol=1e-12 * np.abs(pinv(p[30:32])).max())


def test_inverse_small_matrices_use_lapack():
    p = RNG.standard_normal((50, 3, 3)) + 1j * RNG.standard_normal((50, 3, 3))
    assert np.array_equal(inverse(p), np.linalg.inv(p))


def test_scaled_shifted_kernels_equal_the_explicit_formula(monkeypatch):
    """extremes of S⁻¹GS⁻¹, and (G + diag(shift))⁻¹ with skipped lines, in several chunks, on a badly
    scaled G (12 decades): the inverse is as accurate as that of the equilibrated matrix."""
    monkeypatch.setattr(_smallmat, "CHUNK", 128)
    g = gram(700, 8, 6) * np.logspace(-6, 6, 6)[None, :, None] * np.logspace(-6, 6, 6)[None, None, :]
    scale = np.sqrt(np.einsum("fii->if", g).real)
    gs = g / (scale.T[:, :, None] * scale.T[:, None, :])
    ref = np.linalg.eigvalsh(gs)
    lam_min, lam_max = hermitian_extremes(to_last(g), scale)
    assert np.allclose(lam_min, ref[:, 0], rtol=0, atol=24 * 6 * EPS)
    assert np.allclose(lam_max, ref[:, -1], rtol=0, atol=24 * 6 * EPS)
    mu = 1e-3 * ref[:, -1]
    skip = np.zeros(700, bool)
    skip[::7] = True
    out = to_first(hpd_inverse(to_last(g), mu * scale**2, skip))
    want = np.linalg.inv(gs + mu[:, None, None] * np.eye(6)) / (scale.T[:, :, None] * scale.T[:, None, :])
    keep = ~skip
    # entry by entry in the scaled units: S (out − want) S against the inverse of the equilibrated matrix
    err = np.abs(out[keep] - want[keep]) * (scale.T[keep][:, :, None] * scale.T[keep][:, None, :])
    inv_s = np.abs(np.linalg.inv(gs[keep])).max(axis=(1, 2))
    assert np.all(err.max(axis=(1, 2)) <= 10 * 6 * EPS * np.linalg.cond(gs[keep]) * inv_s)
    assert np.allclose(out[skip], np.eye(6))
