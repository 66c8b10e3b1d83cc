"""Tool-tip FRF prediction of a stack from its parts and resolved joints (docs/theory.md §4).

Pure numerics: the joints of catalogued / queried interfaces arrive already
resolved as FRFs (the application layer, :mod:`jointdb.usecases`, fetches them from
the database); a measured spindle FRF arrives attached to the spec.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from jointdb.errors import InputError
from jointdb.fe import BeamModel, model_from_dict
from jointdb.frf import FRF, Dof, Quantity
from jointdb.stack._chain import tool_tip_chain
from jointdb.stack._partcache import cached_part, spindle_key
from jointdb.stack._parts import NODES, TIP_NODE, holder_model, tool_model
from jointdb.stack._twoplane import spindle_four, two_plane_tip
from jointdb.stack._spec import INTERFACE_NAMES, FrequencyGrid, MeasuredSpindle, ModelledSpindle, StackSpec

__all__ = ["Prediction", "predict_tool_tip", "prediction_grid", "stack_parts", "spindle_model"]

#: Planar (x, θ) view of the y bending plane: θ_y = +dy/dz = −rx.
_Y_PLANE = np.diag([1.0, -1.0])


@dataclass(frozen=True, eq=False)
class Prediction:
    """A predicted tool-tip receptance.

    Attributes
    ----------
    tip
        Receptance at the tool tip, outputs = inputs = ``(1x, 1y)`` [m/N]
        (x and y planes; cross terms H[1x,1y], H[1y,1x] when the spindle FRF couples the planes,
        zero otherwise).
    rigid
        The same stack with every interface rigid (for comparison).
    tip_rotation
        Full planar 2×2 tip blocks per plane, ``{"x": (n_freq, 2, 2), "y": ...}``
        over (translation, rotation θ = +d(displacement)/dz); with coupled planes also
        ``"xy"``: the (n_freq, 4, 4) block over (x, θ_x, y, θ_y).
    interfaces
        Interface name → what was used there (``"rigid"``, ``"k=..."``, ``"th@3"`` ...).
    notes
        Modelling assumptions worth telling the user (e.g. y plane taken equal to x).
    """

    tip: FRF
    rigid: FRF
    tip_rotation: Mapping[str, np.ndarray]
    interfaces: Mapping[str, str]
    notes: tuple[str, ...]

    def summary(self) -> list[dict]:
        """Per direction: dominant peak (frequency, |H|) with the joints and with rigid joints.

        Returns
        -------
        list of dict
            One row per direction.
        """
        rows = []
        for k, dof in enumerate(self.tip.outputs):
            h = np.abs(self.tip.values[:, k, k])
            r = np.abs(self.rigid.values[:, k, k])
            i, j = int(np.argmax(h)), int(np.argmax(r))
            rows.append({
                "direction": dof.direction,
                "peak_hz": float(self.tip.freq[i]),
                "peak_m_per_n": float(h[i]),
                "min_real_m_per_n": float(self.tip.values[:, k, k].real.min()),
                "rigid_peak_hz": float(self.rigid.freq[j]),
                "rigid_peak_m_per_n": float(r[j]),
            })
        return rows


def spindle_model(spec: StackSpec) -> BeamModel:
    """The spindle's beam model of a :class:`ModelledSpindle` stack.

    Parameters
    ----------
    spec
        A stack with a :class:`ModelledSpindle` whose model is a dict or a BeamModel.

    Returns
    -------
    BeamModel
        The spindle's model as given, or read from its dict.

    Raises
    ------
    InputError
        If the spindle is measured, or its model is still a file path.
    """
    sp = spec.spindle
    if not isinstance(sp, ModelledSpindle):
        raise InputError("spindle: this stack has a measured spindle FRF, not a beam model")
    if isinstance(sp.model, BeamModel):
        return sp.model
    if isinstance(sp.model, str):
        raise InputError(f"spindle.model: {sp.model!r} is a file path; load the stack with jointdb.usecases.load_stack")
    try:
        return model_from_dict(sp.model)
    except InputError as exc:
        raise InputError(f"spindle.model.{exc}") from None


def prediction_grid(spec: StackSpec, freq=None) -> np.ndarray:
    """Frequency lines [Hz] of a prediction: ``freq`` if given, else the stack file's
    ``frequency``, else a measured spindle FRF's own lines above 0 Hz, else 10–5000 Hz by 5 Hz.

    Parameters
    ----------
    spec
        The stack.
    freq
        Explicit lines [Hz], ``(n_freq,)``, or None.

    Returns
    -------
    ndarray
        ``(n_freq,)`` strictly increasing lines, all > 0 Hz.

    Raises
    ------
    InputError
        Empty, non-finite, non-positive or non-increasing lines.
    """
    if freq is not None:
        out = np.asarray(freq, dtype=float)
    elif spec.frequency is not None:
        out = spec.frequency.lines()
    elif isinstance(spec.spindle, MeasuredSpindle) and spec.spindle.frf is not None:
        out = spec.spindle.frf.freq[spec.spindle.frf.freq > 0]
    else:
        out = FrequencyGrid().lines()
    if out.ndim != 1 or out.size == 0:
        raise InputError("frequency: need a non-empty 1-D list of lines")
    if np.any(out <= 0) or not np.all(np.isfinite(out)):
        raise InputError("frequency: all lines must be finite and > 0 Hz (the tool and holder are free-free)")
    if out.size > 1 and not np.all(np.diff(out) > 0):
        raise InputError("frequency: lines must be strictly increasing")
    return out


def _on_grid(frf: FRF, freq: np.ndarray, what: str) -> FRF:
    try:
        frf = frf.to(Quantity.RECEPTANCE)
    except InputError as exc:
        raise InputError(f"{what}: {exc}") from None
    if frf.n_freq == freq.size and np.allclose(frf.freq, freq, rtol=1e-12, atol=0):
        return frf
    try:
        return frf.resample(freq)
    except InputError:
        raise InputError(
            f"{what} covers {frf.freq[0]:g}–{frf.freq[-1]:g} Hz but the prediction needs "
            f"{freq[0]:g}–{freq[-1]:g} Hz; "
            "narrow the stack's 'frequency' range"
        ) from None


def _planes(frf: FRF, what: str, node: int | None = None) -> tuple[dict[str, np.ndarray], bool]:
    """Planar (x, θ) 2×2 blocks per bending plane; second value: y plane was present."""
    outs = [d for d in frf.outputs if node is None or d.node == node]

    def find(direction: str) -> Dof | None:
        return next((d for d in outs if d.direction == direction), None)

    dx, dry = find("x"), find("ry")
    if dx is None or dry is None:
        have = " ".join(str(d) for d in frf.outputs)
        where = f" at node {node}" if node is not None else ""
        raise InputError(f"{what} needs x and ry DOFs{where} (translation and rotation); it has: {have}")
    try:
        sq = frf.complete_reciprocal()
    except InputError as exc:
        raise InputError(f"{what}: {exc}") from None
    planes = {"x": sq.block([dx, dry], [dx, dry])}
    dy, drx = find("y"), find("rx")
    if dy is not None and drx is not None:
        planes["y"] = _Y_PLANE @ sq.block([dy, drx], [dy, drx]) @ _Y_PLANE
        return planes, True
    planes["y"] = planes["x"]
    return planes, False


def stack_parts(spec: StackSpec, freq=None) -> dict[str, FRF]:
    """Free receptances of the parts: ``tool`` (nodes 1, 2), ``holder`` (3, 4), ``spindle`` (node 5 for a model,
    the file's node for a measurement), all on the prediction grid.

    Parameters
    ----------
    spec
        The stack (a measured spindle must have its FRF attached).
    freq
        Frequency lines [Hz]; default :func:`prediction_grid`.

    Returns
    -------
    dict[str, FRF]
        ``"tool"``, ``"holder"``: 4×4 receptances over (x, ry) at their two
        points; ``"spindle"``: the spindle side at its nose (m/N, rad/(N·m), ...).

    Raises
    ------
    InputError
        Bad grid, a spindle file not loaded or not covering the grid.
    """
    f = prediction_grid(spec, freq)
    shape = (spec.tool, spec.holder, spec.gauge_length)  # everything the tool and holder models read
    parts = {
        "tool": cached_part("tool", shape, f, lambda: tool_model(spec).frf(f, ["tip", "base"])),
        "holder": cached_part("holder", shape, f, lambda: holder_model(spec).frf(f, ["nose", "base"])),
    }
    sp = spec.spindle
    if isinstance(sp, MeasuredSpindle):
        if sp.frf is None:
            raise InputError(f"spindle.file: {sp.file!r} is not loaded; load the stack with jointdb.usecases.load_stack")
        parts["spindle"] = _on_grid(sp.frf, f, f"spindle.file {sp.file!r}")
    else:
        key = spindle_key(sp.model)
        parts["spindle"] = cached_part("spindle", None if key is None else (key, sp.point), f,
                                       lambda: _modelled_spindle_frf(spec, f))
    return parts


def _modelled_spindle_frf(spec: StackSpec, f: np.ndarray) -> FRF:
    """The modelled spindle's receptance at its nose point (node ``NODES["spindle_nose"]``)."""
    model = spindle_model(spec)
    point = model.point(spec.spindle.point)
    dirs = ("x", "ry") if model.kind == "planar" else ("x", "y", "rx", "ry")
    frf = model.frf(f, [point.name], directions=dirs)
    return frf.replace(outputs=tuple(Dof(NODES["spindle_nose"], d.direction) for d in frf.outputs),
                       inputs=tuple(Dof(NODES["spindle_nose"], d.direction) for d in frf.inputs))


def _joint_planes(name: str, spec: StackSpec, resolved: Mapping[str, FRF], f: np.ndarray):
    choice = spec.interfaces[name]
    if name in resolved and resolved[name] is not None:
        frf = resolved[name]
        if not isinstance(frf, FRF):
            raise InputError(f"interfaces.{name}: the resolved joint must be an FRF, got {type(frf).__name__}")
        planes, _ = _planes(_on_grid(frf, f, f"interfaces.{name} joint"), f"interfaces.{name} joint")
        label = choice.reference if choice.kind == "catalogued" else "resolved joint FRF"
        return planes, label
    if choice.kind == "rigid":
        return None, "rigid"
    if choice.kind == "explicit":
        k, c = np.asarray(choice.k, float), np.asarray(choice.c, float)
        w = 2 * np.pi * f
        vals = np.zeros((f.size, 2, 2), dtype=complex)
        vals[:, 0, 0] = 1.0 / (k[0] + 1j * w * c[0])
        vals[:, 1, 1] = 1.0 / (k[1] + 1j * w * c[1])
        return {"x": vals, "y": vals}, choice.reference
    raise InputError(
        f"interfaces.{name}: {choice.reference} must be resolved from the joint database first "
        "(use jointdb.usecases.predict_stack, or pass resolved_joints)"
    )


def predict_tool_tip(spec: StackSpec, resolved_joints: Mapping[str, FRF] | None = None, freq=None) -> Prediction:
    """Predict the tool-tip receptance of a stack (three-component RC, docs/theory.md §4).

    Parameters
    ----------
    spec
        The stack (a measured spindle must have its FRF attached).
    resolved_joints
        Interface name (``"tool-holder"``, ``"holder-spindle"``) → joint
        receptance FRF with DOFs ``x`` and ``ry`` (and optionally ``y``,
        ``rx`` for the y plane), required for catalogued / queried
        interfaces; it overrides the spec for any interface it names.
    freq
        Frequency lines [Hz], all > 0; default :func:`prediction_grid`.

    Returns
    -------
    Prediction
        Tip receptance in x and y, the rigid-joint prediction, and notes.

    Raises
    ------
    InputError
        Unresolved catalogued joints, joint/spindle FRFs that do not cover the
        grid or lack rotational DOFs, bad grids.
    NumericalError
        Singular interface matrix at some line.

    Examples
    --------
    A 12 mm carbide tool at 50 mm gauge length in a steel chuck on a clamped spindle shaft. The
    tool–holder joint (k [N/m, N·m/rad], c [N·s/m, N·m·s/rad]) moves the dominant tip mode far
    below the rigid-joint prediction; a stiffer joint tends to the rigid one, the gap as 1/k:

    >>> import numpy as np
    >>> from jointdb.stack import stack_from_dict, predict_tool_tip
    >>> spindle = {"segments": [{"length": 0.2, "outer_diameter": 0.07, "material": "steel"}],
    ...            "points": [{"name": "nose", "position": 0.0, "node": 5}], "clamps": [{"position": 0.2}]}
    >>> def stack(tool_holder):
    ...     return stack_from_dict({"name": "example", "gauge_length": 0.05,
    ...         "tool": {"material": "carbide", "segments": [{"length": 0.08, "diameter": 0.012}]},
    ...         "holder": {"material": "steel", "segments": [
    ...             {"length": 0.04, "outer_diameter": 0.032, "inner_diameter": 0.012},
    ...             {"length": 0.03, "outer_diameter": 0.05}]},
    ...         "spindle": {"point": "nose", "model": spindle}, "frequency": {"min": 100, "max": 6000, "step": 20},
    ...         "interfaces": {"tool-holder": tool_holder, "holder-spindle": "rigid"}})
    >>> p = predict_tool_tip(stack({"k": [2e7, 1e6], "c": [100.0, 5.0]}))
    >>> p.tip.shape, [str(dof) for dof in p.tip.outputs]          # (n_freq, n_out, n_in), receptance m/N
    ((296, 2, 2), ['1x', '1y'])
    >>> peak_hz = [float(f.freq[np.argmax(np.abs(f.entry("1x", "1x")))]) for f in (p.tip, p.rigid)]
    >>> peak_hz[0] < 0.5 * peak_hz[1]
    True
    >>> def gap(k, k_rot):
    ...     s = predict_tool_tip(stack({"k": [k, k_rot], "c": [0.0, 0.0]}))
    ...     return np.abs(s.tip.values - s.rigid.values).max() / np.abs(s.rigid.values).max()
    >>> g1, g2 = gap(1e12, 1e10), gap(1e13, 1e11); bool(g2 < 2e-3 and 8 < g1 / g2 < 12)
    True
    """
    resolved = dict(resolved_joints or {})
    unknown = set(resolved) - set(INTERFACE_NAMES)
    if unknown:
        raise InputError(f"resolved_joints: unknown interface(s) {sorted(unknown)}; expected {list(INTERFACE_NAMES)}")
    f = prediction_grid(spec, freq)
    parts = stack_parts(spec, f)
    tool, holder = parts["tool"].values, parts["holder"].values
    notes: list[str] = []
    spindle_node = spec.spindle.node if isinstance(spec.spindle, MeasuredSpindle) else NODES["spindle_nose"]
    spindle, has_y = _planes(parts["spindle"], "spindle FRF", spindle_node)
    if not has_y:
        notes.append("y plane taken equal to the x plane (spindle side given for x only; axisymmetric stack)")
    joints, labels = {}, {}
    for name in INTERFACE_NAMES:
        joints[name], labels[name] = _joint_planes(name, spec, resolved, f)
    out = (Dof(TIP_NODE, "x"), Dof(TIP_NODE, "y"))
    spindle4 = spindle_four(parts["spindle"], spindle_node) if has_y else None
    if spindle4 is not None:  # the spindle couples the planes: one chain over (x, θx, y, θy)
        tip4 = two_plane_tip(tool, holder, spindle4, joints["tool-holder"], joints["holder-spindle"])
        rigid4 = two_plane_tip(tool, holder, spindle4)
        notes.append("x and y planes coupled through the spindle FRF's cross terms; the tip FRF has H[1x,1y], H[1y,1x]")

        def full(b4):
            return FRF(f, b4[:, [0, 2]][:, :, [0, 2]], out, out,
                       Quantity.RECEPTANCE)

        tips = {"x": tip4[:, :2, :2], "y": tip4[:, 2:, 2:], "xy": tip4}
        return Prediction(full(tip4), full(rigid4), tips, labels, tuple(notes))
    tips, rigid = {}, {}
    for plane in ("x", "y"):
        jt = joints["tool-holder"][plane] if joints["tool-holder"] is not None else None
        jh = joints["holder-spindle"][plane] if joints["holder-spindle"] is not None else None
        tips[plane] = tool_tip_chain(tool, holder, spindle[plane], jt, jh)
        rigid[plane] = tool_tip_chain(tool, holder, spindle[plane])

    def diag(blocks):
        v = np.zeros((f.size, 2, 2), dtype=complex)
        v[:, 0, 0] = blocks["x"][:, 0, 0]
        v[:, 1, 1] = blocks["y"][:, 0, 0]
        return FRF(f, v, out, out, Quantity.RECEPTANCE)

    return Prediction(diag(tips), diag(rigid), tips, labels, tuple(notes))
