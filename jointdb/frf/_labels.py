"""DOF labels and FRF quantities: :class:`Dof`, :func:`dofs`, :class:`Quantity`.

Directions use the UFF58 codes ``x y z rx ry rz`` (1..6); a quantity is the power ``p`` of
``(iω)`` relating an FRF to the receptance (convention ``x(t) = X exp(+iωt)``).
"""

from __future__ import annotations

import enum
import re
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from jointdb.errors import InputError

__all__ = ["DIRECTIONS", "Dof", "Quantity", "dofs"]

#: Direction names in UFF58 order: code 1..6.
DIRECTIONS: tuple[str, ...] = ("x", "y", "z", "rx", "ry", "rz")

_DOF_RE = re.compile(r"^\s*(\d+)\s*[:.\s]?\s*([+-]?)\s*(x|y|z|rx|ry|rz)\s*$", re.IGNORECASE)


@dataclass(frozen=True, order=True)
class Dof:
    """A degree of freedom: a node number and a direction (``x y z rx ry rz``).

    ``str(Dof(12, "rx")) == "12rx"``; :meth:`parse` reads ``"12rx"``, ``"12:rx"``
    or ``"12 RX"``.

    Parameters
    ----------
    node
        Node number, >= 0.
    direction
        ``x``, ``y``, ``z`` (translations) or ``rx``, ``ry``, ``rz`` (rotations); case-insensitive.
    """

    node: int
    direction: str

    def __post_init__(self) -> None:
        if isinstance(self.node, bool) or not isinstance(self.node, (int, np.integer)):
            raise InputError(f"DOF node must be an integer, got {self.node!r}")
        if self.node < 0:
            raise InputError(f"DOF node must be >= 0, got {self.node}")
        direction = str(self.direction).lower()
        if direction not in DIRECTIONS:
            raise InputError(
                f"unknown DOF direction {self.direction!r}; expected one of {', '.join(DIRECTIONS)}"
            )
        object.__setattr__(self, "node", int(self.node))
        object.__setattr__(self, "direction", direction)

    def __str__(self) -> str:
        return f"{self.node}{self.direction}"

    @property
    def uff_code(self) -> int:
        """UFF58 direction code 1..6."""
        return DIRECTIONS.index(self.direction) + 1

    @property
    def is_rotation(self) -> bool:
        return self.direction.startswith("r")

    @classmethod
    def parse(cls, text: "str | Dof | tuple[int, str]") -> "Dof":
        """Read a DOF from ``"12x"``, ``"12:rx"``, ``(12, "rx")`` or a Dof.

        Parameters
        ----------
        text
            The label: text, a ``(node, direction)`` pair or a :class:`Dof` (returned as is).

        Returns
        -------
        Dof

        Raises
        ------
        InputError
            If the text names no valid DOF, or carries a sign (signs belong to
            UFF import, see :meth:`from_uff`).
        """
        if isinstance(text, Dof):
            return text
        if isinstance(text, tuple) and len(text) == 2:
            try:
                node = int(text[0])
            except (TypeError, ValueError):
                raise InputError(f"cannot read a DOF from {text!r}: node must be an integer") from None
            return cls(node, str(text[1]))
        m = _DOF_RE.match(str(text))
        if not m:
            raise InputError(f"cannot read a DOF from {text!r}; write it like '12x' or '3:ry'")
        if m.group(2) == "-":
            raise InputError(f"DOF {text!r} has a negative sign; labels are always positive directions")
        return cls(int(m.group(1)), m.group(3).lower())

    @classmethod
    def from_uff(cls, node: int, code: int) -> tuple["Dof", int]:
        """DOF and sign (+1/−1) from a UFF58 node and signed direction code (±1..±6).

        Parameters
        ----------
        node
            UFF node number.
        code
            Signed UFF direction code: ±1..±3 translations x y z, ±4..±6 rotations.

        Returns
        -------
        dof : Dof
        sign : int
            +1 or −1.

        Raises
        ------
        InputError
            For code 0 (scalar) or ``|code| > 6``.
        """
        code = int(code)
        if code == 0 or abs(code) > 6:
            raise InputError(f"UFF direction code {code} is not a translation or rotation (expected ±1..±6)")
        return cls(int(node), DIRECTIONS[abs(code) - 1]), (1 if code > 0 else -1)


def dofs(labels: Iterable["str | Dof | tuple[int, str]"]) -> tuple[Dof, ...]:
    """Parse an iterable of DOF labels into a tuple of :class:`Dof`.

    Parameters
    ----------
    labels
        Labels as :meth:`Dof.parse` reads them; a single label is taken as a list of one.

    Returns
    -------
    tuple of Dof

    Examples
    --------
    >>> from jointdb import dofs
    >>> [str(d) for d in dofs(["1x", "1:RY", (3, "z")])]
    ['1x', '1ry', '3z']
    """
    if isinstance(labels, (str, Dof)):
        labels = [labels]
    return tuple(Dof.parse(label) for label in labels)


class Quantity(str, enum.Enum):
    """What an FRF relates to force: displacement, velocity or acceleration."""

    RECEPTANCE = "receptance"
    MOBILITY = "mobility"
    ACCELERANCE = "accelerance"

    @property
    def power(self) -> int:
        """Power p of (iω) with ``FRF = (iω)^p · receptance``."""
        return {"receptance": 0, "mobility": 1, "accelerance": 2}[self.value]

    @classmethod
    def parse(cls, value: "str | Quantity") -> "Quantity":
        """A Quantity from its name (case-insensitive) or a Quantity.

        Parameters
        ----------
        value
            ``"receptance"``, ``"mobility"``, ``"accelerance"`` or a :class:`Quantity`.

        Returns
        -------
        Quantity

        Raises
        ------
        InputError
            An unknown name.
        """
        try:
            return cls(str(getattr(value, "value", value)).lower())
        except ValueError:
            raise InputError(
                f"unknown FRF quantity {value!r}; expected receptance, mobility or accelerance"
            ) from None
