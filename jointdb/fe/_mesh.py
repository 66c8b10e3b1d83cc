"""The mesh of a beam model: nodes, elements, DOF numbering.

A plain stepped shaft is one chain of nodes along z, element ``e`` joining
nodes ``e`` and ``e + 1``. Interfaces change that topology
(:mod:`jointdb.fe._joints`, whose ``interface_mesh`` builds such a mesh): a joint splits the chain at a node into two
coincident nodes (sharing the DOFs of the directions it leaves rigid), and an
inserted part adds its own chain of nodes over the overlap, bonded to the host
(DOFs shared) or on a contact layer. The main chain's nodes always come first,
so a position's node index is the same with or without interfaces.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from jointdb.errors import InputError
from jointdb.frf import DIRECTIONS, Dof

__all__ = ["Mesh", "PLANAR_DIRECTIONS"]

PLANAR_DIRECTIONS = ("x", "ry")


@dataclass(frozen=True, eq=False)
class Mesh:
    """Nodes, elements and DOF numbering of a model.

    The main chain of nodes (``0 .. n_main-1``, ascending z) comes first; nodes
    added by interfaces (the far side of a :class:`jointdb.fe.Joint`, the nodes
    of an inserted part) follow. ``element_nodes (n_el, 2)`` connects nodes;
    ``element_section`` indexes ``sections`` (the model's segments, then the
    inserted parts' sections). ``dof_table (n_nodes, n_dir)`` gives each node's
    global DOFs; nodes tied in a direction share that DOF.

    Attributes
    ----------
    node_positions
        Axial node positions [m], ``(n_nodes,)``.
    element_segment
        Index into ``sections`` of each element, ``(n_el,)``.
    kind
        ``"planar"`` or ``"frame3d"``.
    tol
        Distance [m] within which a position is taken to be at a node.
    element_nodes
        Node pair of each element, ``(n_el, 2)`` (default: consecutive nodes).
    sections
        The element sections: the model's segments, then the inserted parts'.
    n_main
        Number of nodes on the main chain (default: all).
    dof_table
        Global DOF of each node and direction, ``(n_nodes, n_dir)``.
    splits
        ``(ingredient, staying node, new node)`` of each joint split.
    contacts
        ``(ingredient, node pairs, element pairs)`` of each insertion's contact layer.
    """

    node_positions: np.ndarray
    element_segment: np.ndarray
    kind: str
    tol: float = 0.0
    element_nodes: np.ndarray | None = None
    sections: tuple = ()
    n_main: int = 0
    dof_table: np.ndarray | None = None
    splits: tuple = ()            # (ingredient, staying node, new node)
    contacts: tuple = ()          # (ingredient, node pairs (inner, host, tributary length [m]),
    #                                 elements (inner a, inner b, host a, host b, length [m]))

    def __post_init__(self) -> None:
        n = self.node_positions.size
        if self.element_nodes is None:
            object.__setattr__(self, "element_nodes", np.column_stack([np.arange(n - 1), np.arange(1, n)]))
        if not self.n_main:
            object.__setattr__(self, "n_main", n)
        if self.dof_table is None:
            nd = len(self.directions)
            object.__setattr__(self, "dof_table", np.arange(n * nd).reshape(n, nd))

    @property
    def element_section(self) -> np.ndarray:
        return self.element_segment

    @property
    def directions(self) -> tuple[str, ...]:
        return PLANAR_DIRECTIONS if self.kind == "planar" else DIRECTIONS

    @property
    def n_nodes(self) -> int:
        return self.node_positions.size

    @property
    def n_dof(self) -> int:
        return int(self.dof_table.max()) + 1

    @property
    def length(self) -> float:
        return float(self.node_positions[self.n_main - 1])

    def node_at(self, position: float, what: str = "position") -> int:
        """Index of the main-chain node at ``position`` (mesh nodes include every declared position).

        Parameters
        ----------
        position
            Axial position [m].
        what
            What is placed there, for the error message.

        Returns
        -------
        int

        Raises
        ------
        InputError
            No node at that position.
        """
        main = self.node_positions[: self.n_main]
        i = int(np.argmin(np.abs(main - position)))
        if abs(main[i] - position) > max(self.tol, _merge_tol(self.length)):
            raise InputError(f"{what} at {position:g} m is not a mesh node (model length {self.length:g} m)")
        return i

    def dof(self, node: int, direction: str) -> int:
        """Global DOF index of a node's direction.

        Parameters
        ----------
        node
            Mesh node index.
        direction
            ``"x"``, ``"ry"``, ... (one of the model's directions).

        Returns
        -------
        int
        """
        try:
            return int(self.dof_table[node, self.directions.index(direction)])
        except ValueError:
            raise InputError(
                f"direction {direction!r} does not exist in a {self.kind} model ({', '.join(self.directions)})"
            ) from None

    def split_nodes(self, ingredient) -> tuple[int, int]:
        """``(staying node, new node)`` of the split made by ``ingredient``.

        Parameters
        ----------
        ingredient
            A :class:`jointdb.fe.Joint` of the model.

        Returns
        -------
        tuple of int
        """
        found = _entry_of(self.splits, ingredient)
        if found is not None:
            return found
        raise InputError(f"{type(ingredient).__name__} at {ingredient.positions()} m is not part of this mesh")

    def contact_pairs(self, ingredient) -> tuple:
        """``((inner node, host node, tributary length [m]), ...)`` of an insertion's contact layer.

        Parameters
        ----------
        ingredient
            A :class:`jointdb.fe.Insertion` of the model.

        Returns
        -------
        tuple
            Empty when it has no contact layer.
        """
        found = _entry_of(self.contacts, ingredient)
        return () if found is None else found[0]

    def contact_elements(self, ingredient) -> tuple:
        """``((inner a, inner b, host a, host b, length [m]), ...)``: the overlap's element pairs
        (empty when the insertion has no contact layer).

        Parameters
        ----------
        ingredient
            The :class:`jointdb.fe.Insertion`, as for :meth:`contact_pairs`.

        Returns
        -------
        tuple
        """
        found = _entry_of(self.contacts, ingredient)
        return () if found is None else found[1]

    def dof_labels(self) -> tuple[Dof, ...]:
        """``Dof(node, direction)`` of every global DOF (the first node that owns it).

        Returns
        -------
        tuple of Dof
            One per global DOF, ``(n_dof,)``.
        """
        cached = self.__dict__.get("_labels")
        if cached is not None:
            return cached
        labels: dict[int, Dof] = {}
        for node, row in enumerate(self.dof_table.tolist()):
            for dof, d in zip(row, self.directions):
                if dof not in labels:
                    labels[dof] = _dof_label(node, d)
        out = tuple(labels[i] for i in range(self.n_dof))
        self.__dict__["_labels"] = out
        return out


@functools.lru_cache(maxsize=65536)
def _dof_label(node: int, direction: str) -> Dof:
    """``Dof(node, direction)``, shared: a label is immutable, and every mesh of a fit (one per model
    evaluated) asks for the same few hundred."""
    return Dof(node, direction)


def _merge_tol(length: float, max_element_length: float = 0.0) -> float:
    """Positions closer than this share a node (avoids ill-conditioned sliver elements)."""
    return max(1e-9 * max(abs(length), 1e-3), 1e-3 * max_element_length)


def _entry_of(entries: tuple, ingredient) -> "tuple | None":
    """What a ``(ingredient, ...)`` entry of :attr:`Mesh.splits` / :attr:`Mesh.contacts` holds after the
    ingredient (compared by identity), or None when the ingredient has none."""
    for ing, *rest in entries:
        if ing is ingredient:
            return tuple(rest)
    return None
