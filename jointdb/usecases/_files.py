"""Files the use cases read and write: FRF files by suffix, stack files (with the spindle
FRF or model file they name), and the HDF5 joint exchange file of ``jointdb identify``."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from jointdb.schemas._jsonfile import read_json_file
from jointdb.errors import InputError, NotFoundError
from jointdb.frf import FRF
from jointdb.stack import MeasuredSpindle, ModelledSpindle, StackSpec

#: ``joint_model`` of a campaign / `jointdb identify` file -> model kind of the catalogue
MODEL_KINDS = {"planar": "spring-damper-planar", "n-point": "n-point-translational", "matrix": "full-matrix"}

#: FRF file formats by suffix (reading and writing).
FRF_SUFFIXES = {".uff": "uff58", ".unv": "uff58", ".uff58": "uff58", ".uf": "uff58", ".58": "uff58",
                ".h5": "hdf5", ".hdf5": "hdf5", ".hdf": "hdf5", ".csv": "csv"}


def frf_format(path: Path | str, option: str = "") -> str:
    """The FRF file format a suffix names.

    Parameters
    ----------
    path
        The file name.
    option
        The command-line option or field that gave it, named in the error.

    Returns
    -------
    str
        ``"uff58"``, ``"hdf5"`` or ``"csv"``.

    Raises
    ------
    InputError
        An unknown suffix.
    """
    p = Path(path)
    fmt = FRF_SUFFIXES.get(p.suffix.lower())
    if fmt is None:
        where = f"{option} {str(p)!r}" if option else str(p)
        raise InputError(f"{where}: unknown FRF file type {p.suffix.lower()!r}; use .uff/.unv (UFF58), "
                         ".h5/.hdf5 or .csv")
    return fmt


def read_frf_file(path: Path | str, fill: str = "error") -> FRF:
    """Read an FRF from UFF58 (``.uff``, ``.unv``), HDF5 (``.h5``, ``.hdf5``) or CSV by suffix.

    Parameters
    ----------
    path
        The file.
    fill
        For UFF58 records that do not cover every (output, input) pair: ``"reciprocity"``
        completes a missing H[i, j] from H[j, i] (:func:`jointdb.io.read_frf_uff58`); ``"error"`` refuses.

    Returns
    -------
    FRF

    Raises
    ------
    NotFoundError, InputError
    """
    from jointdb import io

    p = Path(path)
    fmt = frf_format(p)
    if not p.exists():
        raise NotFoundError(f"FRF file {p} does not exist")
    if fmt == "uff58":
        return io.read_frf_uff58(p, fill=fill)
    if fmt == "hdf5":
        return io.read_frf_hdf5(p)
    return io.read_frf_csv(p)


def write_frf_file(path: Path | str, frf: FRF, *, binary: bool = False, round_freq: bool = True,
                   option: str = "--out") -> Path:
    """Write an FRF as UFF58 / HDF5 / CSV chosen by the suffix (atomically).

    Parameters
    ----------
    path
        The target file (its directory must exist).
    frf
        The FRF.
    binary
        Write UFF58 as 58b (exact).
    round_freq
        Let ASCII UFF58 round frequencies to its 6 significant digits
        (see :func:`jointdb.io.write_uff58`).
    option
        The command-line option that named the file, for error messages.

    Returns
    -------
    Path
    """
    from jointdb import io

    p = Path(path)
    fmt = frf_format(p, option)
    if not p.parent.is_dir():
        raise InputError(f"{option} {str(p)!r}: directory {str(p.parent)!r} does not exist")
    if fmt == "uff58":
        io.write_uff58(p, frf, binary=binary, round_freq=round_freq)
    elif fmt == "hdf5":
        io.write_frf_hdf5(p, frf)
    else:
        io.write_frf_csv(p, frf)
    return p


def load_stack(path: Path | str, repo=None) -> StackSpec:
    """Read and validate a stack file; load a measured spindle FRF or a spindle model file it references.

    Catalogued parts it names (``{"part": "name@version"}``) are read from ``repo`` (a store, or a
    database URL / path; ``None``: the default database), opened only then, and recorded in
    ``spec.parts`` (:func:`jointdb.usecases.resolve_stack_parts`).

    Parameters
    ----------
    path
        The stack JSON file (``jointdb-stack/1``); files it names are relative to it.
    repo
        Where named parts are read from: a store, a database URL or path, or None (the default
        database, opened only when the file names a part).

    Returns
    -------
    StackSpec
        With the spindle FRF attached (measured spindle) or the model loaded (modelled one).

    Raises
    ------
    InputError
        Naming the stack file and the field (``stack.json: tool.segments[1].length: must be > 0``).
    NotFoundError
        Missing stack / spindle files, or a part, version or label the database does not hold.
    """
    from jointdb.usecases._parts import stack_from_document

    p = Path(path)
    doc = read_json_file(p, "stack file")
    try:
        spec = stack_from_document(doc, repo)
    except InputError as exc:
        raise InputError(f"{p.name}: {exc}") from None
    sp = spec.spindle
    if isinstance(sp, MeasuredSpindle) and sp.frf is None:
        frf = read_frf_file(p.parent / sp.file)
        est = load_spindle_estimate(p, sp.estimate) if isinstance(sp.estimate, dict) else sp.estimate
        spec = spec.replace(spindle=MeasuredSpindle(sp.file, sp.node, frf, estimate=est))
    elif isinstance(sp, ModelledSpindle) and isinstance(sp.model, str):
        model = read_json_file(p.parent / sp.model, "spindle model file")
        spec = spec.replace(spindle=ModelledSpindle(model, sp.point))
    return spec




def load_spindle_estimate(stack_path: Path, desc: dict):
    """The :class:`jointdb.stack._spindle_band.SpindleEstimate` a stack file's ``spindle.estimate`` describes.

    Parameters
    ----------
    stack_path
        The stack file (relative paths are read beside it).
    desc
        ``{"taps", "extension", "joint_point", "points", "noise"?}`` as written in the file.

    Returns
    -------
    SpindleEstimate
        The taps as read, the bar's free receptance over its joint point (x, ry) and tapped points on the taps'
        lines, and the stated noise level (None: estimated from the taps).

    Raises
    ------
    InputError
        Unknown named points, unreadable files (naming ``spindle.estimate``).
    """
    from jointdb.fe import load_model, model_from_dict
    from jointdb.stack._spindle_band import SpindleEstimate

    taps = read_frf_file(stack_path.parent / desc["taps"]).to("receptance")
    ext = desc["extension"]
    try:
        bar = load_model(stack_path.parent / ext) if isinstance(ext, str) else model_from_dict(ext)
        pts = [bar.point(desc["joint_point"]), *(bar.point(q) for q in desc["points"])]
    except InputError as exc:
        raise InputError(f"spindle.estimate: {exc}") from None
    e_frf = bar.frf(taps.freq, [q.name for q in pts])
    return SpindleEstimate(taps, e_frf, pts[0].node, (pts[1].node, pts[2].node), desc.get("noise"))


def write_joint_file(path: Path, frf: FRF, meta: dict[str, Any]) -> None:
    """Write a joint FRF as the HDF5 exchange file of ``jointdb identify``.

    Readable by ``jointdb couple --joint`` and ``jointdb catalogue``.

    Parameters
    ----------
    path
        The HDF5 file to write.
    frf
        The joint receptance.
    meta
        Its metadata (JSON-serialisable); a ``model_kind`` is written as the file's
        ``joint_model``.
    """
    from jointdb.io import write_frf_hdf5

    kinds = {v: k for k, v in MODEL_KINDS.items()}
    meta = dict(meta)
    meta = {"kind": "joint", "joint_model": kinds.get(meta.pop("model_kind", ""), ""), **meta}
    write_frf_hdf5(path, frf, json.loads(json.dumps(meta, default=str)))
