"""Stepped-shaft beam models: segments, named points, mesh and assembly."""

from __future__ import annotations

import copy
import dataclasses
import math
import threading
from collections import OrderedDict
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from jointdb.errors import InputError
from jointdb.fe._bare import remembered_bare_matrices
from jointdb.fe._fields import FieldError, _number
from jointdb.fe._ingredients import Ingredient
from jointdb.fe._joints import Insertion, Joint, interface_mesh
from jointdb.fe._matrices import FEMatrices, Modes
from jointdb.fe._mesh import Mesh, _merge_tol
from jointdb.fe._segments import Segment
from jointdb.fe._synthesis import frf_direct, frf_modal, natural_modes
from jointdb.frf import FRF, Dof

__all__ = ["Segment", "NamedPoint", "Mesh", "FEMatrices", "Modes", "BeamModel", "THEORIES", "KINDS"]

THEORIES = ("timoshenko", "euler-bernoulli")
KINDS = ("planar", "frame3d")

#: Meshes shared between models of the same geometry (a fit makes one model per evaluation that differs
#: from the last only in a stiffness, a mass or a damping): at most this many, least recently used dropped.
MESH_CACHE_SIZE = 64
_MESH_CACHE: OrderedDict = OrderedDict()
_MESH_LOCK = threading.Lock()


@dataclass(frozen=True)
class NamedPoint:
    """A named position on the model, mapped to a measurement node number.

    Parameters
    ----------
    name
        e.g. ``"tip"``; unique within a model.
    position
        Metres from the model's start (z = 0).
    node
        Node label used in FRF DOFs (``Dof(node, direction)``).
    """

    name: str
    position: float
    node: int

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name.strip() or "," in self.name:
            raise FieldError("name", f"must be a non-empty text without commas, got {self.name!r}")
        _number(self, "position", minimum=0.0)
        if isinstance(self.node, bool) or not isinstance(self.node, (int, np.integer)) or self.node < 0:
            raise FieldError("node", f"must be an integer >= 0, got {self.node!r}")
        object.__setattr__(self, "node", int(self.node))


def _as_tuple(value, what: str) -> tuple:
    if value is None:
        return ()
    if isinstance(value, (list, tuple)):
        return tuple(value)
    raise InputError(f"{what} must be a sequence, got {type(value).__name__}")


@dataclass(frozen=True, eq=False)
class BeamModel:
    """A beam / stepped shaft along z with named points and ingredients.

    Parameters
    ----------
    segments
        :class:`Segment` s from z = 0 onwards.
    points
        :class:`NamedPoint` s (FRF outputs/inputs are labelled by their ``node``).
    ingredients
        :class:`Clamp`, :class:`Support`, :class:`PointMass`, :class:`ModalDamping`,
        :class:`RayleighDamping`, :class:`HystereticDamping` (any number, any order).
    theory
        ``"timoshenko"`` (shear deformation + rotary inertia) or ``"euler-bernoulli"``.
    kind
        ``"planar"`` (DOFs x, ry per node) or ``"frame3d"`` (x y z rx ry rz).
    max_element_length
        Largest element length [m]; nodes are also put at every segment end,
        point and ingredient position.
    name
        Free text.

    Examples
    --------
    A steel shaft of 0.5 m, 20 mm diameter, free at both ends, in Euler–Bernoulli theory: two
    rigid-body modes, then the first bending mode at ``(4.7300² / 2π) √(EI / ρAL⁴)``:

    >>> import numpy as np
    >>> from jointdb.fe import BeamModel, Segment, NamedPoint, get_material
    >>> model = BeamModel(segments=(Segment(0.5, 0.02, material="steel"),),
    ...                   points=(NamedPoint("end", 0.5, node=1),), theory="euler-bernoulli")
    >>> modes = model.modes(3)
    >>> modes.n_rigid
    2
    >>> steel, L, d = get_material("steel"), 0.5, 0.02
    >>> EI, rhoA = steel.E * np.pi * d**4 / 64, steel.rho * np.pi * d**2 / 4
    >>> f1 = 4.7300**2 / (2 * np.pi) * np.sqrt(EI / (rhoA * L**4))
    >>> round(float(modes.freq_hz[2] / f1), 4)
    1.0
    >>> model.frf([100.0, 200.0], points=["end"]).shape           # (n_freq, n_out, n_in): 1x, 1ry
    (2, 2, 2)
    """

    segments: tuple[Segment, ...]
    points: tuple[NamedPoint, ...] = ()
    ingredients: tuple[Ingredient, ...] = ()
    theory: str = "timoshenko"
    kind: str = "planar"
    max_element_length: float = 0.005
    name: str = ""

    def __post_init__(self) -> None:
        segs = _as_tuple(self.segments, "segments")
        if not segs:
            raise FieldError("segments", "needs at least one segment")
        for i, s in enumerate(segs):
            if not isinstance(s, Segment):
                raise FieldError(f"segments[{i}]", f"must be a Segment, got {type(s).__name__}")
        pts = _as_tuple(self.points, "points")
        ings = _as_tuple(self.ingredients, "ingredients")
        object.__setattr__(self, "segments", segs)
        object.__setattr__(self, "points", pts)
        object.__setattr__(self, "ingredients", ings)
        theory = str(self.theory).lower().replace("_", "-")
        if theory in ("eb", "euler"):
            theory = "euler-bernoulli"
        if theory not in THEORIES:
            raise FieldError("theory", f"must be one of {', '.join(THEORIES)}, got {self.theory!r}")
        object.__setattr__(self, "theory", theory)
        kind = str(self.kind).lower()
        if kind not in KINDS:
            raise FieldError("kind", f"must be one of {', '.join(KINDS)}, got {self.kind!r}")
        object.__setattr__(self, "kind", kind)
        _number(self, "max_element_length", minimum=0.0, strict=True)
        length = self.length
        tol = _merge_tol(length)
        names = set()
        nodes: dict[int, str] = {}
        for i, p in enumerate(pts):
            if not isinstance(p, NamedPoint):
                raise FieldError(f"points[{i}]", f"must be a NamedPoint, got {type(p).__name__}")
            if p.name in names:
                raise FieldError(f"points[{i}].name", f"duplicate point name {p.name!r}")
            names.add(p.name)
            if p.node in nodes:
                # two points with one node label would give duplicate FRF DOFs (e.g. two "1x")
                raise FieldError(f"points[{i}].node", f"node {p.node} is already used by point {nodes[p.node]!r}")
            nodes[p.node] = p.name
            if p.position > length + tol:
                raise FieldError(f"points[{i}].position", f"{p.position:g} m is beyond the model's length {length:g} m")
        for i, ing in enumerate(ings):
            if not isinstance(ing, Ingredient):
                raise FieldError(f"ingredients[{i}]", f"is not a model ingredient: {ing!r}")
            for pos in ing.positions():
                if pos > length + tol:
                    raise FieldError(
                        f"ingredients[{i}].position",
                        f"{pos:g} m is beyond the model's length {length:g} m ({type(ing).__name__})",
                    )

        if any(getattr(ing, "splits", False) for ing in ings):
            self.mesh()            # interfaces are checked where they split the mesh (FieldError per ingredient)

    # ------------------------------------------------------------ building
    @property
    def length(self) -> float:
        """Total length [m]."""
        return float(math.fsum(s.length for s in self.segments))

    def replace(self, **changes) -> "BeamModel":
        """A new model with some fields replaced (validated again).

        Parameters
        ----------
        **changes
            Field name → new value (``segments``, ``points``, ``ingredients``, ...).

        Returns
        -------
        BeamModel
        """
        return dataclasses.replace(self, **changes)

    def with_ingredient(self, *ingredients: Ingredient) -> "BeamModel":
        """A new model with the ingredient(s) added.

        Parameters
        ----------
        *ingredients
            :class:`Ingredient` s to append.

        Returns
        -------
        BeamModel
        """
        return self.replace(ingredients=self.ingredients + tuple(ingredients))

    def without(self, kind_or_predicate: "type | str | Callable[[Ingredient], bool]") -> "BeamModel":
        """A new model without the ingredients of a class (or class name), or matching a predicate.

        Parameters
        ----------
        kind_or_predicate
            An ingredient class (``ModalDamping``), its name (``"modal-damping"``; case,
            ``-`` and ``_`` ignored) or a function ``Ingredient -> bool`` (True: drop it).

        Returns
        -------
        BeamModel
        """
        if isinstance(kind_or_predicate, type):
            drop = lambda ing: isinstance(ing, kind_or_predicate)  # noqa: E731
        elif isinstance(kind_or_predicate, str):
            key = kind_or_predicate.replace("-", "").replace("_", "").lower()
            drop = lambda ing: type(ing).__name__.lower() == key  # noqa: E731
        elif callable(kind_or_predicate):
            drop = kind_or_predicate
        else:
            raise InputError(f"without() needs an ingredient class, name or predicate, got {kind_or_predicate!r}")
        return self.replace(ingredients=tuple(i for i in self.ingredients if not drop(i)))

    def point(self, name: str) -> NamedPoint:
        """The named point ``name``.

        Parameters
        ----------
        name
            A point name of the model.

        Returns
        -------
        NamedPoint

        Raises
        ------
        InputError
            No point of that name (the message lists those there are).
        """
        for p in self.points:
            if p.name == name:
                return p
        have = ", ".join(p.name for p in self.points) or "none"
        raise InputError(f"unknown point {name!r}; this model has: {have}")

    def mesh(self) -> Mesh:
        """Nodes at segment ends, point and ingredient positions, refined to ``max_element_length``;
        then the interfaces: splits for joints, extra nodes for inserted parts (see :mod:`jointdb.fe._joints`).

        Computed once per model (a model is immutable; :meth:`replace` makes a new one), and shared by
        models of the same geometry (segment lengths, element length, kind, every position, the interfaces'
        kinds, places and free directions): a fit's models, which differ in a stiffness, a mass or a
        damping, reuse one set of nodes, elements, DOF numbering, labels and bare beam matrices; the
        entries that name interfaces name this model's own ingredients.

        Returns
        -------
        Mesh
        """
        cached = self.__dict__.get("_mesh")
        if cached is None:
            key = self._mesh_key()
            with _MESH_LOCK:
                base = _MESH_CACHE.get(key) if key is not None else None
                if base is not None:
                    _MESH_CACHE.move_to_end(key)
            if base is None:
                cached = self._make_mesh()
                cached.__dict__["_bare"] = object()          # names the bare matrices of every model bound to it
                cached.dof_labels()                            # computed once, shared likewise
                if key is not None:
                    with _MESH_LOCK:
                        _MESH_CACHE[key] = cached
                        while len(_MESH_CACHE) > MESH_CACHE_SIZE:
                            _MESH_CACHE.popitem(last=False)
            else:
                cached = self._bind(base)
            self.__dict__["_mesh"] = cached
        return cached

    def _mesh_key(self) -> "tuple | None":
        """Everything :meth:`_make_mesh` reads but the identities of the ingredients and the sections'
        materials and diameters (None: an interface of a kind this does not know; not shared)."""
        extra = [p.position for p in self.points]
        topo = []
        for ing in self.ingredients:
            extra.extend(ing.positions())
            if not getattr(ing, "splits", False):
                continue
            if type(ing) is Joint:
                topo.append(("joint", ing.split_position(), tuple(sorted(ing.free_directions()))))
            elif type(ing) is Insertion:
                topo.append(("insertion", ing.start, ing.end, ing.joined_at, ing.rigid))
            else:
                return None
        return (tuple(s.length for s in self.segments), self.max_element_length, self.kind,
                tuple(sorted(extra)), tuple(topo))

    def _bind(self, base: Mesh) -> Mesh:
        """``base`` (the mesh of a model of the same geometry) for this model: the same nodes, elements and
        DOFs, with this model's sections and its interfaces in the entries that name them."""
        topo = [i for i in self.ingredients if getattr(i, "splits", False)]
        split = iter([i for i in topo if i.split_position() is not None])
        contact = iter([i for i in topo if isinstance(i, Insertion) and not i.rigid])
        splits = tuple((next(split), *rest) for _, *rest in base.splits)
        contacts = tuple((next(contact), *rest) for _, *rest in base.contacts)
        sections = self.segments + tuple(i.section for i in topo if isinstance(i, Insertion))
        mesh = copy.copy(base)                  # shares the arrays, the DOF labels and the bare matrices
        for name, value in (("splits", splits), ("contacts", contacts), ("sections", sections)):
            object.__setattr__(mesh, name, value)
        return mesh

    def _make_mesh(self) -> Mesh:
        ends = np.concatenate([[0.0], np.cumsum([s.length for s in self.segments])])
        length = float(ends[-1])
        tol = _merge_tol(length, self.max_element_length)
        # segment ends are always nodes; other positions join the nearest node within tol
        marks = list(ends)
        extra = [p.position for p in self.points]
        for ing in self.ingredients:
            extra.extend(ing.positions())
        for pos in sorted(extra):
            if min(abs(m - pos) for m in marks) > tol:
                marks.append(min(pos, length))
        marks = np.sort(np.asarray(marks, dtype=float))
        pieces = []
        for a, b in zip(marks[:-1], marks[1:]):
            n = max(1, int(math.ceil((b - a) / self.max_element_length - 1e-9)))
            pieces.append(np.linspace(a, b, n + 1)[:-1])
        nodes = np.concatenate(pieces + [marks[-1:]])
        mids = 0.5 * (nodes[:-1] + nodes[1:])
        seg = np.clip(np.searchsorted(ends, mids, side="right") - 1, 0, len(self.segments) - 1)
        topo = [i for i in self.ingredients if getattr(i, "splits", False)]
        if not topo:
            return Mesh(node_positions=nodes, element_segment=seg, kind=self.kind, tol=tol,
                        sections=self.segments)
        return interface_mesh(self, nodes, seg, tol, topo)

    def assemble(self) -> FEMatrices:
        """Assemble the bare beam, then apply every ingredient in stage order.

        Returns
        -------
        FEMatrices
            Matrices over all mesh DOFs, with constrained DOFs marked in ``fixed``.
        """
        mesh = self.mesh()
        K, M = remembered_bare_matrices(mesh, mesh.sections or self.segments, self.theory, self.kind)
        n = mesh.n_dof
        mats = FEMatrices(
            K=K, M=M, C=np.zeros((n, n)), K_loss=np.zeros((n, n)),
            dof_labels=mesh.dof_labels(), node_positions=mesh.node_positions, fixed=np.zeros(n, dtype=bool),
        )
        for ing in sorted(self.ingredients, key=lambda i: i.stage):
            mats = ing.apply(mats, mesh)
        return mats

    # ----------------------------------------------------------- analysis
    def modes(self, n: int | None = None) -> Modes:
        """Natural frequencies and mass-normalised mode shapes (undamped).

        Parameters
        ----------
        n
            Number of lowest modes (default: all).

        Returns
        -------
        Modes
            ``freq_hz (n,)``, ``shapes (n_dof, n)`` over all mesh DOFs.
        """
        return natural_modes(self.assemble(), n)

    def frf(
        self,
        freq_hz,
        points: Sequence[str] | None = None,
        directions: Sequence[str] | None = None,
        method: str = "direct",
        n_modes: int | None = None,
        algorithm: str = "auto",
    ) -> FRF:
        """Receptance matrix between named points (square: outputs == inputs).

        Parameters
        ----------
        freq_hz
            Frequencies [Hz], strictly increasing, shape ``(n_freq,)``.
        points
            Names of points (default: all named points).
        directions
            Directions per point (default ``("x", "ry")`` planar, all six for frame3d).
        method
            ``"direct"``: batched solve of ``(K + iK_loss + iωC − ω²M) X = F``;
            ``"modal"``: modal superposition with static residual (theory of
            :func:`jointdb.fe.frf_modal`).
        n_modes
            Modes kept in modal superposition (default: those below 2 × f_max).
        algorithm
            For ``method="direct"``: ``"lu"`` (batched LU solves), ``"spectral"``
            (sum over all modes; classical damping only) or ``"auto"`` (spectral
            when the damping is classical); see :func:`jointdb.fe.frf_direct`.

        Returns
        -------
        FRF
            Receptance, DOFs ``Dof(point.node, direction)``.

        Raises
        ------
        InputError
            Unknown point/direction/method; 0 Hz on a model with rigid-body modes.
        """
        mesh = self.mesh()
        names = [p.name for p in self.points] if points is None else list(points)
        if not names:
            raise InputError("this model has no named points; add points to it to get FRFs")
        dirs = mesh.directions if directions is None else tuple(str(d).lower() for d in directions)
        idx, labels = [], []
        for name in names:
            p = self.point(name)
            node = mesh.node_at(p.position, f"point {name!r}")
            for d in dirs:
                idx.append(mesh.dof(node, d))
                labels.append(Dof(p.node, d))
        freq = np.asarray(freq_hz, dtype=float)
        mats = self.assemble()
        if method == "direct":
            values = frf_direct(mats, freq, idx, algorithm=algorithm)
        elif method == "modal":
            values = frf_modal(mats, freq, idx, n_modes=n_modes)
        else:
            raise InputError(f"method must be 'direct' or 'modal', got {method!r}")
        return FRF(freq, values, tuple(labels), tuple(labels), "receptance")
