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
class _Segmented:
    """A part made of ``segments``, each with a ``length`` [m]."""

    @property
    def length(self) -> float:
        """Total length [m]: the sum of the segments' lengths."""
        return float(sum(s.length for s in self.segments))


@dataclass(frozen=True)
class ToolSegment:
    """One tool section, from the tip.

    Parameters
    ----------
    length
        Section length [m].
    diameter
        Cutter or shank diameter [m].
    fluted
        True for the cutting section: modelled as a solid cylinder of
        ``Tool.fluted_ratio × diameter``.
    """

    length: float
    diameter: float
    fluted: bool = False


@dataclass(frozen=True)
class Tool(_Segmented):
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


@dataclass(frozen=True)
class HolderSegment:
    """One holder section, from the nose.

    Parameters
    ----------
    length
        Section length [m].
    outer_diameter
        Outer diameter [m].
    inner_diameter
        Bore diameter [m] (0 for a solid section).
    """

    length: float
    outer_diameter: float
    inner_diameter: float = 0.0


@dataclass(frozen=True)
class Holder(_Segmented):
    """The tool holder, from its nose (tool side) towards the spindle.

    Parameters
    ----------
    segments
        :class:`HolderSegment` s from the nose.
    material
        A name known to :func:`jointdb.fe.get_material`.
    loss_factor
        Structural (hysteretic) loss factor η of the holder's beam model.
    """

    segments: tuple[HolderSegment, ...]
    material: str = "steel"
    loss_factor: float = 0.0


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
    estimate
        How ``frf`` was estimated from extension-bar taps
        (:class:`jointdb.stack._spindle_band.SpindleEstimate`), for the band's spindle-estimate term;
        ``None``: the spindle is taken as exact.
    """

    file: str
    node: int
    frf: FRF | None = field(default=None, compare=False)
    estimate: Any = field(default=None, compare=False)


@dataclass(frozen=True)
class ModelledSpindle:
    """Spindle side as a beam model with bearing supports (``jointdb.fe`` model dict).

    Parameters
    ----------
    model
        The model description (a dict for :func:`jointdb.fe.model_from_dict`, or a path to
        such a JSON file, loaded by the application layer into a dict), or a
        :class:`jointdb.fe.BeamModel`.
    point
        The model point the holder is attached to.
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

    Parameters
    ----------
    kind
        ``"rigid"``, ``"explicit"``, ``"catalogued"`` or ``"query"`` (above).
    k, c
        Explicit stiffness ``(k_x, k_θ)`` [N/m, N·m/rad] and damping ``(c_x, c_θ)``
        [N·s/m, N·m·s/rad].
    name, version
        A catalogued joint's name and version number or label.
    joint_type
        The joint type a query searches (``"tool-holder"``, ``"holder-spindle"``).
    conditions
        The query's conditions (SI units: torque in N·m, preload in N, geometry in m).
    neighbours
        How many nearest joints a query reports (and interpolates between).
    interpolate
        Interpolate between the neighbours instead of taking the nearest.
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
    """Prediction frequency lines ``fmin, fmin+step, ..., <= fmax`` in Hz.

    Parameters
    ----------
    fmin
        First line [Hz], > 0.
    fmax
        Last line at most [Hz].
    step
        Line spacing [Hz].
    """

    fmin: float = 10.0
    fmax: float = 5000.0
    step: float = 5.0

    def lines(self):
        """The frequency lines [Hz].

        Returns
        -------
        ndarray, shape (n,)
        """
        import numpy as np

        n = int(math.floor((self.fmax - self.fmin) / self.step + 1e-9)) + 1
        return self.fmin + self.step * np.arange(n)


@dataclass(frozen=True)
class StackSpec:
    """A tool / holder / spindle stack (see the module docstring for conventions).

    Parameters
    ----------
    name
        Free text.
    tool
        The :class:`Tool`.
    holder
        The :class:`Holder`.
    spindle
        A :class:`MeasuredSpindle` or :class:`ModelledSpindle`.
    gauge_length
        Tool overhang from the holder face to the tip [m].
    interfaces
        Each of :data:`INTERFACE_NAMES` → a :class:`JointChoice`.
    frequency
        The default prediction grid (:class:`FrequencyGrid`); a measured spindle FRF's own
        grid is used when it is not given.
    parts
        Provenance, not compared: the catalogued parts the stack was assembled from, one mapping
        per slot (``slot``, ``part`` as ``name@version``, ``ref`` as written, ``kind``,
        ``record_sha256``, ``blob_sha256``); empty for a stack written out in full. Set by the
        application layer that resolved the references (:func:`jointdb.usecases.resolve_stack_parts`).
    """

    name: str
    tool: Tool
    holder: Holder
    spindle: MeasuredSpindle | ModelledSpindle
    gauge_length: float
    interfaces: Mapping[str, JointChoice]
    frequency: FrequencyGrid | None = None
    parts: tuple = field(default=(), compare=False)

    @property
    def insertion_length(self) -> float:
        """Tool length clamped in the holder [m]."""
        return self.tool.length - self.gauge_length

    def replace(self, **changes) -> "StackSpec":
        """A copy with some fields replaced.

        Parameters
        ----------
        **changes
            Field name → new value.

        Returns
        -------
        StackSpec
        """
        return replace(self, **changes)
