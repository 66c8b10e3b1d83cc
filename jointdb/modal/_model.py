"""The modal model: poles and residues, FRF re-synthesis, state space, modal mass.

Receptance model (harmonic convention ``x = X e^{iωt}``, docs/theory.md §0)::

    H(ω) = Σ_r [ R_r / (iω − λ_r) + R_r* / (iω − λ_r*) ] + U + L / (iω)²

with poles ``λ_r = −ζ_r ω_r + i ω_r √(1 − ζ_r²)`` (``ω_r = 2π f_r``), complex
residue matrices ``R_r`` (n_out × n_in, units m/N · rad/s for translations),
an upper residual ``U`` (constant compliance of modes above the band, m/N) and a
lower residual ``L`` (mass line of modes below the band, m/N · (rad/s)²).
Mobility and accelerance are ``(iω)^p`` times this.

For a proportionally damped mode seen at a driving point,
``R_r = −i / (2 m_r ω_d)``: the modal mass follows from the residue
(Ewins, *Modal Testing*, 2nd ed., §2.3 and §4.4).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from jointdb.errors import InputError
from jointdb.frf import FRF, Dof, Quantity, dofs

__all__ = ["ModalModel", "single_dof_residue"]


def _readonly(a: np.ndarray) -> np.ndarray:
    a.setflags(write=False)
    return a


def single_dof_residue(freq_hz, zeta, stiffness) -> np.ndarray:
    """Residue ``R = −i/(2 m ω_d)`` of a driving-point mode with stiffness ``k`` [N/m].

    ``m = k / ω_n²`` (Ewins, *Modal Testing*, §2.3). Shapes broadcast.

    Parameters
    ----------
    freq_hz
        Undamped natural frequency f_n [Hz] (converted to ω_n = 2π f_n).
    zeta
        Viscous damping ratio ζ in [0, 1).
    stiffness
        Modal stiffness k [N/m].

    Returns
    -------
    ndarray
        Complex residue in m/N · rad/s (per rad/s, not per Hz), for
        ``H = R/(iω − λ) + R*/(iω − λ*)`` with ω in rad/s.
    """
    wn = 2 * np.pi * np.asarray(freq_hz, dtype=float)
    zeta = np.asarray(zeta, dtype=float)
    m = np.asarray(stiffness, dtype=float) / wn**2
    wd = wn * np.sqrt(1 - zeta**2)
    return -1j / (2 * m * wd)


@dataclass(frozen=True, eq=False)
class ModalModel:
    """Poles and residues of a set of modes on labelled output/input DOFs.

    Parameters
    ----------
    freq_hz
        Undamped natural frequencies ``f_r`` in Hz, shape ``(n_modes,)``, > 0.
    zeta
        Viscous damping ratios, shape ``(n_modes,)``, in [0, 1).
    residues
        Receptance residues ``R_r``, complex, shape ``(n_modes, n_out, n_in)``.
    outputs, inputs
        DOF labels.
    upper, lower
        Real residual terms, shape ``(n_out, n_in)`` (default zero); see module doc.

    Raises
    ------
    InputError
        On inconsistent shapes, non-positive frequencies or damping outside [0, 1).
    """

    freq_hz: np.ndarray
    zeta: np.ndarray
    residues: np.ndarray
    outputs: tuple[Dof, ...]
    inputs: tuple[Dof, ...]
    upper: np.ndarray | None = None
    lower: np.ndarray | None = None

    def __post_init__(self) -> None:
        f = np.atleast_1d(np.array(self.freq_hz, dtype=float))
        z = np.atleast_1d(np.array(self.zeta, dtype=float))
        outputs, inputs = dofs(self.outputs), dofs(self.inputs)
        r = np.array(self.residues, dtype=complex)
        if r.ndim <= 1 and len(outputs) == 1 and len(inputs) == 1:
            r = r.reshape(-1, 1, 1)
        shape = (f.size, len(outputs), len(inputs))
        if f.ndim != 1 or z.shape != f.shape or r.shape != shape:
            raise InputError(
                f"modal model shapes disagree: freq_hz {f.shape}, zeta {z.shape}, residues {r.shape}; "
                f"expected residues (n_modes, n_out, n_in) = {shape}"
            )
        if np.any(~np.isfinite(f)) or np.any(f <= 0):
            raise InputError("modal model: natural frequencies must be finite and > 0 Hz")
        if np.any(~np.isfinite(z)) or np.any(z < 0) or np.any(z >= 1):
            raise InputError("modal model: damping ratios must be in [0, 1)")
        zero = np.zeros(shape[1:])
        u = zero if self.upper is None else np.array(self.upper, dtype=float).reshape(shape[1:])
        low = zero if self.lower is None else np.array(self.lower, dtype=float).reshape(shape[1:])
        for name, v in (("freq_hz", f), ("zeta", z), ("residues", r), ("upper", u), ("lower", low)):
            object.__setattr__(self, name, _readonly(np.array(v)))
        object.__setattr__(self, "outputs", outputs)
        object.__setattr__(self, "inputs", inputs)

    # ------------------------------------------------------------ constructors
    @classmethod
    def from_modal_parameters(
        cls,
        freq_hz: Sequence[float],
        zeta: Sequence[float],
        stiffness: Sequence[float],
        dof: "Dof | str" = "1x",
    ) -> "ModalModel":
        """Driving-point model from modal stiffnesses ``k_r`` [N/m] (``m_r = k_r/ω_r²``).

        Parameters
        ----------
        freq_hz
            Natural frequencies [Hz], ``(n_modes,)``.
        zeta
            Damping ratios, ``(n_modes,)``.
        stiffness
            Modal stiffnesses k_r [N/m], ``(n_modes,)``.
        dof
            The driving-point DOF.

        Returns
        -------
        ModalModel
        """
        f = np.atleast_1d(np.asarray(freq_hz, dtype=float))
        r = single_dof_residue(f, zeta, stiffness)
        d = Dof.parse(dof)
        return cls(f, np.atleast_1d(zeta), np.asarray(r).reshape(-1, 1, 1), (d,), (d,))

    @staticmethod
    def block_diagonal(models: Sequence["ModalModel"]) -> "ModalModel":
        """Combine models of uncoupled directions (e.g. x and y at the tool tip) into one.

        Residue matrices are placed block-diagonally; cross terms are zero.

        Parameters
        ----------
        models
            :class:`ModalModel` s on disjoint DOFs.

        Returns
        -------
        ModalModel
        """
        if not models:
            raise InputError("block_diagonal needs at least one modal model")
        outs = tuple(d for m in models for d in m.outputs)
        ins = tuple(d for m in models for d in m.inputs)
        n_modes = sum(m.n_modes for m in models)
        res = np.zeros((n_modes, len(outs), len(ins)), dtype=complex)
        up = np.zeros((len(outs), len(ins)))
        lo = np.zeros((len(outs), len(ins)))
        k = o = i = 0
        for m in models:
            no, ni = len(m.outputs), len(m.inputs)
            res[k : k + m.n_modes, o : o + no, i : i + ni] = m.residues
            up[o : o + no, i : i + ni] = m.upper
            lo[o : o + no, i : i + ni] = m.lower
            k, o, i = k + m.n_modes, o + no, i + ni
        f = np.concatenate([m.freq_hz for m in models])
        z = np.concatenate([m.zeta for m in models])
        return ModalModel(f, z, res, outs, ins, up, lo)

    # --------------------------------------------------------------- derived
    @property
    def n_modes(self) -> int:
        return int(self.freq_hz.size)

    @property
    def poles(self) -> np.ndarray:
        """Complex poles ``λ_r = −ζω_r + iω_r√(1−ζ²)`` in rad/s, shape ``(n_modes,)``."""
        wn = 2 * np.pi * self.freq_hz
        return -self.zeta * wn + 1j * wn * np.sqrt(1 - self.zeta**2)

    def select(self, outputs=None, inputs=None) -> "ModalModel":
        """The same modes on a subset of DOFs.

        Parameters
        ----------
        outputs, inputs
            DOFs to keep (None: all).

        Returns
        -------
        ModalModel
        """
        oi = list(range(len(self.outputs))) if outputs is None else [self._pos(self.outputs, d, "output") for d in dofs(outputs)]
        ii = list(range(len(self.inputs))) if inputs is None else [self._pos(self.inputs, d, "input") for d in dofs(inputs)]
        return ModalModel(
            self.freq_hz,
            self.zeta,
            self.residues[:, oi][:, :, ii],
            tuple(self.outputs[i] for i in oi),
            tuple(self.inputs[i] for i in ii),
            self.upper[np.ix_(oi, ii)],
            self.lower[np.ix_(oi, ii)],
        )

    @staticmethod
    def _pos(labels, dof, kind) -> int:
        if dof not in labels:
            raise InputError(f"{kind} DOF {dof} is not in this modal model (it has: {' '.join(map(str, labels))})")
        return labels.index(dof)

    def synthesize(
        self, freq: Sequence[float] | np.ndarray, quantity: "str | Quantity" = "receptance", residuals: bool = True
    ) -> FRF:
        """Re-synthesise the FRF on a frequency grid in the given quantity.

        The lower residual is singular at 0 Hz: it is skipped on a 0 Hz line.

        Parameters
        ----------
        freq
            Frequencies [Hz], ``(n_freq,)``.
        quantity
            ``"receptance"``, ``"mobility"`` or ``"accelerance"``.
        residuals
            Add the upper and lower residuals.

        Returns
        -------
        FRF
            Shape ``(n_freq, n_out, n_in)``.
        """
        f = np.asarray(freq, dtype=float)
        q = Quantity.parse(quantity)
        iw = 1j * 2 * np.pi * f
        lam = self.poles
        g = 1.0 / (iw[:, None] - lam[None, :])  # (n_f, n_modes)
        gc = 1.0 / (iw[:, None] - lam.conj()[None, :])
        h = np.einsum("fr,rij->fij", g, self.residues) + np.einsum("fr,rij->fij", gc, self.residues.conj())
        if residuals:
            h = h + self.upper[None]
            with np.errstate(divide="ignore", invalid="ignore"):
                inv = np.where(f > 0, 1.0 / np.where(f > 0, iw, 1.0) ** 2, 0.0)
            h = h + inv[:, None, None] * self.lower[None]
        h = h * (iw**q.power)[:, None, None]
        return FRF(f, h, self.outputs, self.inputs, q)

    def modal_mass_stiffness(self, dof: "Dof | str | None" = None) -> dict[str, np.ndarray]:
        """Modal mass, stiffness and damping per mode at a driving point.

        Uses ``m_r = 1 / (2 ω_d |R_r|)`` (proportional damping, unit mode shape at
        the driving point), ``k_r = m_r ω_r²``, ``c_r = 2 ζ_r m_r ω_r``. Also
        returns ``nonproportionality = |Re R_r| / |R_r|`` (0 for a real mode).

        Parameters
        ----------
        dof
            The driving-point DOF (default: the only DOF that is both output and input).

        Returns
        -------
        dict of ndarray
            ``mass`` [kg], ``stiffness`` [N/m], ``damping`` [N·s/m], ``nonproportionality``,
            one value per mode.

        Raises
        ------
        InputError
            If ``dof`` is not both an output and an input of the model.
        """
        if dof is None:
            common = [d for d in self.outputs if d in self.inputs]
            if len(common) != 1:
                raise InputError("name the driving-point DOF: the model has " f"{len(common)} candidate DOFs")
            dof = common[0]
        d = Dof.parse(dof)
        r = self.residues[:, self._pos(self.outputs, d, "output"), self._pos(self.inputs, d, "input")]
        wn = 2 * np.pi * self.freq_hz
        wd = wn * np.sqrt(1 - self.zeta**2)
        m = 1.0 / (2 * wd * np.abs(r))
        return {
            "mass": m,
            "stiffness": m * wn**2,
            "damping": 2 * self.zeta * m * wn,
            "nonproportionality": np.abs(r.real) / np.abs(r),
        }

    def state_space(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """A real first-order realisation ``ẏ = A y + B F``, ``q = C y`` of the modal part.

        Per mode r and input j two states ``[Re z, Im z]`` with ``ż = λ_r z + F_j``;
        ``q = Σ 2 Re(R_r z)``. Residual terms are not realised (they have no
        dynamics); so ``C (iωI − A)⁻¹ B`` equals :meth:`synthesize` with
        ``residuals=False``. Shapes: A (n, n), B (n, n_in), C (n_out, n) with
        ``n = 2 · n_modes · n_in``; states of modes with zero residue columns are
        dropped.

        Returns
        -------
        A, B, C : ndarray
            Shapes ``(n, n)``, ``(n, n_in)``, ``(n_out, n)`` as above; ``q`` is the receptance
            response [m per N of input].
        """
        blocks_a, cols_b, rows_c = [], [], []
        n_in = len(self.inputs)
        for r, lam in enumerate(self.poles):
            for j in range(n_in):
                col = self.residues[r, :, j]
                if not np.any(col):
                    continue
                s, w = lam.real, lam.imag
                blocks_a.append(np.array([[s, -w], [w, s]]))
                b = np.zeros((2, n_in))
                b[0, j] = 1.0
                cols_b.append(b)
                rows_c.append(np.stack([2 * col.real, -2 * col.imag], axis=1))
        n = 2 * len(blocks_a)
        a = np.zeros((n, n))
        for k, blk in enumerate(blocks_a):
            a[2 * k : 2 * k + 2, 2 * k : 2 * k + 2] = blk
        b = np.concatenate(cols_b, axis=0) if cols_b else np.zeros((0, n_in))
        c = np.concatenate(rows_c, axis=1) if rows_c else np.zeros((len(self.outputs), 0))
        return a, b, c
