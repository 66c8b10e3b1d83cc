"""The stack description: tool, holder, spindle side, gauge length, interfaces.

This module holds the frozen dataclasses of a stack; reading and writing the
JSON document (``stack_from_dict`` / ``stack_to_dict``, errors naming the exact
field) is in :mod:`jointdb.stack._stackfile`. Nothing here reads files: a
measured spindle FRF is referenced by path and attached later by the
application layer (:func:`jointdb.usecases.load_stack`).

Geometry conventions (SI, metres). The tool is described from its tip towards
its shank end; the holder from its nose (the face the tool sticks out of)
towards the spindle. ``gauge_length`` is the tool's stick-out from the holder
face; the rest of the tool (its total length minus the gauge length) is the
insertion length, clamped inside the holder bore (a file may give
``insertion_length`` instead of, or consistently with, ``gauge_length``). A fluted section is replaced
by a solid cylinder of ``fluted_ratio`` × cutter diameter (0.656 after Kops and
Vo 1990; thesis §4.4).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import Any

from jointdb.frf import FRF

__all__ = [
    "FORMAT",
    "INTERFACE_NAMES",
    "KOPS_VO_RATIO",
    "ToolSegment",
    "Tool",
    "HolderSegment",
    "Holder",
    "MeasuredSpindle",
    "ModelledSpindle",
    "JointChoice",
    "FrequencyGrid",
    "StackSpec",
]

#: Format tag written to / accepted in stack files.
FORMAT = "jointdb-stack/1"
#: Equivalent diameter of a fluted section as a fraction of the cutter diameter (Kops & Vo 1990).
KOPS_VO_RATIO = 0.656
#: The two interfaces of a stack, from the tool towards the spindle.
INTERFACE_NAMES: tuple[str, str] = ("tool-holder", "holder-spindle")


# ------------------------------------------------------------------ parts
@dataclass(frozen=True)
class ToolSegment:
    """One tool section: ``length`` and (cutter or shank) ``diameter`` in m.

    ``fluted=True`` marks the cutting section; it is modelled as a solid
    cylinder of ``Tool.fluted_ratio × diameter``.
    """

    length: float
    diameter: float
    fluted: bool = False


@dataclass(frozen=True)
class Tool:
    """The tool, from its tip towards its shank end.

    Parameters
    ----------
    segments
        Tool sections from the tip; the fluted ones come first.
    material
        A name known to :func:`jointdb.fe.get_material` (e.g. ``"carbide"``).
    fluted_ratio
        Equivalent diameter of a fluted section / cutter diameter (Kops & Vo: 0.656).
    loss_factor
        Structural (hysteretic) loss factor η of the tool's beam model, ``K(1 + iη)``.
    fluted_area_ratio
        Cross-section area of a fluted section / the full circle's (e.g. ≈ 0.6 for a 4-flute
        cutter, from its CAD model or its mass). ``None``: the fluted section's mass is that of
        the equivalent cylinder (``fluted_ratio²`` of the full circle's), which underestimates it.
        Given, the fluted section keeps the equivalent cylinder's bending stiffness and gets
        this mass per length (its density is scaled).
    """

    segments: tuple[ToolSegment, ...]
    material: str = "carbide"
    fluted_ratio: float = KOPS_VO_RATIO
    loss_factor: float = 0.0
    fluted_area_ratio: float | None = None

    @property
    def length(self) -> float:
        return float(sum(s.length for s in self.segments))


@dataclass(frozen=True)
class HolderSegment:
    """One holder section (m): outer diameter and bore (0 for solid)."""

    length: float
    outer_diameter: float
    inner_diameter: float = 0.0


@dataclass(frozen=True)
class Holder:
    """The tool holder, from its nose (tool side) towards the spindle."""

    segments: tuple[HolderSegment, ...]
    material: str = "steel"
    loss_factor: float = 0.0

    @property
    def length(self) -> float:
        return float(sum(s.length for s in self.segments))


@dataclass(frozen=True)
class MeasuredSpindle:
    """Spindle side given as a measured receptance at the holder connection point.

    Parameters
    ----------
    file
        UFF58 / HDF5 / CSV file (path as written in the stack file, resolved
        relative to it by the application layer).
    node
        Node number of the connection point in that file. The x plane needs
        ``node x`` and ``node ry`` (e.g. from the extension method, docs/theory.md §3);
        if ``node y`` and ``node rx`` are there too, the y plane is predicted
        from them, otherwise it is taken equal to the x plane (axisymmetric).
    frf
        The loaded FRF (set by :func:`jointdb.usecases.load_stack`; ``None`` until then).
    """

    file: str
    node: int
    frf: FRF | None = field(default=None, compare=False)


@dataclass(frozen=True)
class ModelledSpindle:
    """Spindle side as a beam model with bearing supports (``jointdb.fe`` model dict).

    ``model`` is the model description (a dict for :func:`jointdb.fe.model_from_dict`,
    or a path to such a JSON file, loaded by the application layer into a dict);
    ``point`` names the model point the holder is attached to.
    """

    model: Any
    point: str


@dataclass(frozen=True)
class JointChoice:
    """What one interface is made of.

    ``kind`` is one of

    - ``"rigid"``: no joint flexibility;
    - ``"explicit"``: constant ``k = (k_x [N/m], k_θ [N·m/rad])`` and
      ``c = (c_x [N·s/m], c_θ [N·m·s/rad])``;
    - ``"catalogued"``: a database joint pinned as ``name@version`` (or
      ``name@label``), in ``name`` / ``version``;
    - ``"query"``: the nearest catalogued joint of ``joint_type`` to
      ``conditions`` (keys ``materials``, ``torque_nm``, ``preload_n``,
      ``geometry``, ``extra``), optionally interpolating the ``k`` nearest.
    """

    kind: str
    k: tuple[float, float] | None = None
    c: tuple[float, float] | None = None
    name: str | None = None
    version: int | str | None = None
    joint_type: str | None = None
    conditions: Mapping[str, Any] | None = None
    neighbours: int = 3
    interpolate: bool = False

    @property
    def reference(self) -> str:
        """``name@version`` for a catalogued joint, a short description otherwise."""
        if self.kind == "catalogued":
            return f"{self.name}@{self.version}"
        if self.kind == "explicit":
            k, c = self.k or (0.0, 0.0), self.c or (0.0, 0.0)
            return f"k={k[0]:.4g} N/m, {k[1]:.4g} N·m/rad; c={c[0]:.4g} N·s/m, {c[1]:.4g} N·m·s/rad"
        if self.kind == "query":
            return f"nearest {self.joint_type} to {dict(self.conditions or {})}"
        return "rigid"


@dataclass(frozen=True)
class FrequencyGrid:
    """Prediction frequency lines ``fmin, fmin+step, ..., <= fmax`` in Hz (fmin > 0)."""

    fmin: float = 10.0
    fmax: float = 5000.0
    step: float = 5.0

    def lines(self):
        import numpy as np

        n = int(math.floor((self.fmax - self.fmin) / self.step + 1e-9)) + 1
        return self.fmin + self.step * np.arange(n)


@dataclass(frozen=True)
class StackSpec:
    """A tool / holder / spindle stack (see the module docstring for conventions).

    ``interfaces`` maps each of :data:`INTERFACE_NAMES` to a :class:`JointChoice`.
    ``frequency`` is the default prediction grid (a measured spindle FRF's
    own grid is used when ``frequency`` is not given in the file).
    """

    name: str
    tool: Tool
    holder: Holder
    spindle: MeasuredSpindle | ModelledSpindle
    gauge_length: float
    interfaces: Mapping[str, JointChoice]
    frequency: FrequencyGrid | None = None
    #: provenance: the catalogued parts the stack was assembled from, one mapping per slot (``slot``,
    #: ``part`` as ``name@version``, ``ref`` as written, ``kind``, ``record_sha256``, ``blob_sha256``),
    #: set by the application layer that resolved them (:func:`jointdb.usecases.resolve_stack_parts`)
    parts: tuple = field(default=(), compare=False)

    @property
    def insertion_length(self) -> float:
        """Tool length clamped in the holder [m]."""
        return self.tool.length - self.gauge_length

    def replace(self, **changes) -> "StackSpec":
        return replace(self, **changes)
