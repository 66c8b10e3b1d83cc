"""Batched kernels for many small matrices, one per frequency line, in frequency-last layout.

numpy's batched LAPACK calls (``eigvalsh``, ``inv``) pay a fixed cost per
matrix that dominates for the 6 × 6 matrices of joint identification. The
kernels here work on arrays ``(n, n, n_freq)`` instead: every step of the
algorithm is one vectorised operation over all lines, so the cost is that of
the arithmetic. They are exact to round-off in the same sense as LAPACK
(backward stable) and check their own results, handing any line they cannot
certify to LAPACK.

- :func:`hermitian_extremes`: the smallest and largest eigenvalues of
  Hermitian matrices: Householder reduction to real tridiagonal form, then
  Laguerre's iteration from outside the spectrum (monotone and cubically
  convergent for a polynomial with real roots) on the characteristic
  polynomial, evaluated with its first two derivatives by the three-term
  recurrence, and a Sturm count (LDLᵀ pivots) on either side of each result
  that certifies it is the extreme eigenvalue within ``2·n·eps·‖T‖``.
- :func:`hpd_inverse`: inverse of Hermitian positive definite matrices by
  Gauss–Jordan elimination without pivoting (the pivots of a positive
  definite matrix are those of its Cholesky factorisation: no growth).
  :func:`gauss_jordan_inverse` is the same elimination for any matrix; its
  callers check the result (``jointdb.coupling._linalg.inverse``).
"""

from __future__ import annotations

import numpy as np

__all__ = ["hermitian_extremes", "hpd_inverse", "gauss_jordan_inverse", "to_last", "to_first"]

EPS = np.finfo(float).eps
_MAX_LAGUERRE = 30
#: Lines per pass of the elementwise kernels: their working set (a few (n, n, CHUNK)
#: complex arrays) then stays in the processor's cache instead of streaming from memory.
CHUNK = 2048


def to_last(a: np.ndarray) -> np.ndarray:
    """``(n_freq, m, n)`` → a contiguous ``(m, n, n_freq)`` copy."""
    return np.ascontiguousarray(np.moveaxis(a, 0, -1))


def to_first(a: np.ndarray) -> np.ndarray:
    """``(m, n, n_freq)`` → a contiguous ``(n_freq, m, n)`` copy."""
    return np.ascontiguousarray(np.moveaxis(a, -1, 0))


def _tridiagonalise(s: np.ndarray, d: np.ndarray, e2: np.ndarray, scratch: "tuple | None" = None) -> None:
    """Householder reduction of Hermitian ``s`` (n, n, nf), overwritten, to a real tridiagonal matrix.

    Writes its diagonal into ``d`` (n, nf) and squared off-diagonal into
    ``e2`` (n − 1, nf) (a Hermitian tridiagonal matrix is unitarily similar to
    the real one with the moduli of its off-diagonal entries). ``scratch``:
    buffers from :func:`_tridiagonal_scratch` for at least nf lines.
    """
    n, _, nf = s.shape
    r1, r2, r3, work, outer, outer2 = (b[..., :nf] for b in (scratch or _tridiagonal_scratch(n, nf)))
    for k in range(n - 2):
        m = n - k - 1
        x = s[k + 1 :, k]  # the column below the diagonal, reflected onto its first entry
        u, p, w = work[0, :m], work[1, :m], work[2, :m]
        uw, uw2 = outer[:m, :m], outer2
        d[k] = s[k, k].real
        nx2 = e2[k]
        np.multiply(x.real, x.real, out=u.real)
        np.multiply(x.imag, x.imag, out=u.imag)
        np.add(u.real, u.imag, out=u.real)
        u.real.sum(0, out=nx2)
        nx = np.sqrt(nx2, out=r1)
        ax0 = np.abs(x[0], out=r2)
        # u = (x + e^{i arg x0}‖x‖ e1) / ‖·‖ (no cancellation), ‖·‖² = 2(‖x‖² + |x0|‖x‖); u = 0 where x = 0
        np.multiply(ax0, nx, out=r3)
        r3 += nx2
        r3 *= 2.0
        np.sqrt(r3, out=r3)
        inv = np.divide(1.0, r3, out=r3, where=r3 > 0)
        inv[r3 == 0] = 0.0
        np.multiply(x, inv, out=u)
        phase = np.divide(x[0], ax0, out=np.ones(nf, dtype=complex), where=ax0 > 0)
        phase *= nx * inv
        u[0] += phase
        t = s[k + 1 :, k + 1 :]
        np.multiply(t, u[None], out=uw)
        uw.sum(1, out=p)  # t u
        kk = (u.real * p.real + u.imag * p.imag).sum(0)  # uᴴ t u (real)
        np.multiply(u, kk, out=w)
        np.subtract(p, w, out=w)
        np.conjugate(w, out=w)
        w *= 2.0
        # (I − 2uuᴴ) t (I − 2uuᴴ) = t − 2 u wᴴ − 2 w uᴴ
        np.multiply(u[:, None], w[None], out=uw)
        t -= uw
        np.conjugate(np.swapaxes(uw, 0, 1), out=uw2[:m, :m])
        t -= uw2[:m, :m]
    if n >= 2:
        d[n - 2] = s[n - 2, n - 2].real
        e2[n - 2] = s[n - 1, n - 2].real ** 2 + s[n - 1, n - 2].imag ** 2
    d[n - 1] = s[n - 1, n - 1].real


def _tridiagonal_scratch(n: int, nf: int) -> tuple:
    return (np.empty(nf), np.empty(nf), np.empty(nf), np.empty((3, n, nf), dtype=complex),
            np.empty((n, n, nf), dtype=complex), np.empty((n, n, nf), dtype=complex))


def _sturm_count(d: np.ndarray, e2: np.ndarray, x: np.ndarray, pivmin: np.ndarray) -> np.ndarray:
    """Number of eigenvalues below ``x`` (broadcasting with ``(nf,)``) of each tridiagonal (LDLᵀ pivots)."""
    q = d[0] - x
    q = np.where(np.abs(q) < pivmin, -pivmin, q)
    count = (q < 0).astype(np.int64)
    for i in range(1, d.shape[0]):
        q = d[i] - x - e2[i - 1] / q
        q = np.where(np.abs(q) < pivmin, -pivmin, q)
        count += q < 0
    return count


def _laguerre(d: np.ndarray, e2: np.ndarray, x: np.ndarray, tol: np.ndarray) -> np.ndarray:
    """Laguerre's iteration for a root of ``p(x) = det(T − xI)`` from each start ``x`` (nf,), to ``|step| <= tol``.

    ``T`` has diagonal ``d`` (n, nf) and squared off-diagonal ``e2`` (n − 1, nf),
    scaled so that its entries are at most about 1 (``p`` by the three-term
    recurrence cannot overflow). Lines stop once converged; the others are
    iterated on their own. All arithmetic is in place, in eight buffers.
    """
    n = d.shape[0]
    x = x.copy()
    idx = np.arange(x.size)
    dd, ee, xx, tt = d, e2, x.copy(), tol
    with np.errstate(all="ignore"):
        for _ in range(_MAX_LAGUERRE):
            a, p0, p1, dp0, dp1, ddp0, ddp1, t = np.empty((8, xx.size))
            # p_i = (d_i − x) p_{i−1} − e2_{i−1} p_{i−2}, and its first two derivatives; p_0 = d_0 − x,
            # p_1 = (d_1 − x)(d_0 − x) − e2_0, p_1' = −(d_1 − x) − (d_0 − x), p_1'' = 2
            np.subtract(dd[0], xx, out=p0)
            np.subtract(dd[1], xx, out=a)
            np.multiply(a, p0, out=p1)
            p1 -= ee[0]
            np.add(a, p0, out=dp1)
            np.negative(dp1, out=dp1)
            dp0.fill(-1.0)
            ddp1.fill(2.0)
            ddp0.fill(0.0)
            for i in range(2, n):
                np.subtract(dd[i], xx, out=a)
                e = ee[i - 1]
                np.multiply(e, ddp0, out=ddp0)  # p''_i = a p''_{i−1} − 2 p'_{i−1} − e p''_{i−2}
                np.multiply(a, ddp1, out=t)
                t -= ddp0
                t -= dp1
                t -= dp1
                ddp0, ddp1, t = ddp1, t, ddp0
                np.multiply(e, dp0, out=dp0)  # p'_i = a p'_{i−1} − p_{i−1} − e p'_{i−2}
                np.multiply(a, dp1, out=t)
                t -= p1
                t -= dp0
                dp0, dp1, t = dp1, t, dp0
                np.multiply(e, p0, out=p0)  # p_i = a p_{i−1} − e p_{i−2}
                np.multiply(a, p1, out=t)
                t -= p0
                p0, p1, t = p1, t, p0
            g, h = dp0, ddp0  # reuse: g = p'/p = Σ 1/(x − λ), h = g² − p''/p = Σ 1/(x − λ)²
            np.divide(dp1, p1, out=g)
            np.divide(ddp1, p1, out=h)
            np.multiply(g, g, out=a)
            np.subtract(a, h, out=h)
            np.multiply(h, n, out=t)  # (n − 1)(n h − g²) under the root
            t -= a
            t *= n - 1
            np.maximum(t, 0.0, out=t)
            np.sqrt(t, out=t)
            np.copysign(t, g, out=t)
            t += g
            step = np.divide(n, t, out=t)
            step[~np.isfinite(step)] = 0.0  # x is a root (p = 0)
            xx -= step
            x[idx] = xx
            more = np.abs(step) > tt
            if not more.any():
                break
            if more.mean() < 0.75:  # go on with the lines not yet converged only
                idx, dd, ee, xx, tt = idx[more], dd[:, more], ee[:, more], xx[more], tt[more]
    return x


def hermitian_extremes(
    g: np.ndarray, scale: "np.ndarray | None" = None, psd: bool = False
) -> tuple[np.ndarray, np.ndarray]:
    """Smallest and largest eigenvalue of each Hermitian matrix of ``g`` (n, n, n_freq).

    With ``scale`` (n, n_freq), those of ``diag(1/scale) g diag(1/scale)``
    (scaled chunk by chunk, in cache). Backward stable like LAPACK's
    ``eigvalsh`` (absolute error a small multiple of ``n·eps·‖g‖`` per line);
    each result is certified by Sturm counts, and lines that cannot be
    certified (none in practice) are computed by ``numpy.linalg.eigvalsh``.
    ``g`` is not modified. ``psd``: the matrices are known to be positive
    semi-definite (Gram matrices): the iteration for the smallest eigenvalue
    then starts just below 0 instead of at the Gershgorin bound (half the
    steps); a wrong claim only costs the LAPACK fallback.

    Returns
    -------
    lam_min, lam_max : ndarray ``(n_freq,)``
    """
    n, _, nf = g.shape
    if n <= 2 or nf == 0:
        lam = np.linalg.eigvalsh(to_first(_scaled(g, scale))) if nf else np.zeros((0, n))
        return lam[:, 0], lam[:, -1]
    d, e2 = np.empty((n, nf)), np.empty((n - 1, nf))
    size = min(nf, CHUNK)
    scratch = _tridiagonal_scratch(n, size)
    copy = np.empty((n, n, size), dtype=complex)
    for start in range(0, nf, CHUNK):
        part = slice(start, start + CHUNK)
        c = copy[:, :, : g[:, :, part].shape[2]]
        if scale is None:
            c[...] = g[:, :, part]
        else:
            np.divide(g[:, :, part], scale[:, None, part] * scale[None, :, part], out=c)
        _tridiagonalise(c, d[:, part], e2[:, part], scratch)
    e = np.sqrt(e2)
    radius = np.zeros((n, nf))
    radius[:-1] += e
    radius[1:] += e
    lo, hi = (d - radius).min(0), (d + radius).max(0)  # Gershgorin: the spectrum lies in [lo, hi]
    size = np.maximum(np.abs(lo), np.abs(hi))  # ‖T‖ within a factor of 2
    size[size == 0] = 1.0
    if psd:  # λmin >= 0 up to the reduction's round-off
        lo = np.maximum(lo, -4.0 * n * EPS * size)
    ds, es = d / size, e2 / size**2
    tol = 2.0 * EPS
    x = _laguerre(np.concatenate([ds, ds], 1), np.concatenate([es, es], 1),
                  np.concatenate([lo / size - tol, hi / size + tol]), np.full(2 * nf, tol))
    lam_min, lam_max = x[:nf] * size, x[nf:] * size
    delta = 2.0 * n * EPS * size
    pivmin = np.finfo(float).tiny * np.maximum(1.0, e2.max(0))
    counts = _sturm_count(d, e2, np.stack([lam_min - delta, lam_min + delta, lam_max - delta, lam_max + delta]), pivmin)
    ok = (counts[0] == 0) & (counts[1] >= 1) & (counts[2] <= n - 1) & (counts[3] == n)
    bad = np.flatnonzero(~ok)
    if bad.size:
        lam = np.linalg.eigvalsh(to_first(_scaled(g[:, :, bad], None if scale is None else scale[:, bad])))
        lam_min[bad], lam_max[bad] = lam[:, 0], lam[:, -1]
    return lam_min, lam_max


def _scaled(g: np.ndarray, scale: "np.ndarray | None") -> np.ndarray:
    return g if scale is None else g / (scale[:, None] * scale[None, :])


def gauss_jordan_inverse(a: np.ndarray, shift=None, skip=None) -> np.ndarray:
    """Inverse of each matrix of ``a`` (n, n, n_freq) by Gauss–Jordan elimination without pivoting, in place.

    Stable for Hermitian positive definite matrices (see :func:`hpd_inverse`);
    for others the caller checks the result (small pivots make it grow).
    ``shift`` (n, n_freq): added to the diagonal first; ``skip`` (bool,
    n_freq): lines set to the identity first (all applied chunk by chunk, in
    cache). Returns ``a``.
    """
    n, _, nf = a.shape
    size = min(nf, CHUNK)
    tmp_all = np.empty((n, n, size), dtype=a.dtype)  # scratch allocated once, reused by every chunk
    col_all = np.empty((n, size), dtype=a.dtype)
    piv_all = np.empty(size, dtype=a.dtype)
    buf = np.empty((n, n, size), dtype=a.dtype) if nf > CHUNK else None
    eye = np.eye(n)[:, :, None]
    for start in range(0, nf, CHUNK):
        part = a[:, :, start : start + CHUNK]
        w = part.shape[2]
        tmp, col, piv = tmp_all[:, :, :w], col_all[:, :w], piv_all[:w]
        c = part if buf is None else buf[:, :, :w]  # a contiguous copy: the chunk's rows adjacent in memory
        if buf is not None:
            c[...] = part
        if shift is not None:
            np.einsum("iif->if", c)[...] += shift[:, start : start + w]
        if skip is not None:
            lines = np.flatnonzero(skip[start : start + w])
            if lines.size:
                c[:, :, lines] = eye
        for k in range(n):
            np.divide(1.0, c[k, k], out=piv)
            c[k] *= piv
            col[...] = c[:, k]
            col[k] = 0.0
            np.multiply(col[:, None], c[k][None], out=tmp)
            c -= tmp
            np.multiply(col, piv, out=c[:, k])
            np.negative(c[:, k], out=c[:, k])
            c[k, k] = piv
        if buf is not None:
            part[...] = c
    return a


def hpd_inverse(a: np.ndarray, shift=None, skip=None) -> np.ndarray:
    """Inverse of each Hermitian positive definite matrix of ``a`` (n, n, n_freq), computed in place.

    Gauss–Jordan elimination without pivoting: for a positive definite
    matrix the pivots are the squared diagonal of its Cholesky factor, so
    nothing grows, and the error is that of an LU-based inverse,
    ``O(n·eps·cond(S⁻¹aS⁻¹))`` relative for the best diagonal scaling S:
    elimination without pivoting commutes with scaling by powers of two
    (exact), so equilibrating first would change nothing. ``shift``,
    ``skip``: see :func:`gauss_jordan_inverse`. Returns ``a``.
    """
    return gauss_jordan_inverse(a, shift, skip)
