"""Shared pieces of coupling and identification: the joint-body and result types, block access, checks."""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from jointdb.coupling._linalg import Regularisation
from jointdb.errors import InputError, NumericalError
from jointdb.frf import FRF, Dof, Quantity, dofs, reciprocal_index

__all__ = [
    "IdentificationResult",
    "JointSubstructure",
    "fetch",
    "reciprocal_index",
    "as_receptance",
    "check_grid",
    "same_grid",
    "fill_bad_lines",
    "LazyExtra",
]


class LazyExtra(Mapping):
    """A read-only mapping whose values may be computed on first access (then kept).

    ``LazyExtra(values, deferred)``: ``values`` are stored as given; each
    ``deferred[name]`` is a function of no arguments called the first time
    ``name`` is read. Used for diagnostics that cost a decomposition of their
    own (e.g. the condition number of an intermediate matrix) so that
    identification does not pay for them unless they are looked at.
    """

    def __init__(self, values: Mapping[str, object], deferred: Mapping[str, Callable[[], object]]):
        self._values = dict(values)
        self._deferred = dict(deferred)

    def __getitem__(self, key: str) -> object:
        if key not in self._values and key in self._deferred:
            self._values[key] = self._deferred.pop(key)()
        return self._values[key]

    def __iter__(self) -> Iterator[str]:
        return iter(list(self._values) + [k for k in self._deferred if k not in self._values])

    def __len__(self) -> int:
        return len(self._values) + len(self._deferred)

    def __repr__(self) -> str:
        return f"LazyExtra({', '.join(self)})"


@dataclass(frozen=True)
class JointSubstructure:
    """A joint body with inertia (docs/theory.md §1b).

    Parameters
    ----------
    frf
        Free receptance of the joint body over (at least) ``a_side + b_side``
        DOFs, e.g. from a short free-free beam model of the joint segment.
    a_side, b_side
        The joint body's DOFs attached rigidly to the interface's ``a_dofs``
        and ``b_dofs`` respectively (same lengths, paired in order).
    """

    frf: FRF
    a_side: tuple[Dof, ...]
    b_side: tuple[Dof, ...]

    def __post_init__(self) -> None:
        object.__setattr__(self, "a_side", dofs(self.a_side))
        object.__setattr__(self, "b_side", dofs(self.b_side))
        if not isinstance(self.frf, FRF):
            raise InputError("JointSubstructure.frf must be an FRF container")


@dataclass(frozen=True, eq=False)
class IdentificationResult:
    """A joint identified by inverse receptance coupling, with its diagnostics.

    Attributes
    ----------
    joint
        The identified joint receptance (FRF). For the planar and n-point
        models it is the massless-joint ``H_J`` labelled with the A-side
        contact DOFs (pass it as ``Interface(..., joint=result.joint)``); for
        the full-matrix model it is the free receptance ``H^J`` of the joint
        body over ``a_dofs + b_dofs`` (use :meth:`joint_substructure`).
    model
        ``"planar"``, ``"n-point"`` or ``"matrix"``.
    residual
        ``(n_freq,)`` relative residual ``‖G_rec − G_meas‖ / ‖G_meas‖`` of the
        measured assembly FRFs re-coupled with the identified joint model.
    condition
        ``(n_freq,)`` condition number of the system solved at each line.
    unreliable
        ``(n_freq,)`` bool: lines flagged (ambiguous root, ill-conditioned,
        non-passive, or filled by interpolation).
    flags
        Named boolean arrays ``(n_freq,)`` explaining ``unreliable``.
    extra
        Model-specific arrays (e.g. ``"off_diagonal"`` residue for the
        n-point model, ``"full_joint"`` values before diagonalisation).
    settings
        The method's parameters (smoothing window, regularisation, ...).
    """

    joint: FRF
    model: str
    residual: np.ndarray
    condition: np.ndarray
    unreliable: np.ndarray
    flags: Mapping[str, np.ndarray] = field(default_factory=dict)
    extra: Mapping[str, object] = field(default_factory=dict)
    settings: Mapping[str, object] = field(default_factory=dict)

    @property
    def freq(self) -> np.ndarray:
        return self.joint.freq

    def joint_substructure(self):
        """The identified joint body as a :class:`~jointdb.coupling.JointSubstructure` (matrix model).

        Returns
        -------
        JointSubstructure
            Pass it as ``Interface(..., joint=...)``; InputError for a massless (planar or n-point) joint.
        """
        if self.model != "matrix":
            raise InputError(f"a {self.model} joint is massless; pass result.joint to Interface(joint=...)")
        n = len(self.joint.inputs) // 2
        return JointSubstructure(self.joint, self.joint.inputs[:n], self.joint.inputs[n:])

    def summary(self) -> dict:
        """Scalar reliability report: residual and condition statistics, flagged line counts.

        Returns
        -------
        dict
            ``model``, ``n_lines``, ``band_hz``, ``residual_median``/``_max``,
            ``condition_median``/``_max``, ``unreliable_lines`` and per-flag counts.
        """
        out: dict[str, object] = {
            "model": self.model,
            "n_lines": int(self.joint.n_freq),
            "band_hz": [float(self.freq[0]), float(self.freq[-1])],
            "residual_median": float(np.median(self.residual)),
            "residual_max": float(np.max(self.residual)),
            "condition_median": float(np.median(self.condition)),
            "condition_max": float(np.max(self.condition)),
            "unreliable_lines": int(np.count_nonzero(self.unreliable)),
        }
        for name, mask in self.flags.items():
            out[f"lines_{name}"] = int(np.count_nonzero(mask))
        if "off_diagonal" in self.extra:
            out["off_diagonal_median"] = float(np.median(np.asarray(self.extra["off_diagonal"])))
        return out


def as_receptance(name: str, frf: FRF) -> FRF:
    if not isinstance(frf, FRF):
        raise InputError(f"{name} must be an FRF container, got {type(frf).__name__}")
    try:
        return frf.to(Quantity.RECEPTANCE)
    except InputError as exc:
        raise InputError(f"{name}: {exc}") from None


def check_grid(ref_name: str, ref: np.ndarray, name: str, freq: np.ndarray) -> None:
    """InputError unless ``freq`` equals the reference grid ``ref`` (Hz) to 1e-9 relative."""
    if freq is ref or (freq.shape == ref.shape and np.array_equal(freq, ref)):
        return
    if freq.shape != ref.shape or not np.allclose(freq, ref, rtol=1e-9, atol=1e-12):
        raise InputError(
            f"{name} has {freq.size} lines {freq[0]:g}–{freq[-1]:g} Hz but {ref_name} has "
            f"{ref.size} lines {ref[0]:g}–{ref[-1]:g} Hz; resample onto one frequency grid first"
        )


def same_grid(named: Mapping[str, FRF]) -> np.ndarray:
    """The common frequency grid of the named FRFs (InputError naming the first that differs)."""
    items = list(named.items())
    ref_name, ref = items[0]
    for name, frf in items[1:]:
        check_grid(ref_name, ref.freq, name, frf.freq)
    return ref.freq


def _run(idx: np.ndarray) -> "slice | None":
    """``idx`` as a slice when it is a run of consecutive integers."""
    if idx.size and np.array_equal(idx, np.arange(idx[0], idx[0] + idx.size)):
        return slice(int(idx[0]), int(idx[0]) + idx.size)
    return None


def fetch(
    name: str, frf: FRF, outs: Sequence[Dof], ins: Sequence[Dof], need: str = "", view: bool = False
) -> np.ndarray:
    """Block of ``frf`` on outs × ins, using reciprocity entry by entry where needed.

    A new array; with ``view=True`` a read-only view of ``frf.values`` (or of
    its transpose) when the block is one contiguous rectangle there, so that
    nothing is copied.
    """
    index, missing = reciprocal_index(frf, outs, ins)
    if missing is not None:
        o, i = missing
        hint = f" ({need})" if need else ""
        raise InputError(
            f"{name} has no FRF between {o} and {i}{hint}; it has outputs "
            f"{' '.join(map(str, frf.outputs))} and inputs {' '.join(map(str, frf.inputs))}"
        )
    rows, cols = index
    if view and rows.size:
        for r, c, flip in ((rows, cols, False), (cols.T, rows.T, True)):  # direct, or all by reciprocity
            if (r == r[:, :1]).all() and (c == c[:1, :]).all():
                rs, cs = _run(r[:, 0]), _run(c[0, :])
                if rs is not None and cs is not None:
                    block = frf.values[:, rs, cs]
                    return np.swapaxes(block, 1, 2) if flip else block
    return frf.values[:, rows, cols]


def fill_bad_lines(values: np.ndarray, bad: np.ndarray, freq: np.ndarray, what: str) -> np.ndarray:
    """Replace lines where ``bad`` (or values non-finite) by interpolation over good lines."""
    flat = values.reshape(values.shape[0], -1)
    bad = bad | ~np.all(np.isfinite(flat), axis=1)
    if not bad.any():
        return values
    good = ~bad
    if not good.any():
        raise NumericalError(f"{what}: no frequency line gave a finite, reliable result")
    out = flat.copy()
    for k in range(flat.shape[1]):  # loop over matrix entries, not frequency lines
        out[bad, k] = np.interp(freq[bad], freq[good], flat[good, k].real) + 1j * np.interp(
            freq[bad], freq[good], flat[good, k].imag
        )
    return out.reshape(values.shape)


def solver_settings(reg: Regularisation, smoothing: "int | None", smoothing_order: int, symmetrize: bool) -> dict:
    """The pseudo-inverse and smoothing options as an identification records them in ``settings``."""
    return {"regularisation": f"{reg.method}:{reg.rel:g}", "smoothing": smoothing,
            "smoothing_order": smoothing_order, "symmetrize": symmetrize}


def require_determined(cond: np.ndarray, limit: float, matrix: str, remedy: str) -> None:
    """NumericalError when ``matrix`` is singular at every line (``cond > limit`` everywhere).

    Parameters
    ----------
    cond
        Condition number per line, ``(n_freq,)``.
    limit
        The condition number above which a line counts as singular.
    matrix, remedy
        What is singular (e.g. ``"H_IC (measured DOFs × contact DOFs)"``) and what follows
        for the user, for the message.
    """
    if np.all(cond > limit):
        raise NumericalError(f"{matrix} is singular at every line (condition > {limit:g}); {remedy}")


def receptances_on_one_grid(assembly: FRF, substructure_a: FRF, substructure_b: FRF) -> tuple:
    """The common grid and the three FRFs as receptances: ``(freq, G, A, B)`` (InputError naming the one
    that is not an FRF, cannot be converted or lies on another grid)."""
    G = as_receptance("assembly", assembly)
    A = as_receptance("substructure A", substructure_a)
    B = as_receptance("substructure B", substructure_b)
    return same_grid({"assembly": G, "substructure A": A, "substructure B": B}), G, A, B
