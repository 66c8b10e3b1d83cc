"""Output-error identification of joints: fit the joint's parameters to the measured assembly FRFs.

The per-line IRC (:mod:`jointdb.coupling._planar`, ``_multi``, ``_matrix``) solves the coupling
equations exactly at every line, so measurement noise goes straight into the joint and
the fit quality cannot be judged (an exactly determined problem reproduces any data).
Here a small parametric joint (constant or smoothly frequency-dependent k, c per DOF; or a
joint body K, D, M) is fitted to all lines at once by weighted least squares on the
coupled-minus-measured assembly FRFs, started from the IRC estimate. The Jacobian and the
residual variance give each parameter's standard error and their correlation.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from jointdb.coupling._common import as_receptance, fetch
from jointdb.coupling._kc import fit_constant_kc
from jointdb.coupling._oe_core import (
    JointBodyModel,
    OutputErrorResult,
    SpringDamperModel,
    coupled_blocks,
    fit,
)
from jointdb.errors import InputError, NumericalError
from jointdb.frf import FRF, Dof, dofs

__all__ = [
    "OutputErrorResult",
    "fit_planar_joint",
    "fit_n_point_joints",
    "fit_joint_matrix",
    "sigma_from_coherence",
    "mean_and_sigma_of_repeats",
]


def sigma_from_coherence(frf: FRF, coherence: np.ndarray, n_averages: int) -> np.ndarray:
    """Standard deviation of an H1 estimate from its coherence (random error of averaged FRFs).

    ``σ ≈ |H| √(1 − γ²) / (|γ| √(2 n_avg))`` per line and entry.

    Parameters
    ----------
    frf
        The averaged FRF, values (nf, no, ni).
    coherence
        Ordinary coherence γ² in [0, 1], same shape as ``frf.values``.
    n_averages
        Number of averaged taps (≥ 1).

    Returns
    -------
    ndarray, shape (n_freq, n_out, n_in)
        Standard deviation of each FRF value (the FRF's units), floored at 1e-4 of ``|H|``.

    Raises
    ------
    InputError
        Shape mismatch, coherence outside [0, 1], n_averages < 1.
    """
    g2 = np.asarray(coherence, float)
    if g2.shape != frf.values.shape:
        raise InputError(f"coherence has shape {g2.shape}, the FRF {frf.values.shape}; give one value per entry")
    if np.any(~np.isfinite(g2)) or np.any((g2 < 0) | (g2 > 1)):
        raise InputError("coherence must be in [0, 1] (it is γ², not γ in %)")
    if int(n_averages) < 1:
        raise InputError(f"n_averages must be >= 1, got {n_averages}")
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.abs(frf.values) * np.sqrt((1 - g2) / np.maximum(g2, 1e-12)) / np.sqrt(2 * int(n_averages))
    # a perfect coherence would give zero weight-defining spread: floor at 1e-4 relative
    return np.maximum(s, 1e-4 * np.abs(frf.values) + 1e-300)


def mean_and_sigma_of_repeats(repeats: Sequence[FRF]) -> tuple[FRF, np.ndarray]:
    """Mean FRF of repeated taps and the standard deviation of that mean, per line and entry.

    Parameters
    ----------
    repeats
        Two or more FRFs of the same test, on one grid with the same labels.

    Returns
    -------
    mean : FRF
        The mean of the repeats.
    sigma : ndarray, shape (n_freq, n_out, n_in)
        Standard deviation of the mean (same units as the FRF), floored at 1e-6 of ``|mean|``.

    Raises
    ------
    InputError
        Fewer than 2 repeats, or repeats on different grids/labels.
    """
    if len(repeats) < 2:
        raise InputError(f"the spread of repeated taps needs at least 2 repeats, got {len(repeats)}")
    first = repeats[0]
    for k, r in enumerate(repeats[1:], 1):
        if r.values.shape != first.values.shape or not np.allclose(r.freq, first.freq) or (
                r.outputs, r.inputs) != (first.outputs, first.inputs):
            raise InputError(f"repeat {k} differs from repeat 0 in grid or DOF labels")
    stack = np.stack([r.values for r in repeats])
    mean = stack.mean(axis=0)
    n = stack.shape[0]
    sd = np.sqrt(np.sum(np.abs(stack - mean) ** 2, axis=0) / (n - 1) / n)
    return first.replace(values=mean), np.maximum(sd, 1e-6 * np.abs(mean) + 1e-300)


def _sigma(measured: np.ndarray, sigma: "np.ndarray | None") -> np.ndarray:
    if sigma is None:  # relative error model: the scale is re-estimated from the residual
        return np.abs(measured)
    s = np.asarray(sigma, float)
    if s.shape != measured.shape:
        raise InputError(f"sigma has shape {s.shape}; expected {measured.shape} (one per line and entry)")
    return s


def _band_mask(freq: np.ndarray, band) -> np.ndarray:
    if band is None:
        return np.ones(freq.size, bool)
    m = (freq >= band[0]) & (freq <= band[1])
    if np.count_nonzero(m) < 3:
        raise InputError(f"band {band[0]:g}–{band[1]:g} Hz holds {np.count_nonzero(m)} lines; need at least 3")
    return m


def _multi_start(model, blocks, measured, s, k0, c0, entries) -> OutputErrorResult:
    """Fit from the IRC start and from two damping guesses; keep the lowest cost.

    In log-parameters the misfit flattens out as a damping goes to zero (``∂z/∂log c = iωc``),
    so a per-line estimate that is far too small can strand the fit there; a start with more
    damping (×5, and a loss factor of 1 % at mid-band) avoids that. Stiffnesses start from IRC.
    """
    k0, c0 = np.abs(np.asarray(k0, float)), np.asarray(c0, float)
    w_mid = 2 * np.pi * float(np.mean(blocks.freq))
    starts = [c0, 5 * np.abs(c0), 0.01 * k0 / w_mid]
    best = None
    for c in starts:
        try:
            res = fit(model, blocks, measured, s, model.start(k0, c), entries)
        except NumericalError:
            continue
        if best is None or res.cost < best.cost:
            best = res
    if best is None:
        raise NumericalError("output-error fit: the coupled model is singular at every start point")
    return best


def _fit_springs(blocks, measured, sigma, labels, k0, c0, order, band, settings) -> OutputErrorResult:
    use = _band_mask(blocks.freq, band)
    s = np.where(use[:, None, None], _sigma(measured, sigma), np.inf)
    model = SpringDamperModel(dofs(labels), int(order))
    if model.order < 0:
        raise InputError(f"order must be >= 0 (0 = constant k, c), got {order}")
    res = _multi_start(model, blocks, measured, s, k0, c0, None)
    object.__setattr__(res, "settings", {**settings, "order": model.order,
                                          "band_hz": None if band is None else [float(band[0]), float(band[1])]})
    return res


def fit_planar_joint(
    assembly: FRF,
    substructure_a: FRF,
    a_point: int,
    substructure_b: FRF,
    b_contact: int,
    b_tip: int,
    *,
    translation: str = "x",
    rotation: str = "ry",
    start: "tuple[Sequence[float], Sequence[float]] | None" = None,
    sigma: "np.ndarray | None" = None,
    order: int = 0,
    band: "tuple[float, float] | None" = None,
) -> OutputErrorResult:
    """Output-error fit of a planar spring–damper joint (k, c in translation and rotation).

    Fits ``G_11`` (tip direct) and ``G_12`` (tip response, force at B's contact point),
    the same two FRFs the per-line IRC uses, over all lines at once.

    Parameters
    ----------
    assembly, substructure_a, a_point, substructure_b, b_contact, b_tip, translation, rotation
        As :func:`~jointdb.coupling.identify_planar_joint`.
    start
        ``(k, c)`` start values (2 each); default: the per-line IRC's constant fit on its
        reliable lines.
    sigma
        Standard deviation of the two measured FRFs, shape ``(n_freq, 1, 2)`` (see
        :func:`sigma_from_coherence`, :func:`mean_and_sigma_of_repeats`); default a relative
        error model ``σ ∝ |G|`` whose scale is estimated from the residual.
    order
        0: constant k, c; ``n`` > 0: log k, log c are degree-n polynomials in frequency.
    band
        ``(f_min, f_max)`` Hz of the lines fitted (default all).

    Returns
    -------
    OutputErrorResult
        Parameters ``k 3x, c 3x, k 3ry, c 3ry`` (for ``a_point`` 3) with standard errors,
        covariance (of the log-parameters) and correlation.

    Raises
    ------
    InputError
        Missing DOFs, grid mismatch, bad ``sigma`` shape.
    """
    t, r = translation, rotation
    a_dofs = [Dof(a_point, t), Dof(a_point, r)]
    blocks = coupled_blocks({"A": substructure_a, "B": substructure_b}, "A", a_dofs, "B",
                            [Dof(b_contact, t), Dof(b_contact, r)],
                            [("B", Dof(b_tip, t))], [("B", Dof(b_tip, t)), ("B", Dof(b_contact, t))])
    g = as_receptance("assembly", assembly)
    measured = fetch("assembly", g, [Dof(b_tip, t)], [Dof(b_tip, t), Dof(b_contact, t)])
    if g.freq.shape != blocks.freq.shape or not np.allclose(g.freq, blocks.freq, rtol=1e-9):
        raise InputError("assembly and substructures are on different frequency grids; resample first")
    if start is None:
        from jointdb.coupling._planar import identify_planar_joint

        irc = identify_planar_joint(assembly, substructure_a, a_point, substructure_b, b_contact, b_tip,
                                    translation=t, rotation=r)
        kc = fit_constant_kc(irc.joint, band, mask=~irc.unreliable)
        start = (kc.k, np.abs(kc.c))
    return _fit_springs(blocks, measured, sigma, a_dofs, start[0], start[1], order, band,
                        {"model": "planar", "a_point": a_point, "b_contact": b_contact, "b_tip": b_tip,
                         "translation": t, "rotation": r})


def fit_n_point_joints(
    assembly: FRF,
    substructure_a: FRF,
    internal: Sequence["Dof | str"],
    a_contact: Sequence["Dof | str"],
    substructure_b: FRF,
    b_contact: Sequence["Dof | str"],
    *,
    start: "tuple[Sequence[float], Sequence[float]] | None" = None,
    sigma: "np.ndarray | None" = None,
    order: int = 0,
    band: "tuple[float, float] | None" = None,
) -> OutputErrorResult:
    """Output-error fit of n translational spring–dampers between two bodies.

    Fits the measured m×m assembly FRFs on A's ``internal`` DOFs (the data of
    :func:`~jointdb.coupling.identify_n_point_joints`).

    Parameters
    ----------
    assembly, substructure_a, internal, a_contact, substructure_b, b_contact
        As :func:`~jointdb.coupling.identify_n_point_joints`.
    sigma
        Standard deviation of the measured block, shape ``(n_freq, m, m)``; default ``σ ∝ |G|``.
    start
        ``(k, c)`` per spring; default: the per-line IRC's constant fit.
    order, band
        As :func:`fit_planar_joint`.

    Returns
    -------
    OutputErrorResult
        ``k``, ``c`` per spring (labelled by ``a_contact``) with standard errors.

    Raises
    ------
    InputError
        Missing DOFs, grid mismatch, fewer measured DOFs than springs.
    """
    inner, ca, cb = dofs(internal), dofs(a_contact), dofs(b_contact)
    if len(inner) < len(ca):
        raise InputError(f"{len(ca)} springs need at least {len(ca)} measured DOFs on A, got {len(inner)}")
    blocks = coupled_blocks({"A": substructure_a, "B": substructure_b}, "A", ca, "B", cb,
                            [("A", d) for d in inner], [("A", d) for d in inner])
    g = as_receptance("assembly", assembly)
    measured = fetch("assembly", g, inner, inner)
    if g.freq.shape != blocks.freq.shape or not np.allclose(g.freq, blocks.freq, rtol=1e-9):
        raise InputError("assembly and substructures are on different frequency grids; resample first")
    if start is None:
        from jointdb.coupling._multi import identify_n_point_joints

        irc = identify_n_point_joints(assembly, substructure_a, inner, ca, substructure_b, cb)
        kc = fit_constant_kc(irc.joint, band, mask=~irc.unreliable)
        start = (np.abs(kc.k), np.abs(kc.c))
    # the measured block is symmetric: fit each reciprocal pair once (upper triangle)
    entries = np.triu(np.ones((len(inner), len(inner)), bool))
    use = _band_mask(blocks.freq, band)
    s = np.where(use[:, None, None], _sigma(measured, sigma), np.inf)
    model = SpringDamperModel(ca, int(order))
    res = _multi_start(model, blocks, measured, s, start[0], start[1], entries)
    object.__setattr__(res, "settings", {"model": "n-point", "order": model.order,
                                          "band_hz": None if band is None else [float(band[0]), float(band[1])]})
    return res


def fit_joint_matrix(
    assembly: FRF,
    substructures: Mapping[str, FRF],
    measured: Sequence[tuple[str, "Dof | str"]],
    a: str,
    a_dofs: Sequence["Dof | str"],
    b: str,
    b_dofs: Sequence["Dof | str"],
    *,
    start: "np.ndarray | None" = None,
    sigma: "np.ndarray | None" = None,
    band: "tuple[float, float] | None" = None,
) -> OutputErrorResult:
    """Output-error fit of a joint body with inertia: symmetric K, D (hysteretic) and M over a_dofs + b_dofs.

    Parameters
    ----------
    assembly, substructures, a, a_dofs, b, b_dofs
        As :func:`~jointdb.coupling.identify_joint_matrix`.
    measured
        ``(name, Dof)`` of the L measured DOFs (on ``a`` or ``b``); the L×L block is fitted.
    start
        θ start (upper triangles of K, D, M); default from the per-line IRC joint body's
        impedance (least squares over the band).
    sigma
        Standard deviation of the measured L×L block ``(n_freq, L, L)``; default ``σ ∝ |G|``.
    band
        ``(f_min, f_max)`` [Hz] of the lines fitted; default all.

    Returns
    -------
    OutputErrorResult
        Entries of K, D, M with standard errors (linear parameters).

    Raises
    ------
    InputError
        Missing DOFs, grid mismatch.
    """
    pairs = [(str(n), Dof.parse(d)) for n, d in measured]
    blocks = coupled_blocks(substructures, a, a_dofs, b, b_dofs, pairs, pairs)
    g = as_receptance("assembly", assembly)
    labels = [d for _, d in pairs]
    meas = fetch("assembly", g, labels, labels)
    model = JointBodyModel(dofs(list(a_dofs) + list(b_dofs)))
    use = _band_mask(blocks.freq, band)
    if start is None:
        from jointdb.coupling._matrix import identify_joint_matrix

        irc = identify_joint_matrix(assembly, substructures, pairs, a, a_dofs, b, b_dofs)
        ok = use & ~irc.unreliable
        ok = ok if np.count_nonzero(ok) >= 3 else use
        z = np.linalg.inv(irc.joint.values[ok])
        start = model.start_from_impedance(blocks.freq[ok], z)
    entries = np.triu(np.ones((len(labels), len(labels)), bool))
    s = np.where(use[:, None, None], _sigma(meas, sigma), np.inf)
    res = fit(model, blocks, meas, s, np.asarray(start, float), entries)
    object.__setattr__(res, "settings", {"model": "matrix",
                                          "band_hz": None if band is None else [float(band[0]), float(band[1])]})
    return res
