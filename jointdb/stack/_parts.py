"""Beam models of a stack's parts: the tool overhang and the holder with the clamped shank.

Node numbers used in the parts' FRFs (and in the predicted FRF):

=====  =======================================================
node   where
=====  =======================================================
1      tool tip (:data:`TIP_NODE`)
2      tool at the holder face (tool side of the tool–holder joint)
3      holder nose, at its face (holder side of the tool–holder joint)
4      holder base (holder side of the holder–spindle joint)
5      spindle nose (spindle side of the holder–spindle joint)
=====  =======================================================

The tool part is the overhang only (gauge length), free–free. The clamped
shank is part of the holder model: over the insertion length each holder
section and the tool shank inside it form one perfectly bonded composite
section, represented by a solid circle of the holder's outer diameter with an
equivalent material whose ``E I`` and ``ρ A`` equal the sums of the two
materials' (Schmitz & Duncan 2005, three-component RCSA). Rotary inertia and
shear stiffness of that equivalent section are approximations.
"""

from __future__ import annotations

import math

from jointdb.errors import InputError
from jointdb.fe import BeamModel, HystereticDamping, Material, NamedPoint, Segment, get_material
from jointdb.stack._spec import StackSpec

__all__ = ["TIP_NODE", "NODES", "tool_model", "holder_model", "composite_material"]

TIP_NODE = 1
NODES = {"tip": 1, "tool_base": 2, "holder_nose": 3, "holder_base": 4, "spindle_nose": 5}


def composite_material(holder: Material, tool: Material, outer: float, bore: float, shank: float) -> Material:
    """Equivalent material of a holder ring (``outer``, ``bore``) bonded to a solid tool shank (``shank``).

    The equivalent solid circle of diameter ``outer`` has
    ``E_eq I = E_h I_h + E_t I_t`` and ``ρ_eq A = ρ_h A_h + ρ_t A_t``; ν is the holder's.

    Parameters
    ----------
    holder, tool
        The holder's and the tool's :class:`jointdb.fe.Material`.
    outer
        Holder outer diameter [m].
    bore
        Holder bore diameter [m].
    shank
        Tool shank diameter [m] (<= ``bore``).

    Returns
    -------
    Material
        E_eq [Pa], ν, ρ_eq [kg/m³] of a solid circle of diameter ``outer``.
    """
    a_full, i_full = math.pi * outer**2 / 4, math.pi * outer**4 / 64
    a_h, i_h = math.pi * (outer**2 - bore**2) / 4, math.pi * (outer**4 - bore**4) / 64
    a_t, i_t = math.pi * shank**2 / 4, math.pi * shank**4 / 64
    e_eq = (holder.E * i_h + tool.E * i_t) / i_full
    rho_eq = (holder.rho * a_h + tool.rho * a_t) / a_full
    return Material(f"{holder.name}+{tool.name}", e_eq, holder.nu, rho_eq)


def _part_model(segments: list, ends: tuple, eta: float, max_element_length: float, name: str) -> BeamModel:
    """The free–free beam model of one part: its segments, its two named points ``(name, z [m],
    key of NODES)`` and hysteretic damping of loss factor ``eta`` (none when 0)."""
    return BeamModel(
        tuple(segments),
        points=tuple(NamedPoint(point, z, NODES[key]) for point, z, key in ends),
        ingredients=(HystereticDamping(eta),) if eta > 0 else (),
        max_element_length=max_element_length,
        name=name,
    )


def tool_model(spec: StackSpec, max_element_length: float = 0.005) -> BeamModel:
    """Free–free Timoshenko model of the tool overhang (tip at z = 0, holder face at the gauge length).

    Fluted sections use the equivalent diameter ``fluted_ratio × diameter``; with
    ``tool.fluted_area_ratio`` their density is scaled so that their mass per length is that
    of the true fluted section.
    Points: ``tip`` (node 1), ``base`` (node 2).

    Parameters
    ----------
    spec
        The stack (tool segments, material, gauge length in m, loss factor).
    max_element_length
        FE mesh size [m].

    Returns
    -------
    BeamModel
        Planar (x, ry) model, length = gauge length; hysteretic damping η = tool.loss_factor.

    Raises
    ------
    InputError
        Unknown tool material.

    Examples
    --------
    The 50 mm overhang of a 12 mm carbide tool: free–free, so two rigid-body modes, then the
    first bending mode, about 12 % below the Euler–Bernoulli value ``(4.7300² / 2π) √(EI / ρAL⁴)``
    for so stubby a beam (L/d = 4.2: shear and rotary inertia):

    >>> import numpy as np
    >>> from jointdb.fe import get_material
    >>> from jointdb.stack import stack_from_dict, tool_model
    >>> spec = stack_from_dict({
    ...     "format": "jointdb-stack/1", "name": "example",
    ...     "tool": {"material": "carbide", "segments": [{"length": 0.08, "diameter": 0.012}]},
    ...     "gauge_length": 0.05,
    ...     "holder": {"material": "steel", "segments": [{"length": 0.07, "outer_diameter": 0.05,
    ...                                                   "inner_diameter": 0.012}]},
    ...     "spindle": {"point": "nose", "model": {
    ...         "format": "jointdb-beam-model/1",
    ...         "segments": [{"length": 0.2, "outer_diameter": 0.07, "material": "steel"}],
    ...         "points": [{"name": "nose", "position": 0.0, "node": 5}], "clamps": [{"position": 0.2}]}},
    ...     "interfaces": {"tool-holder": "rigid", "holder-spindle": "rigid"}})
    >>> model = tool_model(spec)
    >>> [(p.name, p.position, p.node) for p in model.points]
    [('tip', 0.0, 1), ('base', 0.05, 2)]
    >>> modes = model.modes(3)
    >>> carbide, L, d = get_material("carbide"), 0.05, 0.012
    >>> EI, rhoA = carbide.E * np.pi * d**4 / 64, carbide.rho * np.pi * d**2 / 4
    >>> f_eb = 4.7300**2 / (2 * np.pi) * np.sqrt(EI / (rhoA * L**4))
    >>> modes.n_rigid, round(float(modes.freq_hz[2] / f_eb), 2)
    (2, 0.88)
    """
    tool = spec.tool
    material = get_material(tool.material)
    segments = []
    pos = 0.0
    for seg in tool.segments:
        if pos >= spec.gauge_length - 1e-12:
            break
        length = min(seg.length, spec.gauge_length - pos)
        diameter = seg.diameter * (tool.fluted_ratio if seg.fluted else 1.0)
        mat = material
        if seg.fluted and tool.fluted_area_ratio is not None:  # true mass per length, Kops–Vo stiffness
            scale = tool.fluted_area_ratio / tool.fluted_ratio**2
            mat = Material(f"{material.name} (fluted)", material.E, material.nu, material.rho * scale)
        segments.append(Segment(length, diameter, 0.0, mat))
        pos += length
    ends = (("tip", 0.0, "tip"), ("base", spec.gauge_length, "tool_base"))
    return _part_model(segments, ends, tool.loss_factor, max_element_length, f"{spec.name}: tool overhang")


def _inserted_shank(spec: StackSpec) -> list[tuple[float, float, float]]:
    """Tool pieces inside the holder as (from, to, diameter), depths measured from the holder face."""
    out = []
    pos = 0.0
    for seg in spec.tool.segments:
        start, end = pos, pos + seg.length
        pos = end
        if end <= spec.gauge_length + 1e-12:
            continue
        out.append((max(start, spec.gauge_length) - spec.gauge_length, end - spec.gauge_length, seg.diameter))
    return out


def holder_model(spec: StackSpec, max_element_length: float = 0.005) -> BeamModel:
    """Free–free model of the holder with the clamped tool shank (nose at z = 0).

    Points: ``nose`` (node 3, at the holder face), ``base`` (node 4, spindle side).
    Over the insertion length each section is the composite of
    :func:`composite_material` (Schmitz & Duncan 2005; docs/theory.md §4).

    Parameters
    ----------
    spec
        The stack (holder segments in m, materials, tool shank, gauge length).
    max_element_length
        FE mesh size [m].

    Returns
    -------
    BeamModel
        Planar (x, ry) model of length ``holder.length``.

    Raises
    ------
    InputError
        Unknown materials, or a holder bore smaller than the tool shank.
    """
    holder = spec.holder
    h_mat = get_material(holder.material)
    t_mat = get_material(spec.tool.material)
    shank = _inserted_shank(spec)
    cuts = {0.0, holder.length}
    pos = 0.0
    bounds = []
    for seg in holder.segments:
        bounds.append((pos, pos + seg.length, seg))
        cuts.add(pos + seg.length)
        pos += seg.length
    for a, b, _ in shank:
        cuts.update((a, b))
    cuts_sorted = sorted(cuts)
    merged = [cuts_sorted[0]]
    for c in cuts_sorted[1:]:
        if c - merged[-1] > 1e-12:
            merged.append(c)
    segments = []
    for a, b in zip(merged[:-1], merged[1:]):
        mid = 0.5 * (a + b)
        hseg = next(s for lo, hi, s in bounds if lo <= mid < hi)
        tool_d = next((d for lo, hi, d in shank if lo <= mid < hi), None)
        if tool_d is None:
            segments.append(Segment(b - a, hseg.outer_diameter, hseg.inner_diameter, h_mat))
            continue
        if tool_d > hseg.inner_diameter + 1e-12:  # stack_from_dict rejects this; guard direct use
            raise InputError(f"holder bore {hseg.inner_diameter:g} m is smaller than the tool shank {tool_d:g} m")
        mat = composite_material(h_mat, t_mat, hseg.outer_diameter, hseg.inner_diameter, tool_d)
        segments.append(Segment(b - a, hseg.outer_diameter, 0.0, mat))
    ends = (("nose", 0.0, "holder_nose"), ("base", holder.length, "holder_base"))
    return _part_model(segments, ends, holder.loss_factor, max_element_length, f"{spec.name}: holder with clamped shank")
