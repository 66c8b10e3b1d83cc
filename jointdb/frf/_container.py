"""The :class:`FRF` container: validated, read-only values on labelled DOFs."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np

from jointdb.errors import InputError
from jointdb.frf._indexing import _check_labels, _take, reciprocal_index
from jointdb.frf._labels import Dof, Quantity, dofs

__all__ = ["FRF"]


def _readonly(a: np.ndarray) -> np.ndarray:
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class FRF:
    """A set of frequency response functions on labelled DOFs.

    Parameters
    ----------
    freq
        Frequencies in Hz, shape ``(n_freq,)``, finite, >= 0, strictly increasing.
    values
        Complex FRF values, shape ``(n_freq, n_out, n_in)``. A 1-D array of length
        ``n_freq`` is accepted for a single output/input pair.
    outputs, inputs
        DOF labels of the rows (responses) and columns (excitations); no duplicates.
    quantity
        Receptance (m/N, rad/N, m/(N·m), rad/(N·m)), mobility or accelerance.

    Raises
    ------
    InputError
        On wrong shapes, NaN/inf, non-increasing or negative frequencies,
        duplicate or unknown DOFs, or an unknown quantity.

    Examples
    --------
    The receptance of a 1 kg mass on a 1 MN/m spring (natural frequency 159.15 Hz), then the
    same as mobility (``iω`` times it) and one entry picked by its labels:

    >>> import numpy as np
    >>> from jointdb import FRF
    >>> freq = np.array([0.0, 100.0, 200.0])                    # Hz
    >>> w = 2 * np.pi * freq
    >>> h = FRF(freq, 1 / (1e6 - 1.0 * w**2), outputs=["1x"], inputs=["1x"])
    >>> h.shape, h.quantity.value
    ((3, 1, 1), 'receptance')
    >>> np.round(h.entry("1x", "1x").real * 1e6, 4)            # µm/N: 1 / (1 − (f/fn)²)
    array([ 1.    ,  1.6523, -1.7267])
    >>> bool(np.allclose(h.to("mobility").values[:, 0, 0], 1j * w * h.values[:, 0, 0]))
    True
    >>> [str(dof) for dof in h.outputs]
    ['1x']
    """

    freq: np.ndarray
    values: np.ndarray
    outputs: tuple[Dof, ...]
    inputs: tuple[Dof, ...]
    quantity: Quantity = Quantity.RECEPTANCE
    _index: dict = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        freq = np.array(self.freq, dtype=np.float64, copy=True)
        if freq.ndim != 1 or freq.size == 0:
            raise InputError(f"frequencies must be a non-empty 1-D array, got shape {freq.shape}")
        if not np.all(np.isfinite(freq)):
            raise InputError("frequencies contain NaN or inf")
        if freq[0] < 0:
            raise InputError(f"frequencies must be >= 0 Hz, first is {freq[0]:g}")
        if freq.size > 1 and not np.all(np.diff(freq) > 0):
            bad = int(np.argmax(~(np.diff(freq) > 0)))
            raise InputError(
                f"frequencies must be strictly increasing; line {bad + 1} ({freq[bad + 1]:g} Hz) "
                f"does not exceed line {bad} ({freq[bad]:g} Hz)"
            )
        outputs = dofs(self.outputs)
        inputs = dofs(self.inputs)
        _check_labels(outputs, inputs)
        values = np.array(self.values, dtype=np.complex128, copy=True)
        if values.ndim == 1 and len(outputs) == 1 and len(inputs) == 1:
            values = values.reshape(-1, 1, 1)
        expected = (freq.size, len(outputs), len(inputs))
        if values.shape != expected:
            raise InputError(
                f"FRF values have shape {values.shape}, expected (n_freq, n_out, n_in) = {expected}"
            )
        if not np.all(np.isfinite(values)):
            n_bad = int(np.count_nonzero(~np.isfinite(values)))
            raise InputError(f"FRF values contain {n_bad} NaN or inf entries")
        self._set(_readonly(freq), values, outputs, inputs, Quantity.parse(self.quantity))

    @classmethod
    def _trusted(
        cls, freq: np.ndarray, values: np.ndarray, outputs: tuple, inputs: tuple, quantity: Quantity
    ) -> "FRF":
        """An FRF from parts that are valid by construction, without copying or re-checking them.

        For results computed inside the package: ``freq`` is the (read-only,
        already validated) grid of an existing FRF or a subset of it, ``values``
        a new complex128 array of the right shape owned by the caller (it is
        made read-only, not copied), ``outputs``/``inputs`` tuples of
        :class:`Dof` (checked: non-empty, distinct — cheap) and ``quantity`` a
        :class:`Quantity`. Public constructors (``FRF(...)``, :meth:`replace`)
        validate everything.
        """
        _check_labels(outputs, inputs)
        if values.dtype != np.complex128 or values.shape != (freq.size, len(outputs), len(inputs)):
            raise ValueError(  # a programming error inside the package, never user input
                f"internal FRF: values {values.dtype} {values.shape} do not match "
                f"({freq.size}, {len(outputs)}, {len(inputs)})"
            )
        self = object.__new__(cls)
        self._set(freq if not freq.flags.writeable else _readonly(freq), values, outputs, inputs, quantity)
        return self

    def _set(self, freq: np.ndarray, values: np.ndarray, outputs: tuple, inputs: tuple, quantity: Quantity) -> None:
        """Store checked fields on this frozen instance (``values`` made read-only) and index the labels."""
        object.__setattr__(self, "freq", freq)
        object.__setattr__(self, "values", _readonly(values))
        object.__setattr__(self, "outputs", outputs)
        object.__setattr__(self, "inputs", inputs)
        object.__setattr__(self, "quantity", quantity)
        index = {"out": {d: i for i, d in enumerate(outputs)}, "in": {d: i for i, d in enumerate(inputs)}}
        object.__setattr__(self, "_index", index)

    # ----------------------------------------------------------------- basics
    @property
    def omega(self) -> np.ndarray:
        """Angular frequencies 2πf in rad/s, shape ``(n_freq,)``."""
        return 2.0 * np.pi * self.freq

    @property
    def n_freq(self) -> int:
        return self.freq.size

    @property
    def shape(self) -> tuple[int, int, int]:
        return self.values.shape  # type: ignore[return-value]

    def __repr__(self) -> str:
        return (
            f"FRF({self.quantity.value}, {self.n_freq} lines {self.freq[0]:g}–{self.freq[-1]:g} Hz, "
            f"outputs=[{' '.join(map(str, self.outputs))}], inputs=[{' '.join(map(str, self.inputs))}])"
        )

    def replace(self, **changes) -> "FRF":
        """A new FRF with some fields replaced (validated again).

        Parameters
        ----------
        **changes
            ``freq``, ``values``, ``outputs``, ``inputs`` or ``quantity``.

        Returns
        -------
        FRF
        """
        kwargs = dict(
            freq=self.freq, values=self.values, outputs=self.outputs, inputs=self.inputs, quantity=self.quantity
        )
        kwargs.update(changes)
        return FRF(**kwargs)

    def allclose(self, other: "FRF", rtol: float = 1e-10, atol: float = 0.0) -> bool:
        """Same labels, quantity and grid, and values equal within tolerances.

        Parameters
        ----------
        other
            The FRF to compare with.
        rtol, atol
            Relative and absolute tolerance on the values (as :func:`numpy.allclose`;
            ``atol`` in the FRF's units).

        Returns
        -------
        bool
        """
        return (
            self.outputs == other.outputs
            and self.inputs == other.inputs
            and self.quantity == other.quantity
            and self.freq.shape == other.freq.shape
            and np.allclose(self.freq, other.freq, rtol=1e-12, atol=0)
            and np.allclose(self.values, other.values, rtol=rtol, atol=atol)
        )

    # ---------------------------------------------------------------- indexing
    def _positions(self, which: str, labels: Iterable) -> list[int]:
        index = self._index[which]
        out = []
        for label in dofs(labels):
            if label not in index:
                have = " ".join(str(d) for d in index)
                kind = "output" if which == "out" else "input"
                raise InputError(f"{kind} DOF {label} is not in this FRF (it has: {have})")
            out.append(index[label])
        return out

    def select(self, outputs: Iterable | None = None, inputs: Iterable | None = None) -> "FRF":
        """Sub-FRF on the given output and input DOFs (in the order given).

        Parameters
        ----------
        outputs, inputs
            DOF labels to keep (None: all).

        Returns
        -------
        FRF
            Shape ``(n_freq, len(outputs), len(inputs))``.

        Raises
        ------
        InputError
            If a requested DOF is not present.
        """
        oi = self._positions("out", outputs) if outputs is not None else list(range(len(self.outputs)))
        ii = self._positions("in", inputs) if inputs is not None else list(range(len(self.inputs)))
        out_labels = tuple(self.outputs[i] for i in oi)
        in_labels = tuple(self.inputs[i] for i in ii)
        return FRF._trusted(self.freq, _take(self.values, oi, ii), out_labels, in_labels, self.quantity)

    def block(self, outputs: Iterable, inputs: Iterable) -> np.ndarray:
        """Values on the given DOFs as a new array ``(n_freq, len(outputs), len(inputs))``.

        Parameters
        ----------
        outputs, inputs
            DOF labels.

        Returns
        -------
        ndarray, complex

        Raises
        ------
        InputError
            If a requested DOF is not present.
        """
        return _take(self.values, self._positions("out", outputs), self._positions("in", inputs))

    def entry(self, output, input) -> np.ndarray:  # noqa: A002 - field's own word
        """One FRF ``H[output, input]`` as an array ``(n_freq,)``.

        Parameters
        ----------
        output, input
            One DOF label each (text, pair or :class:`Dof`).

        Returns
        -------
        ndarray, complex, shape (n_freq,)
        """
        return self.block([output], [input])[:, 0, 0]

    # ------------------------------------------------------------- conversion
    def to(self, quantity: "str | Quantity") -> "FRF":
        """Convert exactly to another quantity: ``(iω)^p`` factors.

        Converting *from* mobility or accelerance to receptance divides by
        ``(iω)^p``, undefined at 0 Hz: a 0 Hz line is refused in that case.

        Parameters
        ----------
        quantity
            ``"receptance"``, ``"mobility"`` or ``"accelerance"``.

        Returns
        -------
        FRF
            This FRF itself when it already is that quantity, else the values times ``(iω)^p``.

        Raises
        ------
        InputError
            When a division at 0 Hz would be needed.
        """
        target = Quantity.parse(quantity)
        dp = target.power - self.quantity.power
        if dp == 0:
            return self
        iw = 1j * self.omega
        if dp < 0 and self.freq[0] == 0.0:
            raise InputError(
                f"cannot convert {self.quantity.value} to {target.value} at 0 Hz "
                "(division by iω); drop the 0 Hz line first, e.g. frf.band(fmin=...)"
            )
        factor = iw**dp
        values = self.values * factor[:, None, None]
        if not np.all(np.isfinite(values)):  # (iω)^p can overflow extreme values
            n_bad = int(np.count_nonzero(~np.isfinite(values)))
            raise InputError(
                f"FRF values contain {n_bad} NaN or inf entries after converting {self.quantity.value} "
                f"to {target.value} (values too large)"
            )
        return FRF._trusted(self.freq, values, self.outputs, self.inputs, target)

    def band(self, fmin: float | None = None, fmax: float | None = None) -> "FRF":
        """The lines with ``fmin <= f <= fmax``.

        Parameters
        ----------
        fmin, fmax
            Band limits [Hz]; None: unbounded on that side.

        Returns
        -------
        FRF
            Same DOFs and quantity, on the lines in the band only.

        Raises
        ------
        InputError
            No line in the band.
        """
        mask = np.ones(self.n_freq, dtype=bool)
        if fmin is not None:
            mask &= self.freq >= fmin
        if fmax is not None:
            mask &= self.freq <= fmax
        if not mask.any():
            raise InputError(f"no frequency lines in [{fmin}, {fmax}] Hz")
        return FRF._trusted(self.freq[mask], self.values[mask], self.outputs, self.inputs, self.quantity)

    def resample(self, freq: Sequence[float] | np.ndarray) -> "FRF":
        """Linear interpolation (real and imaginary parts) onto another grid.

        Parameters
        ----------
        freq
            The new lines [Hz], ``(n,)``, within this FRF's range.

        Returns
        -------
        FRF
            ``(n, n_out, n_in)``, same DOFs and quantity.

        Raises
        ------
        InputError
            If the new grid reaches outside ``[freq[0], freq[-1]]`` (no
            extrapolation).
        """
        new = np.asarray(freq, dtype=np.float64)
        if new.ndim != 1 or new.size == 0:
            raise InputError("the new frequency grid must be a non-empty 1-D array")
        lo, hi = self.freq[0], self.freq[-1]
        tol = 1e-9 * max(abs(hi), 1.0)
        if new.min() < lo - tol or new.max() > hi + tol:
            raise InputError(
                f"resampling to {new.min():g}–{new.max():g} Hz would extrapolate beyond the "
                f"measured {lo:g}–{hi:g} Hz"
            )
        new = np.clip(new, lo, hi)
        flat = self.values.reshape(self.n_freq, -1)
        out = np.empty((new.size, flat.shape[1]), dtype=np.complex128)
        for k in range(flat.shape[1]):  # loop over FRF entries, not frequency lines
            out[:, k] = np.interp(new, self.freq, flat[:, k].real) + 1j * np.interp(new, self.freq, flat[:, k].imag)
        return self.replace(freq=new, values=out.reshape(new.size, *self.values.shape[1:]))

    def complete_reciprocal(self, outputs: Iterable | None = None, inputs: Iterable | None = None) -> "FRF":
        """FRF on the requested DOFs, filling missing entries by reciprocity ``H_ij = H_ji``.

        Parameters
        ----------
        outputs, inputs
            Target DOFs. By default the square set over the union of this
            FRF's output and input DOFs. A measured row (one output, many
            inputs) becomes a column with ``outputs=row.inputs, inputs=row.outputs``.
            Where an entry is present directly it is kept as measured.

        Returns
        -------
        FRF
            ``(n_freq, len(outputs), len(inputs))`` on the target DOFs.

        Raises
        ------
        InputError
            If some requested entry is known neither directly nor by reciprocity.
        """
        union: list[Dof] = list(self.outputs) + [d for d in self.inputs if d not in self._index["out"]]
        target_out = dofs(outputs) if outputs is not None else tuple(union)
        target_in = dofs(inputs) if inputs is not None else tuple(union)
        _check_labels(target_out, target_in)
        index, missing = reciprocal_index(self, target_out, target_in)
        if missing is not None:
            raise InputError(
                f"H[{missing[0]}, {missing[1]}] is known neither directly nor by reciprocity; "
                "measure a row or column that covers it"
            )
        vals = self.values[:, index[0], index[1]]
        return FRF._trusted(self.freq, vals, target_out, target_in, self.quantity)

    def reciprocity_error(self) -> float:
        """Largest relative asymmetry ``|H_ij − H_ji| / max|H|`` over common DOFs.

        Returns
        -------
        float
            0 for an FRF without two common DOFs.
        """
        common = [d for d in self.outputs if d in self._index["in"]]
        if len(common) < 2:
            return 0.0
        h = self.block(common, common)
        scale = np.max(np.abs(h)) or 1.0
        return float(np.max(np.abs(h - np.swapaxes(h, 1, 2))) / scale)

    @staticmethod
    def concat_outputs(parts: Sequence["FRF"]) -> "FRF":
        """Stack FRFs with the same grid, inputs and quantity along outputs.

        Parameters
        ----------
        parts
            The FRFs, in order, each ``(n_freq, n_out_k, n_in)``.

        Returns
        -------
        FRF
            ``(n_freq, sum of n_out_k, n_in)``, outputs in the order given.
        """
        return _concat(parts, along="outputs")

    @staticmethod
    def concat_inputs(parts: Sequence["FRF"]) -> "FRF":
        """Stack FRFs along inputs (the columns); :meth:`concat_outputs` stacks rows.

        Parameters
        ----------
        parts
            The FRFs, in order: each ``(n_freq, n_out, n_in_k)`` with the same
            frequencies, outputs and quantity.

        Returns
        -------
        FRF
            ``(n_freq, n_out, sum of n_in_k)``: the columns of
            ``parts[0]``, then those of ``parts[1]``, and so on.
        """
        return _concat(parts, along="inputs")


def _concat(parts: Sequence[FRF], along: str) -> FRF:
    """Stack FRFs along ``"outputs"`` or ``"inputs"``; the other labels, grid and quantity must agree."""
    if not parts:
        raise InputError("nothing to stack: give at least one FRF")
    shared = "inputs" if along == "outputs" else "outputs"
    first = parts[0]
    for p in parts[1:]:
        if (
            getattr(p, shared) != getattr(first, shared)
            or p.quantity != first.quantity
            or not np.array_equal(p.freq, first.freq)
        ):
            raise InputError(f"FRFs to stack must share frequencies, {shared} and quantity")
    stacked = tuple(d for p in parts for d in getattr(p, along))
    values = np.concatenate([p.values for p in parts], axis=1 if along == "outputs" else 2)
    if along == "outputs":
        return FRF._trusted(first.freq, values, stacked, first.inputs, first.quantity)
    return FRF._trusted(first.freq, values, first.outputs, stacked, first.quantity)
