"""Receptances of small discrete models from (K, M, C) matrices.

Used for monolithic reference models, synthetic campaigns and benchmarks:
``H(ω) = (K + iωC − ω²M)⁻¹`` (docs/theory.md §0), batched over frequency.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from jointdb.errors import InputError
from jointdb.frf import FRF, Dof, Quantity, dofs

__all__ = ["receptance_from_matrices", "add_spring", "model_matrices", "merge_matrices"]


def receptance_from_matrices(
    freq_hz: "Sequence[float] | np.ndarray",
    K: np.ndarray,
    M: np.ndarray,
    labels: "Sequence[Dof | str]",
    C: np.ndarray | None = None,
    outputs: "Sequence[Dof | str] | None" = None,
    inputs: "Sequence[Dof | str] | None" = None,
) -> FRF:
    """Receptance FRF ``(K + iωC − ω²M)⁻¹`` restricted to outputs × inputs.

    Parameters
    ----------
    freq_hz
        Lines in Hz, ``(n_freq,)``.
    K, M, C
        Real or complex ``(n, n)`` stiffness (may carry hysteretic loss as an
        imaginary part), mass and viscous damping matrices.
    labels
        DOF label of each of the ``n`` matrix rows.
    outputs, inputs
        Subsets of ``labels`` (default: all).

    Returns
    -------
    FRF
        Receptance, shape ``(n_freq, n_out, n_in)``. Solved for the requested
        input columns only.
    """
    labels = dofs(labels)
    K = np.asarray(K)
    M = np.asarray(M)
    n = len(labels)
    if K.shape != (n, n) or M.shape != (n, n):
        raise InputError(f"K {K.shape} and M {M.shape} must both be ({n}, {n}) to match the labels")
    C = np.zeros((n, n)) if C is None else np.asarray(C)
    index = {d: i for i, d in enumerate(labels)}
    out = dofs(outputs) if outputs is not None else labels
    inp = dofs(inputs) if inputs is not None else labels
    try:
        oi = [index[d] for d in out]
        ii = [index[d] for d in inp]
    except KeyError as exc:
        raise InputError(f"DOF {exc.args[0]} is not among the model labels") from None
    f = np.asarray(freq_hz, dtype=float)
    w = 2 * np.pi * f
    z = K[None] + 1j * w[:, None, None] * C[None] - (w**2)[:, None, None] * M[None]
    rhs = np.zeros((n, len(ii)), dtype=complex)
    rhs[ii, np.arange(len(ii))] = 1.0
    x = np.linalg.solve(z, np.broadcast_to(rhs, (f.size, n, len(ii))))
    return FRF(f, x[:, oi, :], out, inp, Quantity.RECEPTANCE)


def add_spring(
    K: np.ndarray, C: np.ndarray, i: int, j: int | None, k: "float | complex", c: float = 0.0
) -> None:
    """Add a spring–damper between matrix rows ``i`` and ``j`` (``None``: ground), in place."""
    K[i, i] += k
    C[i, i] += c
    if j is not None:
        K[j, j] += k
        K[i, j] -= k
        K[j, i] -= k
        C[j, j] += c
        C[i, j] -= c
        C[j, i] -= c


def model_matrices(model, node_offset: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, tuple[Dof, ...]]:
    """Free-DOF matrices of a :class:`jointdb.fe.BeamModel` with measurement labels.

    Returns ``(K + i·K_loss, M, C, labels)`` over the unconstrained DOFs. Mesh
    nodes at a named point are labelled with the point's node number; the
    others ``node_offset + mesh index`` (so that two models can be merged
    without label clashes). Used to build monolithic reference models.
    """
    fm = model.assemble()
    free = ~np.asarray(fm.fixed, dtype=bool)
    named = {}
    for p in model.points:
        named[int(np.argmin(np.abs(fm.node_positions - p.position)))] = p.node
    labels = tuple(Dof(named.get(d.node, node_offset + d.node), d.direction) for d in fm.dof_labels)
    K = fm.K + 1j * fm.K_loss
    ix = np.ix_(free, free)
    return K[ix], fm.M[ix], fm.C[ix], tuple(lab for lab, f in zip(labels, free) if f)


def merge_matrices(*parts):
    """Block-diagonal merge of ``(K, M, C, labels)`` tuples."""
    n = sum(p[0].shape[0] for p in parts)
    K = np.zeros((n, n), dtype=complex)
    M = np.zeros((n, n))
    C = np.zeros((n, n))
    labels: list[Dof] = []
    o = 0
    for k, m, c, lab in parts:
        s = slice(o, o + k.shape[0])
        K[s, s], M[s, s], C[s, s] = k, m, c
        labels += list(lab)
        o += k.shape[0]
    if len(set(labels)) != len(labels):
        raise InputError("merged models have clashing DOF labels; use different node offsets / point nodes")
    return K, M, C, tuple(labels)
