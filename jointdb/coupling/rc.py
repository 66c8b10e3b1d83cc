"""Forward receptance coupling (RC): LM-FBS with flexible interfaces.

docs/theory.md §1a/§1b. Any number of substructures (FRF containers) are joined
through any number of interfaces. An interface pairs contact DOFs of two
substructures and is

* rigid (``joint=None``): ``u_a − u_b = 0``;
* a massless joint with receptance ``H_J(ω)`` (diagonal or full):
  ``u_a − u_b = H_J λ`` (§1a);
* a joint body with inertia (:class:`JointSubstructure`): the joint's own
  free receptance over its two end-node DOF sets, rigidly attached to both
  sides (§1b). It is handled as an extra substructure with two rigid
  interfaces, which is algebraically the same as
  ``G = H − H_:C (H_CC + H^J)⁻¹ H_C:``.

Only the requested outputs and inputs are computed:

    G_oi = H_oi − H_oC Bᵀ (B H_CC Bᵀ + H_J)⁻¹ B H_Ci

batched over frequency, where ``C`` are the contact DOFs only (never the full
assembled matrix).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from jointdb.coupling._common import JointSubstructure, reciprocal_index
from jointdb.coupling._common import as_receptance as _receptance
from jointdb.coupling._common import check_grid as _check_grid
from jointdb.errors import InputError, NumericalError
from jointdb.frf import FRF, Dof, Quantity, dofs

__all__ = ["Interface", "JointSubstructure", "couple", "spring_damper_joint"]


@dataclass(frozen=True)
class Interface:
    """One interface between substructures ``a`` and ``b``.

    Parameters
    ----------
    a, b
        Names of the substructures (keys of the ``substructures`` mapping).
    a_dofs, b_dofs
        Contact DOFs on each side, paired in order (same length ``n``). The
        joint force acts ``+λ`` on ``b`` and ``−λ`` on ``a``.
    joint
        ``None`` for a rigid joint; an :class:`~jointdb.frf.FRF` (``n × n``
        receptance, m/N, rad/(N·m), ...) or an array of shape
        ``(n_freq, n, n)`` or ``(n, n)`` for a massless joint with
        ``u_a − u_b = H_J λ``; or a :class:`JointSubstructure` for a joint
        with inertia. An FRF joint whose input labels equal ``a_dofs`` or
        ``b_dofs`` (as sets) is reordered to match; otherwise its rows and
        columns are taken in the order of ``a_dofs``.
    """

    a: str
    a_dofs: tuple[Dof, ...]
    b: str
    b_dofs: tuple[Dof, ...]
    joint: "None | FRF | np.ndarray | JointSubstructure" = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "a_dofs", dofs(self.a_dofs))
        object.__setattr__(self, "b_dofs", dofs(self.b_dofs))
        if len(self.a_dofs) != len(self.b_dofs):
            raise InputError(
                f"interface {self.a}–{self.b}: {len(self.a_dofs)} DOFs on {self.a} but "
                f"{len(self.b_dofs)} on {self.b}; contact DOFs are paired one to one"
            )
        if not self.a_dofs:
            raise InputError(f"interface {self.a}–{self.b} has no contact DOFs")
        for name, side in ((self.a, self.a_dofs), (self.b, self.b_dofs)):
            if len(set(side)) != len(side):
                raise InputError(
                    f"interface {self.a}–{self.b}: a contact DOF on {name} is listed twice "
                    f"({' '.join(map(str, side))}); each DOF is paired once"
                )
        if isinstance(self.joint, JointSubstructure) and len(self.joint.a_side) != len(self.a_dofs):
            raise InputError(
                f"interface {self.a}–{self.b}: joint body has {len(self.joint.a_side)} DOFs on side a, "
                f"interface has {len(self.a_dofs)}"
            )
        if isinstance(self.joint, JointSubstructure) and len(self.joint.b_side) != len(self.b_dofs):
            raise InputError(
                f"interface {self.a}–{self.b}: joint body has {len(self.joint.b_side)} DOFs on side b, "
                f"interface has {len(self.b_dofs)}"
            )


def spring_damper_joint(
    freq_hz: "Sequence[float] | np.ndarray",
    k: "float | Sequence[float]",
    c: "float | Sequence[float]",
    dofs_: "Sequence[Dof | str]",
) -> FRF:
    """Diagonal receptance of independent spring–dampers, ``1/(k + iωc)``.

    Parameters
    ----------
    freq_hz
        Frequency lines in Hz, shape ``(n_freq,)``.
    k, c
        Stiffness (N/m or N·m/rad) and viscous damping (N·s/m or N·m·s/rad)
        per DOF; scalars are broadcast.
    dofs_
        DOF labels of the joint (typically the ``a_dofs`` of the interface).

    Returns
    -------
    FRF
        Receptance ``(n_freq, n, n)``, diagonal, docs/theory.md §1a.

    Raises
    ------
    InputError
        If lengths differ, a stiffness is not positive or a damping negative.
    """
    labels = dofs(dofs_)
    n = len(labels)
    k_arr = np.broadcast_to(np.asarray(k, dtype=float), (n,)) if np.ndim(k) == 0 else np.asarray(k, float)
    c_arr = np.broadcast_to(np.asarray(c, dtype=float), (n,)) if np.ndim(c) == 0 else np.asarray(c, float)
    if k_arr.shape != (n,) or c_arr.shape != (n,):
        raise InputError(f"spring_damper_joint: {n} DOFs but {k_arr.size} stiffnesses and {c_arr.size} dampings")
    if np.any(~np.isfinite(k_arr)) or np.any(k_arr <= 0):
        raise InputError(f"spring_damper_joint: stiffness must be finite and > 0, got {k_arr.tolist()}")
    if np.any(~np.isfinite(c_arr)) or np.any(c_arr < 0):
        raise InputError(f"spring_damper_joint: damping must be finite and >= 0, got {c_arr.tolist()}")
    f = np.asarray(freq_hz, dtype=float)
    if f.ndim != 1:
        raise InputError(f"spring_damper_joint: freq_hz must be a 1-D array of lines in Hz, got shape {f.shape}")
    omega = 2 * np.pi * f
    z = k_arr[None, :] + 1j * omega[:, None] * c_arr[None, :]
    values = np.zeros((f.size, n, n), dtype=complex)
    idx = np.arange(n)
    values[:, idx, idx] = 1.0 / z
    return FRF(f, values, labels, labels, Quantity.RECEPTANCE)


# --------------------------------------------------------------------- helpers
def _as_pairs(items, what: str) -> list[tuple[str, Dof]]:
    out = []
    for item in items:
        if not (isinstance(item, (tuple, list)) and len(item) == 2):
            raise InputError(f"{what} must be (substructure name, DOF) pairs, got {item!r}")
        out.append((str(item[0]), Dof.parse(item[1])))
    return out


def _gather(name: str, frf: FRF, outs: Sequence[Dof], ins: Sequence[Dof]) -> np.ndarray:
    """Block ``outs × ins`` of a substructure's receptance in one gather, by reciprocity where needed."""
    oidx, iidx = frf._index["out"], frf._index["in"]
    for d in list(outs) + list(ins):
        if d not in oidx and d not in iidx:
            raise InputError(
                f"substructure {name!r} has no FRF for DOF {d} "
                f"(it has: {' '.join(str(x) for x in dict.fromkeys(frf.outputs + frf.inputs))})"
            )
    index, missing = reciprocal_index(frf, outs, ins)
    if missing is not None:
        raise InputError(
            f"substructure {name!r}: H[{missing[0]}, {missing[1]}] is known neither directly nor by "
            "reciprocity; measure a row or column that covers it"
        )
    return frf.values[:, index[0], index[1]]


def _span(idx: np.ndarray) -> "slice | np.ndarray":
    """A slice when ``idx`` is a run of consecutive integers (basic indexing: no gather), else ``idx``."""
    if idx.size and np.array_equal(idx, np.arange(idx[0], idx[0] + idx.size)):
        return slice(int(idx[0]), int(idx[0]) + idx.size)
    return idx


def _at(rows: np.ndarray, cols: np.ndarray):
    """Index of the ``rows × cols`` sub-block of the last two axes (slices where possible)."""
    r, c = _span(rows), _span(cols)
    if isinstance(r, slice) or isinstance(c, slice):
        return (slice(None), r, c)
    return (slice(None), r[:, None], c[None, :])


def _joint_matrix(iface: Interface, freq: np.ndarray, label: str) -> np.ndarray | None:
    """The (n_freq, n, n) joint receptance of a massless-joint interface (None if rigid)."""
    n = len(iface.a_dofs)
    j = iface.joint
    if j is None:
        return None
    if isinstance(j, FRF):
        j = _receptance(f"joint of {label}", j)
        _check_grid("the substructures", freq, f"joint of {label}", j.freq)
        if len(j.outputs) != n or len(j.inputs) != n:
            raise InputError(f"joint of {label} is {len(j.outputs)}×{len(j.inputs)}, the interface has {n} DOFs")
        for side in (iface.a_dofs, iface.b_dofs):
            if j.inputs == side and j.outputs == side:
                return j.values  # already in interface order (read-only; only read)
            if set(j.inputs) == set(side) and set(j.outputs) == set(side):
                return j.block(side, side)
        return np.asarray(j.values)
    arr = np.asarray(j, dtype=complex)
    if arr.shape == (n, n):
        arr = np.broadcast_to(arr, (freq.size, n, n))
    if arr.shape != (freq.size, n, n):
        raise InputError(f"joint of {label} has shape {arr.shape}, expected ({freq.size}, {n}, {n}) or ({n}, {n})")
    if not np.all(np.isfinite(arr)):
        raise InputError(f"joint of {label} contains NaN or inf")
    return arr


def couple(
    substructures: Mapping[str, FRF],
    interfaces: Sequence[Interface],
    outputs: Sequence[tuple[str, "Dof | str"]],
    inputs: Sequence[tuple[str, "Dof | str"]] | None = None,
) -> FRF:
    """Assembled receptances of substructures joined through interfaces.

    LM-FBS with flexible interfaces (docs/theory.md §1a, §1b; thesis eq. 4.1–4.8):

        G_oi = H_oi − H_oC Bᵀ (B H_CC Bᵀ + H_J)⁻¹ B H_Ci

    with ``B`` the signed Boolean matrix over the contact DOFs only, ``H``
    block-diagonal over substructures and ``H_J`` block-diagonal over
    interfaces (zero for rigid ones). Batched over frequency; only the
    requested ``outputs × inputs`` block is formed.

    Parameters
    ----------
    substructures
        Name → FRF (receptance, mobility or accelerance; converted to
        receptance). Each must contain (directly or by reciprocity) its contact
        DOFs and the requested output/input DOFs. All on one frequency grid.
    interfaces
        :class:`Interface` objects; any number, any mix of rigid, massless and
        inertial joints. Several interfaces may touch the same DOF.
    outputs, inputs
        ``(substructure name, DOF)`` pairs; ``inputs`` default to ``outputs``.

    Returns
    -------
    FRF
        Receptance ``(n_freq, len(outputs), len(inputs))`` labelled with the
        given DOFs (they must therefore be distinct across substructures).

    Raises
    ------
    InputError
        Unknown substructure names or DOFs, grid mismatches, duplicate output
        labels.
    NumericalError
        If the interface matrix ``B H_CC Bᵀ + H_J`` is singular at some line
        (e.g. rigidly coupling two rigid-body DOFs with no flexibility).

    Examples
    --------
    A mass ``m1`` on a spring ``k`` to ground (node 1) and a free mass ``m2`` (node 2). Joined
    rigidly they are one mass ``m1 + m2`` on the spring; joined by a spring ``kj`` they are the
    two-mass chain, whose driving-point receptance at 1 is
    ``(kj − m2ω²) / ((k + kj − m1ω²)(kj − m2ω²) − kj²)``:

    >>> import numpy as np
    >>> from jointdb import FRF
    >>> from jointdb.coupling import Interface, couple, spring_damper_joint
    >>> freq = np.array([10.0, 50.0, 100.0, 400.0])            # Hz
    >>> w = 2 * np.pi * freq
    >>> k, kj, m1, m2 = 1e6, 2e6, 2.0, 0.5                      # N/m, N/m, kg, kg
    >>> A = FRF(freq, (1 / (k - m1 * w**2))[:, None, None], ["1x"], ["1x"])
    >>> B = FRF(freq, (-1 / (m2 * w**2))[:, None, None], ["2x"], ["2x"])
    >>> rigid = couple({"A": A, "B": B}, [Interface("A", ["1x"], "B", ["2x"])], outputs=[("A", "1x")])
    >>> rigid.shape
    (4, 1, 1)
    >>> bool(np.allclose(rigid.values[:, 0, 0], 1 / (k - (m1 + m2) * w**2)))
    True
    >>> spring = spring_damper_joint(freq, kj, 0.0, ["1x"])
    >>> G = couple({"A": A, "B": B}, [Interface("A", ["1x"], "B", ["2x"], joint=spring)],
    ...            outputs=[("A", "1x"), ("B", "2x")], inputs=[("A", "1x")])
    >>> expected = (kj - m2 * w**2) / ((k + kj - m1 * w**2) * (kj - m2 * w**2) - kj**2)
    >>> bool(np.allclose(G.entry("1x", "1x"), expected))
    True
    """
    subs, freq = _receptances(substructures)
    flat = _flatten(interfaces, subs, freq)
    outs = _as_pairs(outputs, "outputs")
    ins = outs if inputs is None else _as_pairs(inputs, "inputs")
    for which, pairs in (("output", outs), ("input", ins)):
        for name, _ in pairs:
            if name not in substructures:
                raise InputError(f"{which} substructure {name!r} is unknown (have: {', '.join(substructures)})")
        labels = [d for _, d in pairs]
        if len(set(labels)) != len(labels):
            raise InputError(
                f"{which} DOF labels must be distinct across substructures (got "
                f"{', '.join(f'{n}:{d}' for n, d in pairs)}); give the substructures distinct node numbers"
            )
    z, u, v, g = _interface_problem(subs, flat, freq, outs, ins)
    # Interface problem: Z λ = V,  G = H_oi − U λ.
    try:
        lam = np.linalg.solve(z, v)
    except np.linalg.LinAlgError:
        raise NumericalError(
            "the interface matrix B H_CC Bᵀ + H_J is singular at some frequency line; "
            "check for redundant interfaces or rigid couplings between rigid-body DOFs"
        ) from None
    g -= u @ lam
    if not np.all(np.isfinite(g)):
        raise NumericalError("coupling produced NaN/inf: the interface matrix is singular at some line")
    return FRF._trusted(freq, g, tuple(d for _, d in outs), tuple(d for _, d in ins), Quantity.RECEPTANCE)


def _receptances(substructures: Mapping[str, FRF]) -> tuple[dict[str, FRF], np.ndarray]:
    """The substructures as receptances by name, and their common grid (InputError otherwise)."""
    if not isinstance(substructures, Mapping):
        raise InputError(f"couple: substructures must be a mapping name -> FRF, got {type(substructures).__name__}")
    if not substructures:
        raise InputError("couple: no substructures given")
    subs: dict[str, FRF] = {}
    for name, frf in substructures.items():
        if not isinstance(frf, FRF):
            raise InputError(f"substructure {name!r} must be an FRF container, got {type(frf).__name__}")
        subs[str(name)] = _receptance(f"substructure {name!r}", frf)
    ref_name = next(iter(subs))
    freq = subs[ref_name].freq
    for name, frf in subs.items():
        _check_grid(f"substructure {ref_name!r}", freq, f"substructure {name!r}", frf.freq)
    return subs, freq


def _flatten(interfaces: Sequence[Interface], subs: dict[str, FRF], freq: np.ndarray) -> list[tuple[Interface, str]]:
    """The interfaces with each joint body expanded into an extra substructure (added to ``subs``)
    with two rigid interfaces; each with its label for messages."""
    ref_name = next(iter(subs))
    flat: list[tuple[Interface, str]] = []
    for k, iface in enumerate(interfaces):
        if not isinstance(iface, Interface):
            raise InputError(f"interfaces[{k}] must be an Interface, got {type(iface).__name__}")
        label = f"interfaces[{k}] ({iface.a}–{iface.b})"
        for side in (iface.a, iface.b):
            if side not in subs:
                raise InputError(f"{label}: unknown substructure {side!r} (have: {', '.join(subs)})")
        if iface.a == iface.b:
            raise InputError(f"{label}: a substructure cannot be coupled to itself")
        if isinstance(iface.joint, JointSubstructure):
            jname = f"<joint {k}>"
            jfrf = _receptance(f"joint body of {label}", iface.joint.frf)
            _check_grid(f"substructure {ref_name!r}", freq, f"joint body of {label}", jfrf.freq)
            subs[jname] = jfrf
            flat.append((Interface(iface.a, iface.a_dofs, jname, iface.joint.a_side), label))
            flat.append((Interface(jname, iface.joint.b_side, iface.b, iface.b_dofs), label))
        else:
            flat.append((iface, label))
    return flat


def _interface_problem(subs: dict[str, FRF], flat: list[tuple[Interface, str]], freq: np.ndarray,
                       outs: list, ins: list):
    """``Z = Σ_s B_s H_s,CC B_sᵀ + H_J``, ``U = H_oC Bᵀ``, ``V = B H_Ci`` and ``H_oi``, batched over lines.

    One row per paired contact DOF (a Lagrange multiplier λ): B u = u_a − u_b. For each
    substructure s: the λ rows it takes part in, its DOF there and the sign (+1 on side a,
    −1 on side b); only the blocks needed are read.
    """
    n_lambda = sum(len(i.a_dofs) for i, _ in flat)
    lam_rows: dict[str, list[int]] = {name: [] for name in subs}
    lam_dofs: dict[str, list[Dof]] = {name: [] for name in subs}
    lam_sign: dict[str, list[float]] = {name: [] for name in subs}
    nf = freq.size
    joints: list[tuple[np.ndarray, np.ndarray]] = []
    row = 0
    for iface, label in flat:
        n = len(iface.a_dofs)
        for r, (da, db) in enumerate(zip(iface.a_dofs, iface.b_dofs)):
            for name, d, sign in ((iface.a, da, 1.0), (iface.b, db, -1.0)):
                lam_rows[name].append(row + r)
                lam_dofs[name].append(d)
                lam_sign[name].append(sign)
        jm = _joint_matrix(iface, freq, label)
        if jm is not None:
            joints.append((np.arange(row, row + n), jm))
        row += n

    n_out, n_in = len(outs), len(ins)
    z = np.zeros((nf, n_lambda, n_lambda), dtype=complex)
    u = np.zeros((nf, n_out, n_lambda), dtype=complex)
    v = np.zeros((nf, n_lambda, n_in), dtype=complex)
    g = np.zeros((nf, n_out, n_in), dtype=complex)
    for name, frf in subs.items():
        ro = np.array([r for r, (n_, _) in enumerate(outs) if n_ == name], dtype=np.intp)
        ci = np.array([c_ for c_, (n_, _) in enumerate(ins) if n_ == name], dtype=np.intp)
        lr = np.array(lam_rows[name], dtype=np.intp)
        if not lr.size and not (ro.size and ci.size):
            continue
        nl = lr.size
        blk = _gather(
            name, frf, lam_dofs[name] + [outs[r][1] for r in ro], lam_dofs[name] + [ins[c_][1] for c_ in ci]
        )
        if nl:
            sign = np.array(lam_sign[name])
            flip = not np.all(sign == 1.0)
            cc = blk[:, :nl, :nl]
            z[_at(lr, lr)] += cc if np.all(sign == sign[0]) else cc * np.outer(sign, sign)
            if ro.size:
                u[_at(ro, lr)] = blk[:, nl:, :nl] * sign if flip else blk[:, nl:, :nl]
            if ci.size:
                v[_at(lr, ci)] = blk[:, :nl, nl:] * sign[:, None] if flip else blk[:, :nl, nl:]
        if ro.size and ci.size:
            g[_at(ro, ci)] = blk[:, nl:, nl:]
    for rows, jm in joints:
        z[_at(rows, rows)] += jm
    return z, u, v, g
