"""Substructure A of a tool–holder campaign from catalogued parts: the holder on the spindle, through a
catalogued holder–spindle (taper) joint (``jointdb campaign init --spindle --holder --through-joint``).

A tool–holder identification test measures a test tool (substructure B, free–free) clamped in a holder that
sits on the spindle. IRC needs A = everything behind the tool–holder contact: the holder *with the clamped
shank stub* on the spindle, as the receptance at the holder nose including rotations. With the spindle and the
holder catalogued as parts (``jointdb parts add``) and the taper joint catalogued from a holder–spindle
campaign, A is one receptance-coupling step (docs/theory.md §4, :func:`jointdb.stack.attach`)::

    G_33 = H_33 − H_34 (H_44 + S_55 + J_hs)⁻¹ H_43

with ``H`` the free–free holder with the shank stub (nose node 3, base node 4; the composite section of
:func:`jointdb.stack.holder_model`), ``S_55`` the spindle at its nose and ``J_hs`` the catalogued joint. The
same code path as ``jointdb predict`` builds the parts (:func:`jointdb.usecases.stack_from_document`,
:func:`jointdb.usecases.resolve_joints`), so a campaign and a later prediction see the same holder, spindle and
taper joint. Planar: the x bending plane (a spindle with a y plane is used in x).
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from jointdb.errors import InputError
from jointdb.frf import FRF, Dof, Quantity

__all__ = ["SubstructureA", "through_joint_choice", "holder_on_spindle"]

#: The node of the holder nose in the result (the tool side of the tool–holder joint: A's contact point).
A_NODE = 3


@dataclass(frozen=True, eq=False)
class SubstructureA:
    """The holder (with the shank stub) on the spindle through the taper joint, at the holder nose.

    Attributes
    ----------
    frf
        Receptance over ``(3x, 3ry)`` × ``(3x, 3ry)`` [m/N, rad/N, m/(N·m), rad/(N·m)], ``(n_freq, 2, 2)``.
    provenance
        Which parts (name@version, record SHA-256), which joint (name@version, how it was chosen, distance)
        and which shank stub were used: JSON-able, written into the campaign file.
    """

    frf: FRF
    provenance: Mapping[str, Any]


def through_joint_choice(text: str) -> Any:
    """The stack-file interface value of a ``--through-joint`` argument.

    Parameters
    ----------
    text
        ``NAME@VERSION`` or ``NAME@LABEL`` (a catalogued joint), ``rigid``, or a JSON object: a query
        (``{"joint_type": "holder-spindle", "preload_n": 18000, ...}``, the nearest catalogued joint),
        ``{"query": {...}}``, or an explicit spring–damper ``{"k": [k_x, k_θ], "c": [c_x, c_θ]}``.

    Returns
    -------
    str or dict
        The value of ``interfaces.holder-spindle`` of a stack file.

    Raises
    ------
    InputError
        Neither a reference nor a JSON object.
    """
    text = text.strip()
    if text == "rigid":
        return text
    if text.startswith("{"):
        try:
            obj = json.loads(text)
        except ValueError as exc:
            raise InputError(f"--through-joint: not valid JSON ({exc.msg} at character {exc.pos})") from None
        if not isinstance(obj, dict):
            raise InputError("--through-joint: a JSON value must be an object")
        return obj if ("query" in obj or "k" in obj) else {"query": obj}
    if "@" not in text:
        raise InputError(f"--through-joint {text!r}: give NAME@VERSION, NAME@LABEL, rigid or a JSON query "
                         "such as '{\"joint_type\": \"holder-spindle\", \"preload_n\": 18000}'")
    return text


def _stack_document(spindle: str, holder: str, joint: Any, shank_diameter: float, shank_material: str,
                    insertion: float, freq: np.ndarray) -> dict:
    """A stack document whose tool is the shank stub alone (the tool–holder joint rigid: it is not used)."""
    for value, flag in ((shank_diameter, "--shank-diameter"), (insertion, "--insertion")):
        if not (np.isfinite(value) and value > 0):
            raise InputError(f"{flag} {value!r}: must be a positive length in metres")
    return {
        "format": "jointdb-stack/1", "name": "substructure A: holder on spindle",
        # a 1 mm overhang: the tool part is not coupled, only its inserted shank goes into the holder model
        "tool": {"material": shank_material, "segments": [{"length": insertion + 1e-3, "diameter": shank_diameter}]},
        "gauge_length": 1e-3,
        "holder": {"part": holder}, "spindle": {"part": spindle},
        "interfaces": {"tool-holder": "rigid", "holder-spindle": joint},
    }


def _x_plane(frf: FRF, node: int | None, what: str) -> np.ndarray:
    """The (x, ry) 2×2 block of an FRF at ``node`` (any node when None), receptance, reciprocity-completed."""
    frf = frf.to(Quantity.RECEPTANCE).complete_reciprocal()
    pick = [d for d in frf.outputs if node is None or d.node == node]
    dx = next((d for d in pick if d.direction == "x"), None)
    dr = next((d for d in pick if d.direction == "ry"), None)
    if dx is None or dr is None:
        raise InputError(f"{what} has no x and ry DOFs{'' if node is None else f' at node {node}'} "
                         f"(it has {' '.join(map(str, frf.outputs))})")
    return frf.block([dx, dr], [dx, dr])


def _on(frf: FRF, freq: np.ndarray, what: str) -> FRF:
    if frf.n_freq == freq.size and np.allclose(frf.freq, freq, rtol=1e-12, atol=0):
        return frf
    try:
        return frf.to(Quantity.RECEPTANCE).resample(freq)
    except InputError:
        raise InputError(f"{what} covers {frf.freq[0]:g}–{frf.freq[-1]:g} Hz; the campaign's measurements need "
                         f"{freq[0]:g}–{freq[-1]:g} Hz") from None


def _joint_block(spec, joint, freq: np.ndarray) -> np.ndarray | None:
    """The holder–spindle joint's receptance over (x, ry), ``(n_freq, 2, 2)``; None for a rigid joint."""
    if joint.frf is not None:
        return _x_plane(_on(joint.frf, freq, "the holder–spindle joint"), None, "the holder–spindle joint")
    if joint.kind != "explicit":
        return None
    choice = spec.interfaces["holder-spindle"]
    z = np.asarray(choice.k, float)[None, :] + 2j * np.pi * freq[:, None] * np.asarray(choice.c, float)[None, :]
    out = np.zeros((freq.size, 2, 2), dtype=complex)
    out[:, 0, 0], out[:, 1, 1] = 1.0 / z[:, 0], 1.0 / z[:, 1]
    return out


def holder_on_spindle(freq, *, spindle: str, holder: str, through_joint: Any, shank_diameter: float,
                      shank_material: str, insertion: float, store=None) -> SubstructureA:
    """Substructure A of a tool–holder campaign: the catalogued holder with a shank stub on the catalogued
    spindle through a catalogued holder–spindle joint, at the holder nose (module docstring).

    Parameters
    ----------
    freq
        The campaign's frequency lines [Hz], ``(n_freq,)``, all > 0 (the measurements' grid).
    spindle, holder
        Catalogued parts, ``NAME@VERSION`` or ``NAME@LABEL`` (``jointdb parts add``).
    through_joint
        The holder–spindle joint as a stack interface value (:func:`through_joint_choice`).
    shank_diameter
        Diameter [m] of the test tool's shank clamped in the holder.
    shank_material
        Its material (a name :func:`jointdb.fe.get_material` knows, e.g. ``carbide``).
    insertion
        Clamped length [m] of the shank inside the holder bore, from the holder face.
    store
        A joint store, database URL or path (None: ``$JOINTDB_URL`` or the per-user database).

    Returns
    -------
    SubstructureA
        Receptance over ``(3x, 3ry)`` on ``freq`` and the provenance of the parts and joint used.

    Raises
    ------
    NotFoundError
        An unknown part or joint (version, label), or no catalogued joint of a queried type.
    InputError
        A part of the wrong kind, a joint without x and ry, a shank wider than the holder bore, bad lengths.
    """
    from jointdb.stack import attach, stack_parts
    from jointdb.usecases._stack import _open_repo, resolve_joints
    from jointdb.usecases._parts import stack_from_document

    freq = np.asarray(freq, dtype=float)
    doc = _stack_document(spindle, holder, through_joint, shank_diameter, shank_material, insertion, freq)
    handle, owned = _open_repo(store)
    try:
        spec = stack_from_document(doc, handle)
        joint = resolve_joints(spec, handle)["holder-spindle"]
    finally:
        if owned:
            handle.close()
    parts = stack_parts(spec, freq)
    h = parts["holder"].values
    node = spec.spindle.node if getattr(spec.spindle, "frf", None) is not None else None
    s = _x_plane(parts["spindle"], node, "the spindle")
    j = _joint_block(spec, joint, freq)
    g = attach(h[:, :2, :2], h[:, :2, 2:], h[:, 2:, :2], h[:, 2:, 2:], s, j)
    dofs = (Dof(A_NODE, "x"), Dof(A_NODE, "ry"))
    frf = FRF(freq, g, dofs, dofs, Quantity.RECEPTANCE)
    row = joint.row()
    provenance = {
        "built_by": "jointdb campaign init --spindle --holder --through-joint",
        "parts": [{"slot": p["slot"], "part": p["part"], "record_sha256": p["record_sha256"]} for p in spec.parts],
        "through_joint": {"interface": "holder-spindle", "method": row["method"], "joint": row["joint"],
                          "distance": row["distance"], "joints_used": row["joints_used"],
                          "warnings": row["warnings"]},
        "shank_stub": {"diameter_m": float(shank_diameter), "material": shank_material,
                       "insertion_m": float(insertion)},
        "plane": "x", "contact": "holder nose (node 3)",
    }
    return SubstructureA(frf, provenance)


#: File name of substructure A in the campaign folder (UFF58 receptance, ``3x 3ry``).
A_FILE = "holder-on-spindle.uff"


def measurement_grid(folder) -> np.ndarray:
    """The frequency lines [Hz] of a campaign folder's measured assembly files (UFF58, translations only).

    Parameters
    ----------
    folder
        The campaign folder.

    Returns
    -------
    ndarray
        ``(n_freq,)`` lines shared by every measurement file.

    Raises
    ------
    InputError
        No measurement file, files on different grids, or a 0 Hz line (free–free parts have no static
        receptance: measure from a line above 0 Hz or give ``band`` later).
    """
    from pathlib import Path

    from jointdb.io import read_frf_uff58

    grids = []
    for p in sorted(Path(folder).iterdir()):
        if p.suffix.lower() not in (".uff", ".unv", ".uff58", ".uf", ".58") or not p.is_file() or p.name == A_FILE:
            continue
        try:
            frf = read_frf_uff58(p)
        except InputError as exc:
            raise InputError(f"{p.name}: {exc}") from None
        if any(d.is_rotation for d in (*frf.outputs, *frf.inputs)):
            continue
        grids.append((p.name, frf.freq))
    if not grids:
        raise InputError(f"{folder}: no measured assembly UFF58 file (translations only) to take the frequency "
                         "lines of substructure A from")
    name, freq = grids[0]
    for other, f in grids[1:]:
        if f.shape != freq.shape or not np.allclose(f, freq, rtol=1e-9, atol=1e-9):
            raise InputError(f"{other} and {name} have different frequency lines; one grid per campaign")
    if freq[0] <= 0:
        raise InputError(f"{name} starts at {freq[0]:g} Hz; substructure A is computed above 0 Hz only "
                         "(drop the 0 Hz line from the measurement)")
    return freq


def write_substructure_a(folder, *, force: bool = False, **parts) -> tuple[Any, SubstructureA]:
    """Compute substructure A on the grid of ``folder``'s measurements and write it there as UFF58.

    Parameters
    ----------
    folder
        The campaign folder (measured assembly UFF58 files and substructure B's model).
    force
        Overwrite an existing :data:`A_FILE`.
    **parts
        The keyword arguments of :func:`holder_on_spindle` but ``freq``.

    Returns
    -------
    (Path, SubstructureA)
        The file written (``folder / A_FILE``) and what it holds.

    Raises
    ------
    InputError
        As :func:`measurement_grid` and :func:`holder_on_spindle`; the file exists and ``force`` is false.
    NotFoundError
        As :func:`holder_on_spindle`.
    """
    from pathlib import Path

    from jointdb.usecases._files import write_frf_file

    target = Path(folder) / A_FILE
    if target.exists() and not force:
        raise InputError(f"{target}: exists (substructure A of an earlier run); give --force to overwrite")
    sub = holder_on_spindle(measurement_grid(folder), **parts)
    write_frf_file(target, sub.frf, binary=True)  # 58b: exact doubles
    return target, sub
