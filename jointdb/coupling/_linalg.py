"""Batched linear algebra for identification: regularised pseudo-inverses, smoothing.

All functions take frequency-first stacks ``(n_freq, m, n)``.

Least squares with model matrices (:func:`equilibrated_pinv`): per line, the
extreme eigenvalues of the equilibrated Gram matrix give the exact 2-norm
condition number, and the pseudo-inverse follows from the Gram matrix by an
inverse (the normal equations) where that condition number is small enough for
their round-off (``eps·cond²``) to stay below ``2e-10``; the other lines go
through one SVD, reused for the pseudo-inverse and the condition number.
Block-diagonal model matrices (each measured DOF sees only its own body's
contacts) are handled block by block. The eigenvalues and inverses of the
small Gram matrices, and the 2 × 2 block inverse of :func:`inverse`, use the
vectorised kernels of ``jointdb.coupling._smallmat`` (numpy's batched LAPACK
pays a fixed cost per small matrix that dominates here); results are checked
and lines the kernels cannot vouch for go to LAPACK.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from jointdb.errors import InputError

__all__ = [
    "Regularisation",
    "pinv",
    "condition",
    "pinv_condition",
    "equilibrated_pinv",
    "equilibrated_pinvs",
    "inverse",
    "frobenius",
    "savgol_smooth",
]


@dataclass(frozen=True)
class Regularisation:
    """How to invert the (possibly ill-conditioned) model matrices in IRC.

    Parameters
    ----------
    method
        ``"none"`` (Moore–Penrose pseudo-inverse, exact when well posed),
        ``"tsvd"`` (truncated SVD: singular values below ``rel * s_max`` are
        dropped) or ``"tikhonov"`` (filter factors ``s²/(s² + (rel·s_max)²)``).
    rel
        Relative threshold / regularisation parameter, per frequency line.
    """

    method: str = "none"
    rel: float = 0.0

    def __post_init__(self) -> None:
        if self.method not in ("none", "tsvd", "tikhonov"):
            raise InputError(f"regularisation method {self.method!r}: expected none, tsvd or tikhonov")
        if not (np.isfinite(self.rel) and 0.0 <= self.rel < 1.0):
            raise InputError(f"regularisation parameter {self.rel!r} must be in [0, 1)")

    @classmethod
    def parse(cls, value: "Regularisation | str | None | tuple") -> "Regularisation":
        """A :class:`Regularisation` from its written forms.

        Parameters
        ----------
        value
            None (no regularisation), a :class:`Regularisation` (returned as is), text
            ``"method:rel"`` (``"tikhonov:1e-3"``, ``"tsvd:1e-4"``, ``"none"``; a method
            without ``rel`` takes 1e-3) or a tuple ``(method, rel)``.

        Returns
        -------
        Regularisation

        Raises
        ------
        InputError
            An unknown method, a ``rel`` that is not a number in [0, 1), or another type.
        """
        if value is None:
            return cls()
        if isinstance(value, Regularisation):
            return value
        if isinstance(value, str):
            name, _, rel = value.partition(":")
            try:
                rel_value = float(rel) if rel else (0.0 if name.strip().lower() == "none" else 1e-3)
            except ValueError:
                raise InputError(
                    f"regularisation {value!r}: {rel!r} is not a number; use e.g. 'tikhonov:1e-3' or 'tsvd:1e-4'"
                ) from None
            return cls(name.strip().lower(), rel_value)
        if isinstance(value, tuple) and len(value) == 2:
            return cls(str(value[0]), float(value[1]))
        raise InputError(f"cannot read a regularisation from {value!r}; use e.g. 'tikhonov:1e-3' or 'tsvd:1e-4'")


#: Lines whose equilibrated model matrix has a condition number below this are solved
#: through the normal equations (relative round-off ~ eps·cond² <= 2e-10); others by SVD.
NORMAL_EQUATIONS_MAX_COND = 1e3


def pinv(a: np.ndarray, reg: Regularisation = Regularisation()) -> np.ndarray:
    """Batched (regularised) pseudo-inverse of ``a`` with shape ``(n_freq, m, n)`` → ``(n_freq, n, m)``."""
    return pinv_condition(a, reg)[0]


def pinv_condition(a: np.ndarray, reg: Regularisation = Regularisation()) -> tuple[np.ndarray, np.ndarray]:
    """:func:`pinv` and :func:`condition` of ``a`` from one batched SVD: ``((n_freq, n, m), (n_freq,))``."""
    u, s, vh = np.linalg.svd(a, full_matrices=False)
    with np.errstate(divide="ignore"):
        cond = np.where(s[:, -1] > 0, s[:, 0] / np.where(s[:, -1] > 0, s[:, -1], 1.0), np.inf)
    smax = s[:, :1]
    if reg.method == "tikhonov" and reg.rel > 0:
        mu = reg.rel * smax
        inv_s = s / (s**2 + mu**2)
    else:
        tol = (reg.rel if reg.method == "tsvd" else 0.0) * smax
        tol = np.maximum(tol, np.finfo(float).eps * max(a.shape[1:]) * smax)
        with np.errstate(divide="ignore"):
            inv_s = np.where(s > tol, 1.0 / np.where(s > 0, s, 1.0), 0.0)
    return np.conj(np.swapaxes(vh, 1, 2)) @ (inv_s[:, :, None] * np.conj(np.swapaxes(u, 1, 2))), cond


def equilibrated_pinv(
    blocks: "list[np.ndarray]", reg: Regularisation = Regularisation(), wide: bool = False
) -> tuple[list[np.ndarray], np.ndarray]:
    """Pseudo-inverse of a block-diagonal model matrix through its equilibrated form.

    The matrix is ``a = diag(a_1, a_2, ...)`` (e.g. measured DOFs on each body
    against that body's contact DOFs). Tall (``wide=False``): its columns are
    scaled to unit norm per line, ``a = a_s · diag(scale)``; wide: its rows,
    ``a = diag(scale) · a_s``. The scaling keeps mixed units (translations,
    rotations) from inflating the condition number and makes the
    regularisation threshold unit-free. Returns the diagonal blocks of
    ``diag(1/scale) · pinv(a_s)`` (tall) or ``pinv(a_s) · diag(1/scale)``
    (wide): ``pinv(a)`` itself when nothing is regularised or truncated.

    Parameters
    ----------
    blocks
        The diagonal blocks ``(n_freq, m_k, n_k)``; ``m_k >= n_k`` (tall) or
        ``m_k <= n_k`` (wide) for a full-rank problem.
    reg
        Regularisation of ``pinv(a_s)`` (thresholds relative to the largest
        singular value of the whole ``a_s``).
    wide
        Whether the matrix has more columns than rows (rows are equilibrated).

    Returns
    -------
    pinvs : list of ndarray ``(n_freq, n_k, m_k)``
        Diagonal blocks of the pseudo-inverse (it is block diagonal too).
    cond : ndarray ``(n_freq,)``
        2-norm condition number of the whole ``a_s`` (inf when rank deficient).

    Notes
    -----
    Where ``cond < NORMAL_EQUATIONS_MAX_COND`` (and no singular value is
    truncated) each block is inverted on its own: ``inv(a_s)`` for a square
    block, else through the normal equations with the Gram matrix
    ``G_s = a_sᴴ a_s`` (tall) or ``a_s a_sᴴ`` (wide):
    ``pinv(a_s) = (G_s + μ²I)⁻¹ a_sᴴ`` or ``a_sᴴ (G_s + μ²I)⁻¹``. The
    extreme eigenvalues of the Gram matrices give the condition number (the
    singular values of a block-diagonal matrix are those of its blocks), with
    relative round-off ~ eps·cond², below 2e-10 there. Elsewhere one SVD of
    the whole ``a_s`` gives both, as :func:`pinv_condition`. The eigenvalues
    and the Gram inverses come from the batched kernels of
    ``jointdb.coupling._smallmat`` (one call for all blocks).
    """
    return equilibrated_pinvs([(blocks, wide)], reg)[0]


def equilibrated_pinvs(
    sides: "list[tuple[list[np.ndarray], bool]]", reg: Regularisation = Regularisation()
) -> list[tuple[list[np.ndarray], np.ndarray]]:
    """:func:`equilibrated_pinv` of several block-diagonal matrices ``[(blocks, wide), ...]`` at once.

    The Gram matrices of all blocks go through one eigenvalue kernel call and
    one inverse kernel call (per block size), which is what costs.
    """
    nf = sides[0][0][0].shape[0]
    parts, buffers = _gram_buffers(sides, nf)
    conds, fasts, lam_maxs = _side_conditions(sides, buffers, reg, nf)
    inverses = _gram_inverses(sides, buffers, fasts, lam_maxs, reg, nf)
    out_sides = []
    for k, side in enumerate(parts):
        wide, fast, cond = sides[k][1], fasts[k], conds[k]
        out = []
        for j, (ab, abh, _, sb) in enumerate(side):
            sb = sb.T
            if not fast.any():
                out.append(np.zeros(abh.shape, dtype=complex))
            elif (k, j) in inverses:
                gi = inverses[k, j]
                out.append(abh @ gi if wide else gi @ abh)
            else:  # square: a solve, no normal equations
                n = ab.shape[1]
                a_s = ab / (sb[:, :, None] if wide else sb[:, None, :])
                a_s[~fast] = np.eye(n)  # those lines are solved by SVD below
                x = np.linalg.inv(a_s)
                out.append(x / (sb[:, None, :] if wide else sb[:, :, None]))
        slow = np.flatnonzero(~fast)
        if slow.size:
            _svd_lines(side, wide, slow, out, cond, reg)
        out_sides.append((out, cond))
    return out_sides


def _gram_buffers(sides, nf: int):
    """Per block: ``[ab, abh, gram (n, n, nf) frequency-last, scale sb (n, nf)]``; and per block size
    ``n``: ``(buffer, scales, members)``. The Gram matrices of equal size share one buffer (one kernel
    call each); elementwise work is done there, frequency-last, where every operation runs over long
    contiguous rows."""
    parts = [[None] * len(blocks) for blocks, _ in sides]
    sizes = {}
    for k, (blocks, wide) in enumerate(sides):
        for j, ab in enumerate(blocks):
            sizes.setdefault(ab.shape[1] if wide else ab.shape[2], []).append((k, j))
    buffers = {}
    for n, members in sizes.items():
        buf = np.empty((n, n, nf * len(members)), dtype=complex)
        for i, (k, j) in enumerate(members):
            ab, wide = sides[k][0][j], sides[k][1]
            abh = np.conj(np.swapaxes(ab, 1, 2))
            gram = buf[:, :, i * nf : (i + 1) * nf]
            gram[...] = np.moveaxis(ab @ abh if wide else abh @ ab, 0, -1)
            parts[k][j] = [ab, abh, gram, None]
        sb = np.sqrt(np.einsum("iif->if", buf).real)  # the squared row/column norms are on the diagonal
        sb[sb == 0] = 1.0  # (the kernels equilibrate: S⁻¹ G S⁻¹, S = diag(sb))
        for i, (k, j) in enumerate(members):
            parts[k][j][3] = sb[:, i * nf : (i + 1) * nf]
        buffers[n] = (buf, sb, members)
    return parts, buffers


def _side_conditions(sides, buffers, reg: Regularisation, nf: int):
    """Per side: the condition number of the equilibrated matrix, the lines the normal equations may
    serve (``fast``), and the largest Gram eigenvalue, from the extreme eigenvalues of every block."""
    from jointdb.coupling._smallmat import hermitian_extremes

    # extreme eigenvalues of the Gram matrices (fewer equations than unknowns: rank deficient, λmin = 0)
    extremes = {}
    for n, (buf, sb, members) in buffers.items():
        lmin, lmax = hermitian_extremes(buf, sb, psd=True)
        for i, (k, j) in enumerate(members):
            ab, wide = sides[k][0][j], sides[k][1]
            deficient = (ab.shape[2] if wide else ab.shape[1]) < (ab.shape[1] if wide else ab.shape[2])
            lo = np.zeros(nf) if deficient else lmin[i * nf : (i + 1) * nf]
            extremes[k, j] = (lo, lmax[i * nf : (i + 1) * nf])
    conds, fasts, lam_maxs = [], [], []
    for k, (blocks, _) in enumerate(sides):
        lam_max = np.zeros(nf)
        lam_min = np.full(nf, np.inf)
        for j in range(len(blocks)):
            lo, hi = extremes[k, j]
            lam_max = np.maximum(lam_max, hi)
            lam_min = np.minimum(lam_min, lo)
        with np.errstate(divide="ignore", invalid="ignore"):
            cond = np.where(lam_min > 0, np.sqrt(lam_max / np.where(lam_min > 0, lam_min, 1.0)), np.inf)
        fast = cond < NORMAL_EQUATIONS_MAX_COND
        if reg.method == "tsvd" and reg.rel > 0:
            fast &= cond * reg.rel < 1.0  # no singular value below the truncation threshold
        conds.append(cond)
        fasts.append(fast)
        lam_maxs.append(lam_max)
    return conds, fasts, lam_maxs


def _gram_inverses(sides, buffers, fasts, lam_maxs, reg: Regularisation, nf: int) -> dict:
    """``{(side, block): S⁻¹ (G_s + μ²I)⁻¹ S⁻¹}`` for the non-square blocks (and all with Tikhonov).

    Normal equations: S⁻¹ (G_s + μ²I)⁻¹ S⁻¹ = (G + μ²S²)⁻¹ (identity on the lines left to the SVD);
    no need to equilibrate: see hpd_inverse.
    """
    from jointdb.coupling._smallmat import hpd_inverse, to_first

    tikhonov = reg.method == "tikhonov" and reg.rel > 0
    inverses = {}
    for n, (buf, sb, members) in buffers.items():
        use = [(i, k, j) for i, (k, j) in enumerate(members)
               if fasts[k].any() and (sides[k][0][j].shape[1] != sides[k][0][j].shape[2] or tikhonov)]
        if not use:
            continue
        if len(use) == len(members):  # the Gram matrices are not needed any more: invert in place
            inv, scale = buf, sb
            where = [i for i, _, _ in use]
        else:
            inv = np.concatenate([buf[:, :, i * nf : (i + 1) * nf] for i, _, _ in use], axis=2)
            scale = np.concatenate([sb[:, i * nf : (i + 1) * nf] for i, _, _ in use], axis=1)
            where = list(range(len(use)))
        # (G_s + μ²I)⁻¹ unscaled: G + μ² S², with S² the Gram diagonal (μ² relative to the side's λmax)
        skip = np.concatenate([~fasts[k] for _, k, _ in use])
        shift = None
        if tikhonov:
            shift = np.concatenate([reg.rel**2 * lam_maxs[k] for _, k, _ in use]) * scale**2
        hpd_inverse(inv, shift, skip if skip.any() else None)
        for u, (i, k, j) in zip(where, use):
            inverses[k, j] = to_first(inv[:, :, u * nf : (u + 1) * nf])
    return inverses


def _svd_lines(side, wide: bool, slow: np.ndarray, out: list, cond: np.ndarray, reg: Regularisation) -> None:
    """On the ``slow`` lines, the pseudo-inverse blocks of one side (into ``out``) and its condition
    number (into ``cond``) from one SVD of the whole equilibrated block-diagonal matrix."""
    blocks = [p[0] for p in side]
    rows = np.cumsum([0] + [ab.shape[1] for ab in blocks])
    cols = np.cumsum([0] + [ab.shape[2] for ab in blocks])
    whole = np.zeros((slow.size, rows[-1], cols[-1]), dtype=complex)
    scale = np.ones((slow.size, rows[-1] if wide else cols[-1]))
    for b, (ab, _, _, sb) in enumerate(side):
        whole[:, rows[b] : rows[b + 1], cols[b] : cols[b + 1]] = ab[slow]
        span = slice(rows[b], rows[b + 1]) if wide else slice(cols[b], cols[b + 1])
        scale[:, span] = sb.T[slow]
    if wide:
        ps, cond[slow] = pinv_condition(whole / scale[:, :, None], reg)
        ps /= scale[:, None, :]
    else:
        ps, cond[slow] = pinv_condition(whole / scale[:, None, :], reg)
        ps /= scale[:, :, None]
    for b, pk in enumerate(out):
        pk[slow] = ps[:, cols[b] : cols[b + 1], rows[b] : rows[b + 1]]


def frobenius(x: np.ndarray) -> np.ndarray:
    """``‖x‖_F`` per line of a complex stack ``(n_freq, m, n)``, any strides (no copy, no temporary)."""
    if x.flags.c_contiguous and x.dtype == complex and x.size:
        v = x.reshape(x.shape[0], -1).view(np.float64)  # real and imaginary parts side by side
        return np.sqrt(np.einsum("fi,fi->f", v, v))
    return np.sqrt(np.einsum("fij,fij->f", x.real, x.real) + np.einsum("fij,fij->f", x.imag, x.imag))


def inverse(p: np.ndarray, out: "np.ndarray | None" = None) -> np.ndarray:
    """Batched inverse of square ``(n_freq, n, n)``; the SVD pseudo-inverse on numerically singular lines.

    For n >= 4 the inverse is first formed by 2 × 2 block elimination (Schur
    complement, the two diagonal blocks inverted by the Gauss–Jordan kernel of
    ``jointdb.coupling._smallmat``, no pivoting) and kept on the lines where
    its residual is that of a backward-stable inverse,
    ``‖p x − I‖_F <= 10·n·eps·‖p‖_F‖x‖_F``; the other lines (a nearly singular
    leading block) are inverted by LAPACK (LU with partial pivoting).
    ``inv`` and ``pinv`` agree to round-off unless ``cond₂ > 1/(n·eps)``, where
    ``pinv`` drops singular values. ``‖p‖_F‖p⁻¹‖_F >= cond₂`` flags those
    lines (with a factor 100 to spare), which are then pseudo-inverted.
    ``out``: an array of p's shape to write the result into (returned).
    """
    nf, n = p.shape[0], p.shape[-1]
    eps = np.finfo(float).eps
    if nf == 0:
        return np.empty(p.shape, dtype=np.result_type(p, 1.0)) if out is None else out
    x = None
    norm_x = None
    norm_p = frobenius(p)
    if n >= 4:
        x = _block_inverse(p, out)
        with np.errstate(all="ignore"):
            r = p @ x
            r.reshape(nf, -1)[:, :: n + 1] -= 1.0
            norm_x = frobenius(x)
            redo = np.flatnonzero(~(frobenius(r) <= 10.0 * n * eps * norm_p * norm_x))  # also NaN
    else:
        redo = np.arange(nf)
    if redo.size:
        sub = p if redo.size == nf else p[redo]
        try:
            xr = np.linalg.inv(sub)
        except np.linalg.LinAlgError:  # exactly singular at some line
            xr = np.full(sub.shape, np.nan, dtype=np.result_type(sub, 1.0))
        if x is None and out is None:
            x = xr
        elif x is None:
            x = out
            x[...] = xr
        else:
            x[redo] = xr
    with np.errstate(over="ignore", invalid="ignore"):
        est = norm_p * (frobenius(x) if redo.size or norm_x is None else norm_x)
    bad = ~(est < 0.01 / (n * eps))  # also NaN
    if bad.any():
        x[bad] = pinv(p[bad])
    return x


def _block_inverse(p: np.ndarray, out: "np.ndarray | None" = None) -> np.ndarray:
    """``p⁻¹`` by 2 × 2 block elimination without pivoting (unchecked; see :func:`inverse`), into ``out``."""
    from jointdb.coupling._smallmat import gauss_jordan_inverse, to_first, to_last

    h = p.shape[-1] // 2
    a, b, c, d = p[:, :h, :h], p[:, :h, h:], p[:, h:, :h], p[:, h:, h:]
    x = np.empty(p.shape, dtype=np.result_type(p, 1.0)) if out is None else out
    with np.errstate(all="ignore"):
        ai = to_first(gauss_jordan_inverse(to_last(a).astype(x.dtype, copy=False)))
        naib = ai @ b
        np.negative(naib, out=naib)  # −A⁻¹ B
        s = c @ naib
        s += d  # Schur complement S = D − C A⁻¹ B
        np.copyto(x[:, h:, h:], np.moveaxis(gauss_jordan_inverse(to_last(s)), -1, 0))
        si = x[:, h:, h:]
        ncai = c @ ai
        np.negative(ncai, out=ncai)  # −C A⁻¹
        np.matmul(si, ncai, out=x[:, h:, :h])  # −S⁻¹ C A⁻¹
        np.matmul(naib, si, out=x[:, :h, h:])  # −A⁻¹ B S⁻¹
        np.matmul(naib, x[:, h:, :h], out=x[:, :h, :h])
        x[:, :h, :h] += ai  # A⁻¹ + A⁻¹ B S⁻¹ C A⁻¹
    return x


def condition(a: np.ndarray) -> np.ndarray:
    """2-norm condition number per line, ``(n_freq,)`` (inf for rank deficiency)."""
    if a.shape[0] == 0:
        return np.zeros(0)
    s = np.linalg.svd(a, compute_uv=False)
    with np.errstate(divide="ignore"):
        return np.where(s[:, -1] > 0, s[:, 0] / np.where(s[:, -1] > 0, s[:, -1], 1.0), np.inf)


def savgol_smooth(values: np.ndarray, window: int, order: int = 4) -> np.ndarray:
    """Savitzky–Golay smoothing along frequency of real and imaginary parts (thesis §6.3: 4th order).

    Raises
    ------
    InputError
        If the window is even, not larger than the order, or longer than the data.
    """
    from scipy.signal import savgol_filter

    n = values.shape[0]
    if window % 2 == 0 or window <= order or window > n:
        raise InputError(
            f"Savitzky–Golay window {window} must be odd, > order {order} and <= the {n} frequency lines"
        )
    re = savgol_filter(values.real, window, order, axis=0, mode="interp")
    im = savgol_filter(values.imag, window, order, axis=0, mode="interp")
    return re + 1j * im
