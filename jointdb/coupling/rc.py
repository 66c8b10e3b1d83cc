"""Forward receptance coupling (RC): LM-FBS with flexible interfaces.

theory.md §1a/§1b. Any number of substructures (FRF containers) are joined
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

from jointdb.coupling._common import as_receptance as _receptance
from jointdb.coupling._common import check_grid as _check_grid
from jointdb.errors import InputError, NumericalError
from jointdb.frf import FRF, Dof, Quantity, dofs

__all__ = ["Interface", "JointSubstructure", "couple", "spring_damper_joint"]


@dataclass(frozen=True)
class JointSubstructure:
    """A joint body with inertia (theory.md §1b).

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
        Receptance ``(n_freq, n, n)``, diagonal, theory.md §1a.

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


class _Blocks:
    """Fetch blocks of a substructure's receptance, using reciprocity if needed."""

    def __init__(self, name: str, frf: FRF):
        self.name = name
        self.frf = frf
        self._full: FRF | None = None

    def block(self, outs: Sequence[Dof], ins: Sequence[Dof]) -> np.ndarray:
        if not outs or not ins:
            return np.zeros((self.frf.n_freq, len(outs), len(ins)), dtype=complex)
        oset, iset = self.frf._index["out"], self.frf._index["in"]
        if all(d in oset for d in outs) and all(d in iset for d in ins):
            return self.frf.block(outs, ins)
        if all(d in iset for d in outs) and all(d in oset for d in ins):
            return np.swapaxes(self.frf.block(ins, outs), 1, 2)
        if self._full is None:
            try:
                self._full = self.frf.complete_reciprocal()
            except InputError as exc:
                raise InputError(f"substructure {self.name!r}: {exc}") from None
        have = self._full._index["out"]
        for d in list(outs) + list(ins):
            if d not in have:
                raise InputError(
                    f"substructure {self.name!r} has no FRF for DOF {d} "
                    f"(it has: {' '.join(str(x) for x in self._full.outputs)})"
                )
        return self._full.block(outs, ins)


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

    LM-FBS with flexible interfaces (theory.md §1a, §1b; thesis eq. 4.1–4.8):

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
    """
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

    # Expand joint bodies into extra substructures with two rigid interfaces.
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

    # Contact DOF index C: unique (substructure, dof) pairs, grouped per substructure.
    contact: dict[str, list[Dof]] = {name: [] for name in subs}
    for iface, _ in flat:
        for name, side in ((iface.a, iface.a_dofs), (iface.b, iface.b_dofs)):
            for d in side:
                if d not in contact[name]:
                    contact[name].append(d)
    offset: dict[str, int] = {}
    n_c = 0
    for name in subs:
        offset[name] = n_c
        n_c += len(contact[name])
    pos = {(name, d): offset[name] + i for name in subs for i, d in enumerate(contact[name])}

    n_lambda = sum(len(i.a_dofs) for i, _ in flat)
    bmat = np.zeros((n_lambda, n_c))
    nf = freq.size
    hj = np.zeros((nf, n_lambda, n_lambda), dtype=complex)
    row = 0
    for iface, label in flat:
        n = len(iface.a_dofs)
        for r, (da, db) in enumerate(zip(iface.a_dofs, iface.b_dofs)):
            bmat[row + r, pos[(iface.a, da)]] += 1.0
            bmat[row + r, pos[(iface.b, db)]] -= 1.0
        jm = _joint_matrix(iface, freq, label)
        if jm is not None:
            hj[:, row : row + n, row : row + n] = jm
        row += n

    blocks = {name: _Blocks(name, frf) for name, frf in subs.items()}
    h_cc = np.zeros((nf, n_c, n_c), dtype=complex)
    for name in subs:
        c = contact[name]
        if c:
            o = offset[name]
            h_cc[:, o : o + len(c), o : o + len(c)] = blocks[name].block(c, c)

    h_oc = np.zeros((nf, len(outs), n_c), dtype=complex)
    for r, (name, d) in enumerate(outs):
        c = contact[name]
        if c:
            h_oc[:, r, offset[name] : offset[name] + len(c)] = blocks[name].block([d], c)[:, 0, :]
    h_ci = np.zeros((nf, n_c, len(ins)), dtype=complex)
    for col, (name, d) in enumerate(ins):
        c = contact[name]
        if c:
            h_ci[:, offset[name] : offset[name] + len(c), col] = blocks[name].block(c, [d])[:, :, 0]
    h_oi = np.zeros((nf, len(outs), len(ins)), dtype=complex)
    for name in substructures:
        ro = [r for r, (n_, _) in enumerate(outs) if n_ == name]
        ci = [c_ for c_, (n_, _) in enumerate(ins) if n_ == name]
        if ro and ci:
            blk = blocks[name].block([outs[r][1] for r in ro], [ins[c_][1] for c_ in ci])
            h_oi[:, np.array(ro)[:, None], np.array(ci)[None, :]] = blk

    # Interface problem: Z λ = B H_Ci,  G = H_oi − (H_oC Bᵀ) Z⁻¹ (B H_Ci).
    z = bmat @ h_cc @ bmat.T + hj
    rhs = bmat @ h_ci
    try:
        lam = np.linalg.solve(z, rhs)
    except np.linalg.LinAlgError:
        raise NumericalError(
            "the interface matrix B H_CC Bᵀ + H_J is singular at some frequency line; "
            "check for redundant interfaces or rigid couplings between rigid-body DOFs"
        ) from None
    h_oi -= (h_oc @ bmat.T) @ lam
    g = h_oi
    if not np.all(np.isfinite(g)):
        raise NumericalError("coupling produced NaN/inf: the interface matrix is singular at some line")
    return FRF(freq, g, tuple(d for _, d in outs), tuple(d for _, d in ins), Quantity.RECEPTANCE)

