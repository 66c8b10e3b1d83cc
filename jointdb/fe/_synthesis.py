"""Natural modes and FRF synthesis (direct, batched over frequency; modal superposition).

Harmonic convention ``x = X e^{iωt}`` (docs/theory.md §0): the dynamic stiffness is
``D(ω) = K + i K_loss + iω C − ω² M`` and the receptance ``H = D⁻¹``.
"""

from __future__ import annotations

import numpy as np

from jointdb.errors import InputError, NumericalError
from jointdb.fe._matrices import Modes, free_block
from jointdb.fe._rigid import rigid_body_count, rigid_body_modes

__all__ = ["eigen_free", "natural_modes", "natural_frequencies", "frf_direct", "frf_modal"]

#: Memory budget [bytes] for one chunk of stacked dynamic-stiffness matrices.
CHUNK_BYTES = 64 * 2**20
#: ``frf_direct(algorithm="auto")`` uses LU while ``n_freq · n_free³`` stays below this.
AUTO_LU_WORK = 2e9


def eigen_free(matrices, n: int | None, max_value: float | None = None, vectors: bool = True):
    """Eigen-solution of the constrained (free-DOF) problem ``K φ = λ M φ``.

    With ``vectors=False`` only the eigenvalues are computed (the same LAPACK driver without the
    shapes: the same eigenvalues, at about half the cost) and ``phi`` is None.

    Returns
    -------
    lam : ndarray ``(m,)``
        Eigenvalues ω² [rad²/s²], ascending; the rigid-body ones set to 0.
    phi : ndarray ``(n_free, m)`` or None
        Mass-normalised shapes on the free DOFs (None with ``vectors=False``).
    n_rb : int
        Number of rigid-body modes (the first ``n_rb`` columns).
    """
    cached = getattr(matrices, "eigen_solution", None)
    if (vectors and cached is not None and n is None and max_value is None and cached[0] is matrices.K
            and cached[1] is matrices.M and cached[2] is matrices.fixed):
        return cached[3], cached[4], cached[5]  # the same problem, already solved (modal damping)
    Kf = free_block(matrices.K, matrices.fixed)
    Mf = free_block(matrices.M, matrices.fixed)
    nf = Kf.shape[0]
    if nf == 0:
        raise InputError("every DOF of the model is fixed; nothing can move")
    n_rb = rigid_body_count(matrices)
    kwargs = {}
    if max_value is not None:
        kwargs["subset_by_value"] = (-np.inf, max_value)
    elif n is not None and n < nf:
        kwargs["subset_by_index"] = (0, max(n, n_rb, 1) - 1)
    if not vectors:
        kwargs["eigvals_only"] = True
    try:
        lam, phi = _eigh(Kf, Mf, kwargs)
    except np.linalg.LinAlgError as exc:
        raise NumericalError(f"eigenvalue problem failed ({exc}); is the mass matrix positive definite?") from None
    if lam.size < n_rb and max_value is not None:  # make sure all rigid-body modes are there
        lam, phi = _eigh(Kf, Mf, {"subset_by_index": (0, n_rb - 1), "eigvals_only": not vectors})
    lam = lam.copy()
    lam[: min(n_rb, lam.size)] = 0.0
    if np.any(lam[n_rb:] <= 0.0):
        raise NumericalError(
            "the model has more zero-frequency modes than rigid-body motions explain "
            "(a mechanism, or a badly conditioned mesh: check supports and very short elements)"
        )
    return lam, phi, n_rb


def _eigh(K, M, kwargs: dict):
    """``(λ, φ)`` of ``scipy.linalg.eigh`` (φ None when only eigenvalues are asked for)."""
    import scipy.linalg  # deferred: importing jointdb.fe stays cheap (CLI start-up)

    out = scipy.linalg.eigh(K, M, **kwargs)
    return (out, None) if kwargs.get("eigvals_only") else out


def natural_frequencies(matrices, n: int) -> np.ndarray:
    """The ``n`` lowest natural frequencies [Hz] without the mode shapes (cheaper than
    :func:`natural_modes`, whose ``freq_hz`` it equals).

    Parameters
    ----------
    matrices
        :class:`FEMatrices` of an assembled model.
    n
        Number of lowest modes, >= 1.

    Returns
    -------
    ndarray, shape (n,) or fewer when the model has fewer DOFs
    """
    if isinstance(n, bool) or int(n) < 1:
        raise InputError(f"number of modes must be >= 1, got {n!r}")
    lam, _, _ = eigen_free(matrices, int(n), vectors=False)
    return np.sqrt(lam[: int(n)]) / (2.0 * np.pi)


def natural_modes(matrices, n: int | None = None):
    """Natural frequencies [Hz] and mass-normalised mode shapes over all DOFs.

    Parameters
    ----------
    matrices
        :class:`FEMatrices` of an assembled model.
    n
        Number of lowest modes (default: all).

    Returns
    -------
    Modes
    """
    if n is not None and (isinstance(n, bool) or int(n) < 1):
        raise InputError(f"number of modes must be >= 1, got {n!r}")
    lam, phi, n_rb = eigen_free(matrices, None if n is None else int(n))
    if n is not None:
        lam, phi = lam[: int(n)], phi[:, : int(n)]
    shapes = np.zeros((matrices.K.shape[0], lam.size))
    shapes[~matrices.fixed] = phi
    return Modes(
        freq_hz=np.sqrt(lam) / (2.0 * np.pi),
        shapes=shapes,
        dof_labels=matrices.dof_labels,
        n_rigid=min(n_rb, lam.size),
    )


def _check_freq(freq) -> np.ndarray:
    f = np.asarray(freq, dtype=float)
    if f.ndim != 1 or f.size == 0 or not np.all(np.isfinite(f)) or f.min() < 0:
        raise InputError("frequencies must be a non-empty 1-D array of finite values >= 0 Hz")
    return f


def _free_positions(matrices, dof_index):
    """Positions of the requested DOFs within the free set (−1 where fixed)."""
    free = ~matrices.fixed
    pos = np.cumsum(free) - 1
    dof_index = np.asarray(dof_index, dtype=int)
    return np.where(free[dof_index], pos[dof_index], -1)


def frf_direct(
    matrices, freq_hz, dof_index, chunk_bytes: int = CHUNK_BYTES, algorithm: str = "auto"
) -> np.ndarray:
    """Receptances by exact (untruncated) solution of the full equations, batched over frequency.

    ``(K + iK_loss + iωC − ω²M) X = F`` for unit loads at the requested DOFs.
    Two exact algorithms:

    - ``"lu"``: stacks of ``(n_chunk, n, n)`` dynamic stiffness matrices, one
      ``np.linalg.solve`` per chunk (chunks bound the memory to ``chunk_bytes``;
      no loop over lines); rigid-body modes are split off exactly first.
    - ``"spectral"``: when the damping is classical (the undamped modes
      diagonalise C and K_loss: modal, Rayleigh, hysteretic damping; not
      dampers in supports), the inverse is the sum over *all* modes,
      ``Σ φφᵀ/(ω_r² + iκ_r + iωc_r − ω²)`` — one eigen-solution, then an
      einsum over frequency: orders of magnitude faster than LU for many lines.
    - ``"auto"`` (default): LU for small problems (``n_freq · n³ <= AUTO_LU_WORK``,
      a few seconds at most), otherwise spectral when the damping is classical,
      else LU. Both are exact; LU's round-off is about 10x smaller
      (~1e-14 vs ~1e-13 relative, checked against exact rational arithmetic).

    Parameters
    ----------
    matrices
        :class:`FEMatrices`.
    freq_hz
        Frequencies [Hz], ``(n_freq,)``.
    dof_index
        Global DOF indices of outputs = inputs, ``(m,)``.
    chunk_bytes, algorithm
        Memory bound [bytes] of one stack of LU systems; ``"auto"``, ``"lu"`` or ``"spectral"``.

    Returns
    -------
    ndarray, complex, ``(n_freq, m, m)``; zero rows/columns for fixed DOFs.

    Raises
    ------
    InputError
        At 0 Hz when the model has rigid-body modes (the receptance is infinite).
    NumericalError
        If the dynamic stiffness is singular at some line.
    """
    f = _check_freq(freq_hz)
    free = ~matrices.fixed
    nf = int(free.sum())
    if f.min() == 0.0 and rigid_body_count(matrices) > 0:
        raise InputError(
            "the model has rigid-body modes (it is not fully supported), so its receptance at 0 Hz is "
            "infinite; start the frequency range above 0 Hz"
        )
    pos = _free_positions(matrices, dof_index)
    ok = pos >= 0
    m = pos.size
    if algorithm not in ("auto", "lu", "spectral"):
        raise InputError(f"algorithm must be 'auto', 'lu' or 'spectral', got {algorithm!r}")
    if algorithm == "auto" and f.size * float(nf) ** 3 <= AUTO_LU_WORK:
        algorithm = "lu"  # small problem: LU (round-off ~10x smaller than the spectral sum)
    if algorithm != "lu":
        lam, phi, n_rb = eigen_free(matrices, None)
        out, _, classical = _modal_sum(matrices, f, lam, phi, n_rb, pos, ok, coupled="none")
        if classical:
            return out
        if algorithm == "spectral":
            raise InputError("the spectral algorithm needs classical damping (no dampers in supports); use 'lu'")
    Kc = free_block(matrices.K, matrices.fixed) + 1j * free_block(matrices.K_loss, matrices.fixed)
    Mf = free_block(matrices.M, matrices.fixed)
    Cf = free_block(matrices.C, matrices.fixed)
    rhs = np.zeros((nf, int(ok.sum())), dtype=complex)
    rhs[pos[ok], np.arange(rhs.shape[1])] = 1.0
    out = np.zeros((f.size, m, m), dtype=complex)
    w = 2.0 * np.pi * f
    Lf = free_block(matrices.K_loss, matrices.fixed)
    deflation = _rigid_deflation(Kc.real, Mf, Cf, Lf, rigid_body_modes(matrices))
    rigid_rhs = None
    if deflation is not None:
        # split off the rigid-body motion exactly (see _rigid_deflation): far better
        # conditioned than K − ω²M near 0 Hz for free-free parts
        phi_r, shift_matrix, Cr, Lr = deflation
        rigid_rhs = phi_r.T @ rhs
        rhs = rhs - Mf @ phi_r @ rigid_rhs
        Kc = Kc + shift_matrix
    chunk = max(1, int(chunk_bytes // (3 * 16 * nf * nf)))
    sel = np.ix_(ok, ok)
    for start in range(0, f.size, chunk):  # loop over memory chunks, not over lines
        wc = w[start : start + chunk, None, None]
        D = Kc[None] + 1j * wc * Cf[None] - wc**2 * Mf[None]
        try:
            X = np.linalg.solve(D, np.broadcast_to(rhs, (D.shape[0],) + rhs.shape))
            if rigid_rhs is not None:
                Dr = 1j * Lr[None] + 1j * wc * Cr[None] - wc**2 * np.eye(Cr.shape[0])[None]
                X = X + phi_r[None] @ np.linalg.solve(Dr, np.broadcast_to(rigid_rhs, (D.shape[0],) + rigid_rhs.shape))
        except np.linalg.LinAlgError:
            raise NumericalError(
                f"dynamic stiffness is singular between {f[start]:g} and {f[min(start + chunk, f.size) - 1]:g} Hz "
                "(an undamped resonance exactly on a line?)"
            ) from None
        block = out[start : start + chunk]
        block[:, sel[0], sel[1]] = X[:, pos[ok], :]
    return out


def _rigid_deflation(K, M, C, L, phi_r):
    """Data to split the rigid-body motion off a direct solve, or None.

    When damping maps rigid-body modes ``Φ_r`` into ``M Φ_r`` (modal, hysteretic,
    mass- or stiffness-proportional damping; not a damper between ground and a
    free part), ``D(ω) Φ_r = M Φ_r (iL_r + iωC_r − ω²)``, and the response to
    ``F`` is exactly ``Φ_r a + u_e`` with ``(iL_r + iωC_r − ω²) a = Φ_rᵀ F`` and
    ``(D + s M Φ_r Φ_rᵀ M) u_e = (I − M Φ_r Φ_rᵀ) F`` for any shift ``s ≠ ω²``
    (here the median of diag K / diag M, far above the band of interest).
    """
    if phi_r.shape[1] == 0:
        return None
    mp = M @ phi_r
    Cr = phi_r.T @ C @ phi_r
    # rigid-body motion strains nothing, so it has no hysteretic loss (K_loss Φ_r = 0 up to
    # round-off, which must not leak into the rigid-body response as a spurious loss)
    Lr = np.zeros_like(Cr)
    for A, Ar in ((C, Cr), (L, Lr)):
        scale = float(np.abs(A).max(initial=0.0))
        if scale and np.abs(A @ phi_r - mp @ Ar).max() > 1e-9 * scale * np.abs(phi_r).max():
            return None
    # damping of the rigid-body motion (e.g. α M) is positive semi-definite: clip round-off
    ev, vec = np.linalg.eigh(0.5 * (Cr + Cr.T))
    Cr = (vec * np.clip(ev, 0.0, None)) @ vec.T
    d = np.diag(M)
    shift = float(np.median(np.diag(K)[d > 0] / d[d > 0]))
    return phi_r, shift * (mp @ mp.T), Cr, Lr


def frf_modal(matrices, freq_hz, dof_index, n_modes: int | None = None, residual: bool = True) -> np.ndarray:
    """Receptances by modal superposition with static residual compensation.

    ``H(ω) = Σ_r φ_r φ_rᵀ / (ω_r² + i κ_r + iω c_r − ω²) + R`` over the kept
    modes r, with modal damping ``c_r = φ_rᵀ C φ_r`` and loss ``κ_r = φ_rᵀ K_loss φ_r``
    (when the projected damping is not diagonal, the projected system is solved
    instead, batched over frequency). ``R`` is the static flexibility of the
    truncated modes: ``(K + iK_loss)⁻¹ − Σ_kept φφᵀ/(ω_r² + iκ_r)``; for a model
    with rigid-body modes the singular ``K`` is shifted by ``s M Φ_rb Φ_rbᵀ M``
    (which only moves the rigid-body modes to ω² = s, s = the lowest elastic
    eigenvalue), so ``R`` is the exact elastic flexibility of the truncated modes. Rigid-body modes enter as
    ``φφᵀ/(−ω²)``.

    Parameters
    ----------
    matrices, freq_hz, dof_index
        As for :func:`frf_direct`: the :class:`FEMatrices`, the frequencies [Hz] ``(n_freq,)``
        and the global DOF indices of outputs = inputs ``(m,)``.
    n_modes
        Number of lowest modes kept (default: all modes below 2 × max(freq)).
    residual
        Add the static residual (default True).

    Returns
    -------
    ndarray, complex, ``(n_freq, m, m)``.
    """
    f = _check_freq(freq_hz)
    if n_modes is None:
        lam, phi, n_rb = eigen_free(matrices, None, max_value=(2.0 * np.pi * 2.0 * f.max()) ** 2)
    else:
        if isinstance(n_modes, bool) or int(n_modes) < 1:
            raise InputError(f"n_modes must be >= 1, got {n_modes!r}")
        lam, phi, n_rb = eigen_free(matrices, int(n_modes))
        lam, phi = lam[: max(int(n_modes), n_rb)], phi[:, : max(int(n_modes), n_rb)]
    if n_rb and f.min() == 0.0:
        raise InputError(
            "the model has rigid-body modes, so its receptance at 0 Hz is infinite; "
            "start the frequency range above 0 Hz"
        )
    pos = _free_positions(matrices, dof_index)
    ok = pos >= 0
    out, Lm, _ = _modal_sum(matrices, f, lam, phi, n_rb, pos, ok, coupled="solve")
    if residual:
        out += _static_residual(matrices, lam, phi, n_rb, Lm, pos, ok)[None]
    return out


def _project(a, free, phi) -> np.ndarray:
    """``φᵀ A φ`` over the free DOFs; a zero matrix (no such damping) costs no product."""
    if not a.any():
        return np.zeros((phi.shape[1], phi.shape[1]))
    return phi.T @ (free_block(a, ~free) @ phi)


def _modal_sum(matrices, f, lam, phi, n_rb, pos, ok, coupled: str = "solve"):
    """Σ_r φ_r φ_rᵀ / (ω_r² + iκ_r + iωc_r − ω²) over the given modes, ``(n_freq, m, m)``.

    Returns ``(values, Lm, classical)``. When the projected damping is not
    diagonal (non-classical damping) the projected system is solved batched over
    frequency (``coupled="solve"``), or ``None`` is returned (``coupled="none"``).
    """
    free = ~matrices.fixed
    m = pos.size
    Cm, Lm = (_project(a, free, phi) for a in (matrices.C, matrices.K_loss))
    # rigid-body modes strain nothing: no hysteretic loss (drop round-off), and no
    # negative modal damping from round-off either
    Lm[:n_rb, :] = 0.0
    Lm[:, :n_rb] = 0.0
    Cm[np.diag_indices_from(Cm)] = np.clip(np.diag(Cm), 0.0, None)
    Lm[np.diag_indices_from(Lm)] = np.clip(np.diag(Lm), 0.0, None)
    phi_io = np.zeros((m, lam.size))
    phi_io[ok] = phi[pos[ok]]
    w = 2.0 * np.pi * f
    off = np.abs(Cm - np.diag(np.diag(Cm))).max(initial=0.0) + np.abs(Lm - np.diag(np.diag(Lm))).max(initial=0.0)
    diag_scale = np.abs(np.diag(Cm)).max(initial=0.0) + np.abs(np.diag(Lm)).max(initial=0.0)
    classical = off == 0.0 or off <= 1e-8 * diag_scale
    if classical:
        # den_fr = ω_r² − ω_f² + i(κ_r + ω_f c_r), written part by part (no complex temporaries)
        den = np.empty((f.size, lam.size), dtype=complex)
        np.subtract(lam[None, :], (w**2)[:, None], out=den.real)
        np.multiply(w[:, None], np.diag(Cm)[None, :], out=den.imag)
        den.imag += np.diag(Lm)[None, :]
        with np.errstate(divide="ignore", invalid="ignore"):
            np.reciprocal(den, out=den)
        # Σ_r φ_ir φ_jr / den_r for every line at once: one matrix product of the (n_freq × modes)
        # modal factors with the (modes × pairs i <= j) products of mode-shape entries (symmetric)
        iu, ju = np.triu_indices(m)
        sym = (den @ (phi_io[iu] * phi_io[ju]).T.astype(complex))
        out = np.empty((f.size, m, m), dtype=complex)
        out[:, iu, ju] = sym
        out[:, ju, iu] = sym
        if not np.all(np.isfinite(sym)):  # 1/0: a denominator vanished
            k = int(np.argwhere(~np.isfinite(sym))[0, 0])
            raise NumericalError(f"an undamped resonance lies exactly on the line {f[k]:g} Hz; add damping")
    elif coupled == "none":
        return None, Lm, False
    else:
        out = np.empty((f.size, m, m), dtype=complex)
        chunk = max(1, int(CHUNK_BYTES // (3 * 16 * max(1, lam.size) ** 2)))
        base = np.diag(lam) + 1j * Lm
        for start in range(0, f.size, chunk):  # memory chunks, not lines
            wc = w[start : start + chunk, None, None]
            D = base[None] + 1j * wc * Cm[None] - wc**2 * np.eye(lam.size)[None]
            q = np.linalg.solve(D, np.broadcast_to(phi_io.T, (D.shape[0],) + phi_io.T.shape))
            out[start : start + chunk] = phi_io[None] @ q
    return out, Lm, classical


def _static_residual(matrices, lam, phi, n_rb, Lm, pos, ok) -> np.ndarray:
    Kc = free_block(matrices.K, matrices.fixed) + 1j * free_block(matrices.K_loss, matrices.fixed)
    Mf = free_block(matrices.M, matrices.fixed)
    shift = 1.0
    if n_rb:
        # move the rigid-body modes to ω² = shift, of the order of the elastic ones (conditioning)
        if lam.size > n_rb:
            shift = float(lam[n_rb])
        else:
            d = np.diag(Mf)
            shift = float(np.median(np.diag(Kc).real[d > 0] / d[d > 0]))
        mp = Mf @ phi[:, :n_rb]
        Kc = Kc + shift * (mp @ mp.T)
    rhs = np.zeros((Kc.shape[0], int(ok.sum())))
    rhs[pos[ok], np.arange(rhs.shape[1])] = 1.0
    try:
        G = np.linalg.solve(Kc, rhs)[pos[ok]]
    except np.linalg.LinAlgError:
        raise NumericalError("static stiffness is singular; cannot form the residual flexibility") from None
    sub = phi[pos[ok]]
    kept = sub[:, n_rb:] / (lam[n_rb:] + 1j * np.diag(Lm)[n_rb:])[None, :]
    G = G - kept @ sub[:, n_rb:].T - sub[:, :n_rb] @ sub[:, :n_rb].T / shift
    m = pos.size
    out = np.zeros((m, m), dtype=complex)
    out[np.ix_(ok, ok)] = 0.5 * (G + G.T)
    return out
