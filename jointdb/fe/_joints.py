"""Interfaces inside a beam model: point joints and inserted parts.

Two ingredients change the *topology* of a model, not only its matrices:

:class:`Joint`
    A compliant joint between two parts of the shaft at one position (a
    tool–holder face, a bolted flange, a modular thread). The beam is split at
    ``position`` into two coincident nodes; springs (and dampers / a loss
    factor) connect them in the directions given; every direction *not* given
    stays rigidly tied (the two nodes share that DOF). A planar joint with
    ``{"x": k, "ry": k_θ}`` is the classic translational + rotational
    spring–damper interface.

:class:`Insertion`
    A part that continues *inside* another over an overlap: a tool shank in the
    holder bore, a holder's taper in the spindle. The inserted part is a second,
    concentric beam from ``start`` to ``end`` (its own diameter and material)
    whose nodes coincide with the host's. At ``joined_at`` (the *mouth*) it is
    one piece with the main beam on the far side of the mouth (e.g. the tool's
    overhang). Over the overlap it is tied to the host either rigidly
    (``contact="rigid"``: the two share DOFs, i.e. a perfectly bonded composite
    section) or by a :class:`Contact` layer of distributed springs per unit
    length with a loss factor; with a compliant contact the main beam is split
    at the mouth, so the host and the inserted part meet only through the
    contact layer.

Both are applied like any other ingredient (``BeamModel.with_ingredient``), so a
diagnosis can add one at any interface and a model file can state it
(``"joints"``, ``"insertions"``). Points, clamps, supports and point masses at a
split position attach to the node that stays: the lower-z side of a joint, the
host side of an insertion's mouth.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from jointdb.errors import InputError
from jointdb.fe._fields import FieldError, _number
from jointdb.fe._ingredients import Ingredient, _check_directions
from jointdb.fe._materials import Material
from jointdb.fe._mesh import PLANAR_DIRECTIONS, Mesh
from jointdb.fe._segments import Segment
from jointdb.frf import DIRECTIONS

__all__ = ["Joint", "Contact", "Insertion"]


def _direction_values(raw, name: str) -> dict:
    if not isinstance(raw, dict):
        raise FieldError(name, f"must be a mapping of direction to value, got {raw!r}")
    clean = {}
    for key, value in raw.items():
        if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)) \
                or not math.isfinite(value):
            raise FieldError(f"{name}.{key}", f"must be a finite number, got {value!r}")
        if value < 0:
            raise FieldError(f"{name}.{key}", f"must be >= 0, got {value:g}")
        clean[str(key).lower()] = float(value)
    return clean


def _spring(K: np.ndarray, i: int, j: int, k: float) -> None:
    """Add a spring ``k`` between global DOFs ``i`` and ``j`` (in place)."""
    K[i, i] += k
    K[j, j] += k
    K[i, j] -= k
    K[j, i] -= k


@dataclass(frozen=True)
class Joint(Ingredient):
    """A compliant joint splitting the beam at ``position``.

    Parameters
    ----------
    position
        Axial position [m], strictly inside the model.
    stiffness
        ``{direction: k}`` between the two sides: N/m (translations), N·m/rad
        (rotations). Directions not listed stay rigidly tied.
    damping
        ``{direction: c}`` viscous dampers between the sides [N·s/m, N·m·s/rad]
        (only in directions that have a stiffness).
    loss_factor
        Hysteretic loss η of the joint springs (``K_loss += η k``).
    label
        Free text naming the interface (e.g. ``"tool–holder"``).
    """

    position: float
    stiffness: dict = field(default_factory=dict)
    damping: dict = field(default_factory=dict)
    loss_factor: float = 0.0
    label: str = ""
    splits = True

    def __post_init__(self) -> None:
        _number(self, "position", minimum=0.0)
        _number(self, "loss_factor", minimum=0.0)
        object.__setattr__(self, "stiffness", _direction_values(self.stiffness, "stiffness"))
        object.__setattr__(self, "damping", _direction_values(self.damping, "damping"))
        if not self.stiffness:
            raise FieldError("stiffness", "needs at least one direction (directions not given stay rigid)")
        for d in self.damping:
            if d not in self.stiffness:
                raise FieldError(f"damping.{d}", "a damper needs a spring in the same direction (give stiffness."
                                                 f"{d}); directions without stiffness are rigid")

    def __hash__(self) -> int:
        return hash((self.position, tuple(sorted(self.stiffness.items())), tuple(sorted(self.damping.items())),
                     self.loss_factor))

    def positions(self) -> tuple[float, ...]:
        """Axial positions [m] where the mesh needs a node.

        Returns
        -------
        tuple of float
        """
        return (self.position,)

    def split_position(self) -> float:
        """Axial position [m] where the mesh is split into two sides.

        Returns
        -------
        float
        """
        return self.position

    def free_directions(self) -> tuple[str, ...]:
        """Directions in which the two sides move separately (the rest share a DOF).

        Returns
        -------
        tuple of str
        """
        return tuple(self.stiffness)

    def apply(self, matrices, mesh):
        what = f"joint at {self.position:g} m"
        _check_directions(self.stiffness, mesh, what)
        a, b = mesh.split_nodes(self)
        K, C, L = matrices.K.copy(), matrices.C.copy(), matrices.K_loss.copy()
        for d, k in self.stiffness.items():
            i, j = mesh.dof(a, d), mesh.dof(b, d)
            _spring(K, i, j, k)
            if self.loss_factor > 0:
                _spring(L, i, j, self.loss_factor * k)
        for d, c in self.damping.items():
            _spring(C, mesh.dof(a, d), mesh.dof(b, d), c)
        return dataclasses.replace(matrices, K=K, C=C, K_loss=L)


@dataclass(frozen=True)
class Contact:
    """A distributed contact layer between an inserted part and its host.

    Parameters
    ----------
    stiffness_per_length
        ``{direction: k'}``: N/m per metre (= N/m²) for translations,
        N·m/rad per metre for rotations. Directions not listed have no contact
        stiffness (a bed of translational springs alone already carries
        bending moment through its spread).
    loss_factor
        Hysteretic loss η of the contact springs.
    """

    stiffness_per_length: dict = field(default_factory=dict)
    loss_factor: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "stiffness_per_length",
                           _direction_values(self.stiffness_per_length, "stiffness_per_length"))
        _number(self, "loss_factor", minimum=0.0)
        if not any(v > 0 for v in self.stiffness_per_length.values()):
            raise FieldError("stiffness_per_length", "needs a positive stiffness in at least one direction "
                                                     '(or use contact "rigid")')

    def __hash__(self) -> int:
        return hash((tuple(sorted(self.stiffness_per_length.items())), self.loss_factor))


@dataclass(frozen=True)
class Insertion(Ingredient):
    """A concentric part inside the host beam over ``[start, end]`` (see the module docstring).

    Parameters
    ----------
    start, end
        The overlap [m], ``start < end``, inside the model.
    outer_diameter, inner_diameter
        Section of the inserted part [m].
    material
        Material name or :class:`Material` of the inserted part.
    joined_at
        ``"end"`` or ``"start"``: the end of the overlap where the inserted
        part continues as the main beam beyond it (the mouth).
    contact
        ``"rigid"`` (bonded: shares the host's DOFs) or a :class:`Contact`.
    label
        Free text (e.g. ``"tool shank in holder bore"``).
    """

    start: float
    end: float
    outer_diameter: float
    inner_diameter: float = 0.0
    material: "str | Material" = "steel"
    joined_at: str = "end"
    contact: "str | Contact" = "rigid"
    label: str = ""
    splits = True

    def __post_init__(self) -> None:
        _number(self, "start", minimum=0.0)
        _number(self, "end", minimum=0.0)
        if not self.end > self.start:
            raise FieldError("end", f"must be > start ({self.start:g} m), got {self.end:g}")
        # the inserted part's section is validated (and its material normalised) as a segment's
        section = Segment(self.end - self.start, self.outer_diameter, self.inner_diameter, self.material)
        for name in ("outer_diameter", "inner_diameter", "material"):
            object.__setattr__(self, name, getattr(section, name))
        if self.joined_at not in ("start", "end"):
            raise FieldError("joined_at", f"must be 'start' or 'end', got {self.joined_at!r}")
        if isinstance(self.contact, str):
            if self.contact.strip().lower() != "rigid":
                raise FieldError("contact", f"must be \"rigid\" or a contact layer, got {self.contact!r}")
            object.__setattr__(self, "contact", "rigid")
        elif not isinstance(self.contact, Contact):
            raise FieldError("contact", f"must be \"rigid\" or a Contact, got {type(self.contact).__name__}")

    def __hash__(self) -> int:
        return hash((self.start, self.end, self.outer_diameter, self.inner_diameter, str(self.material),
                     self.joined_at, self.contact))

    @property
    def section(self) -> Segment:
        """The inserted part's section as a segment over the overlap."""
        return Segment(self.length, self.outer_diameter, self.inner_diameter, self.material)

    @property
    def rigid(self) -> bool:
        return self.contact == "rigid"

    @property
    def mouth(self) -> float:
        """Position [m] where the inserted part continues as the main beam."""
        return self.end if self.joined_at == "end" else self.start

    @property
    def length(self) -> float:
        return self.end - self.start

    def positions(self) -> tuple[float, ...]:
        """Axial positions [m] where the mesh needs a node.

        Returns
        -------
        tuple of float
        """
        return (self.start, self.end)

    def split_position(self) -> float | None:
        """Axial position [m] where the inserted part joins the main beam, or None.

        Returns
        -------
        float or None
        """
        return None if self.rigid else self.mouth

    def apply(self, matrices, mesh):
        if self.rigid:
            return matrices            # the shared DOFs are the tie; the section was assembled with the beam
        k_per = self.contact.stiffness_per_length
        _check_directions(k_per, mesh, f"insertion {self.start:g}–{self.end:g} m contact")
        Kc = np.zeros_like(matrices.K)
        # translational contact: consistent (Winkler-foundation) matrices on the relative deflection
        # Δw = N (q_inner − q_host) with cubic Hermite shape functions, so the bed ties slopes as well
        planes = {"x": ("x", "ry", 1.0), "y": ("y", "rx", -1.0)}
        for d, (t, r, sign) in planes.items():
            kp = k_per.get(d, 0.0)
            if kp <= 0 or t not in mesh.directions:
                continue
            elems = mesh.contact_elements(self)
            if not elems:
                continue
            h = np.array([e[4] for e in elems])
            kf = _foundation(kp, h, sign)                               # (n_el, 4, 4)
            dof = mesh.dof_table[:, [mesh.directions.index(t), mesh.directions.index(r)]]
            ends = np.array([e[:4] for e in elems], dtype=int)
            inner = dof[ends[:, :2]].reshape(-1, 4)                     # (w_a, θ_a, w_b, θ_b) of each element
            host = dof[ends[:, 2:4]].reshape(-1, 4)
            # the four blocks of every element in the order a loop over elements would add them
            rows = np.stack([inner, host, inner, host], axis=1)         # (n_el, 4 blocks, 4)
            cols = np.stack([inner, host, host, inner], axis=1)
            vals = kf[:, None] * np.array([1.0, 1.0, -1.0, -1.0])[None, :, None, None]
            np.add.at(Kc, (rows[:, :, :, None], cols[:, :, None, :]), vals)
        # other directions (rotations, axial, torsion): springs lumped at the nodes
        for inner, host, trib in mesh.contact_pairs(self):
            for d, kp in k_per.items():
                if d in planes or kp <= 0:
                    continue
                _spring(Kc, mesh.dof(inner, d), mesh.dof(host, d), kp * trib)
        eta = self.contact.loss_factor
        L = matrices.K_loss + eta * Kc if eta > 0 else matrices.K_loss
        return dataclasses.replace(matrices, K=matrices.K + Kc, K_loss=L)


def _foundation(k_per_length: float, h, sign: float = 1.0) -> np.ndarray:
    """Consistent Winkler-foundation matrix ``∫ k' NᵀN dz`` of a cubic Hermite element ``(w1, θ1, w2, θ2)``.

    ``h``: element length [m], a number (``(4, 4)`` result) or an array ``(n,)`` (``(n, 4, 4)``);
    ``sign = −1`` for a plane whose rotation is ``−dw/dz`` (the y–z plane of a 3-D frame).
    """
    h = np.asarray(h, dtype=float)
    c156, c54 = np.full_like(h, 156.0), np.full_like(h, 54.0)
    m = np.stack([np.stack(row, axis=-1) for row in (
        [c156, 22 * h, c54, -13 * h],
        [22 * h, 4 * h * h, 13 * h, -3 * h * h],
        [c54, 13 * h, c156, -22 * h],
        [-13 * h, -3 * h * h, -22 * h, 4 * h * h])], axis=-2) * (k_per_length * h / 420.0)[..., None, None]
    s = np.array([1.0, sign, 1.0, sign])
    return m * np.outer(s, s)


def interface_mesh(model, nodes: np.ndarray, seg: np.ndarray, tol: float, topo: list) -> Mesh:
    """The mesh of ``model`` with joints split and inserted parts added (see :mod:`jointdb.fe._joints`).

    ``nodes`` are the main chain's positions, ``seg`` its elements' segment indices, ``topo`` the
    ingredients that change the topology (in model order).
    """
    n_main = nodes.size
    length = float(nodes[-1])
    nd = len(PLANAR_DIRECTIONS if model.kind == "planar" else DIRECTIONS)
    dirs = PLANAR_DIRECTIONS if model.kind == "planar" else DIRECTIONS
    positions = list(nodes)
    elements = [[e, e + 1] for e in range(n_main - 1)]
    section = list(seg)
    sections = list(model.segments)
    splits, contacts, tied = [], [], []        # tied: (new node, staying node, directions shared)
    split_at: dict[int, str] = {}

    def main_node(z, what):
        i = int(np.argmin(np.abs(nodes - z)))
        if abs(nodes[i] - z) > tol:  # pragma: no cover - every declared position is a node
            raise InputError(f"{what} at {z:g} m is not a mesh node")
        return i

    index = {id(ing): i for i, ing in enumerate(model.ingredients)}
    for ing in topo:
        where = f"ingredients[{index[id(ing)]}]"
        z = ing.split_position()
        what = (f"insertion {ing.start:g}–{ing.end:g} m (mouth at {ing.mouth:g} m)" if isinstance(ing, Insertion)
                else f"joint at {ing.positions()[0]:g} m")
        if z is not None:
            j = main_node(z, what)
            if j == 0 or j == n_main - 1:
                raise FieldError(where, f"{what}: an interface must be inside the model (0 < z < {length:g} m), "
                                        "not at its end")
            if j in split_at:
                raise FieldError(where, f"{what}: the model already has an interface there ({split_at[j]})")
            split_at[j] = what
            new = len(positions)
            positions.append(float(nodes[j]))
            right = not isinstance(ing, Insertion) or ing.joined_at == "end"
            if right:
                elements[j][0] = new          # element j: (j, j+1) -> (new, j+1)
            else:
                elements[j - 1][1] = new      # element j-1: (j-1, j) -> (j-1, new)
            splits.append((ing, j, new))
            shared = tuple(d for d in dirs if d not in ing.free_directions()) if not isinstance(ing, Insertion) \
                else ()
            tied.append((new, j, shared))
        if isinstance(ing, Insertion):
            lo, hi = main_node(ing.start, what), main_node(ing.end, what)
            host = list(range(lo, hi + 1))
            k_sec = len(sections)
            sections.append(ing.section)
            if ing.rigid:
                inner = host
            else:
                mouth = hi if ing.joined_at == "end" else lo
                inner = []
                for h in host:
                    if h == mouth:
                        inner.append(splits[-1][2])
                    else:
                        inner.append(len(positions))
                        positions.append(float(nodes[h]))
            for a, b in zip(inner[:-1], inner[1:]):
                elements.append([a, b])
                section.append(k_sec)
            if not ing.rigid:
                zs = nodes[host]
                trib = np.zeros(len(host))
                dz = np.diff(zs)
                trib[:-1] += dz / 2
                trib[1:] += dz / 2
                pairs = tuple(zip(inner, host, (float(t) for t in trib)))
                elems = tuple((inner[k], inner[k + 1], host[k], host[k + 1], float(dz[k])) for k in range(len(dz)))
                contacts.append((ing, pairs, elems))
    n_nodes = len(positions)
    table = np.arange(n_nodes * nd).reshape(n_nodes, nd)
    for new, j, shared in tied:
        for d in shared:
            k = dirs.index(d)
            table[new, k] = table[j, k]
    _, table = np.unique(table, return_inverse=True)
    return Mesh(node_positions=np.asarray(positions), element_segment=np.asarray(section), kind=model.kind, tol=tol,
                element_nodes=np.asarray(elements), sections=tuple(sections), n_main=n_main,
                dof_table=table.reshape(n_nodes, nd), splits=tuple(splits), contacts=tuple(contacts))
