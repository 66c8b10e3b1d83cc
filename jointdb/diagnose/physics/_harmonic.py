"""Amplitude-dependent joints line by line: single-harmonic balance on a few joint DOFs.

A micro-slip joint does not have one stiffness per excitation level: near a
resonance the slip amplitude is large and the joint soft and lossy, away from
it the joint is nearly linear. With a force of amplitude ``F`` at an input, the
steady single-harmonic response at each line is found by a fixed point on the
joint's stiffness (the describing function of the law), batched over lines:

1. receptances of the *linear* model (the joint at its small-amplitude
   stiffness ``k₀ (1 + iη₀)``) at the outputs, the inputs and the joint's
   relative DOFs ``B q`` (rows: relative deflection / rotation of the two sides);
2. at every line, ``a_j = F |(B q)_j|`` gives the slip amplitude of each
   joint row; the law gives ``k_j(a) (1 + iη(a))``; the change
   ``Δk_j = k(a)(1+iη(a)) − k₀(1+iη₀)`` enters exactly by a low-rank
   (Woodbury) update ``H = H₀ − H₀Bᵀ Δk (I + B H₀ Bᵀ Δk)⁻¹ B H₀``;
3. iterate 2 with relaxation until the amplitudes settle.

Every input column is solved with its own force at its own input (a tap test
drives one point at a time).
"""

from __future__ import annotations

import numpy as np

__all__ = ["JointRows", "harmonic_balance_receptance"]

#: Fixed-point iterations and relaxation of the harmonic balance.
HB_ITERATIONS = 25
#: Stop when the stiffness update is below this fraction of the largest small-amplitude stiffness.
HB_TOL = 1e-4
HB_RELAX = 0.6


class JointRows:
    """Relative DOFs of a joint: ``B`` rows over global DOFs, their small-amplitude stiffness and
    which slip measure (group) each row follows.

    Parameters
    ----------
    pairs
        ``[(dof_a, dof_b), ...]``: the row measures ``q[dof_a] − q[dof_b]``.
    stiffness
        ``(n_rows,)`` small-amplitude stiffness of each row (N/m or N·m/rad).
    group
        ``(n_rows,)`` index of the slip measure of each row.
    amplitude_weight
        ``(n_rows,)`` metres of slip per unit of the row (1 for deflections,
        a radius for rotations); a group's slip amplitude is the sum of
        ``weight × |row|`` over its rows.
    """

    def __init__(self, pairs, stiffness, group, amplitude_weight):
        self.pairs = list(pairs)
        self.stiffness = np.asarray(stiffness, dtype=float)
        self.group = np.asarray(group, dtype=int)
        self.weight = np.asarray(amplitude_weight, dtype=float)

    @property
    def dofs(self) -> list[int]:
        return list(dict.fromkeys(d for p in self.pairs for d in p))


def harmonic_balance_receptance(mats, freq_hz, out_dofs, in_dofs, rows: JointRows, force: float, law,
                                eta0: float, n_modes: int | None = None, linear: np.ndarray | None = None
                                ) -> np.ndarray:
    """Receptance ``(n_freq, n_out, n_in)`` with an amplitude-dependent joint (see the module docstring).

    Parameters
    ----------
    mats
        :class:`jointdb.fe.FEMatrices` of the model with the joint at ``k₀ (1 + iη₀)``.
    freq_hz
        ``(n_freq,)`` lines [Hz].
    out_dofs, in_dofs
        Global DOF indices of the outputs and inputs.
    rows
        The joint's relative DOFs (:class:`JointRows`).
    force
        Excitation amplitude [N] at each input.
    law
        ``law(r) -> (s, η)``: stiffness scale and loss factor at slip amplitude ``r`` [m]
        (arrays, broadcast).
    eta0
        The loss factor already in ``mats`` for the joint.
    linear
        The linear model's receptance over ``out_dofs + in_dofs + rows.dofs`` (duplicates
        removed, in that order), if already computed (it does not depend on the force).
    """
    from jointdb.fe import frf_modal

    every = list(dict.fromkeys(list(out_dofs) + list(in_dofs) + rows.dofs))
    H = linear if linear is not None else frf_modal(mats, freq_hz, every, n_modes=n_modes)
    idx = {d: i for i, d in enumerate(every)}
    a = np.array([idx[p[0]] for p in rows.pairs])
    b = np.array([idx[p[1]] for p in rows.pairs])
    n_b = a.size
    oi = [idx[d] for d in out_dofs]
    Hrow = H[:, a, :] - H[:, b, :]                        # B H      (n_freq, n_b, n_every)
    HbB = Hrow[:, :, a] - Hrow[:, :, b]                   # B H Bᵀ   (n_freq, n_b, n_b)
    Hob = H[:, oi][:, :, a] - H[:, oi][:, :, b]           # H Bᵀ at the outputs
    n_groups = int(rows.group.max()) + 1
    k0 = rows.stiffness * (1 + 1j * eta0)
    eye = np.eye(n_b)[None]
    cols = []
    for d_in in in_dofs:
        hbi = Hrow[:, :, idx[d_in]]                        # (n_freq, n_b)
        dk = np.zeros((len(freq_hz), n_b), dtype=complex)
        for _ in range(HB_ITERATIONS):
            xb = np.linalg.solve(eye + HbB * dk[:, None, :], hbi[:, :, None])[:, :, 0]   # B q per unit force
            amp = np.zeros((n_groups, len(freq_hz)))
            np.add.at(amp, rows.group, (rows.weight[None] * np.abs(xb)).T)
            s, eta = law(force * amp.T[:, rows.group])
            target = rows.stiffness[None] * s * (1 + 1j * eta) - k0[None]
            step = target - dk
            dk = dk + HB_RELAX * step
            if np.max(np.abs(step)) <= HB_TOL * np.max(np.abs(k0)):
                break
        corr = np.linalg.solve(eye + HbB * dk[:, None, :], hbi[:, :, None])[:, :, 0]
        cols.append(H[:, oi, idx[d_in]] - np.einsum("for,fr->fo", Hob, dk * corr))
    return np.stack(cols, axis=2)
