"""Files the use cases read and write: FRF files by suffix, stack files (with the spindle
FRF or model file they name), and the HDF5 joint exchange file of ``jointdb identify``."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from jointdb._jsonfile import read_json_file
from jointdb.errors import InputError, NotFoundError
from jointdb.frf import FRF
from jointdb.stack import MeasuredSpindle, ModelledSpindle, StackSpec

#: ``joint_model`` of a campaign / `jointdb identify` file -> model kind of the catalogue
MODEL_KINDS = {"planar": "spring-damper-planar", "n-point": "n-point-translational", "matrix": "full-matrix"}

#: FRF file formats by suffix (reading and writing).
FRF_SUFFIXES = {".uff": "uff58", ".unv": "uff58", ".uff58": "uff58", ".uf": "uff58", ".58": "uff58",
                ".h5": "hdf5", ".hdf5": "hdf5", ".hdf": "hdf5", ".csv": "csv"}


def frf_format(path: Path | str, option: str = "") -> str:
    """``"uff58"``, ``"hdf5"`` or ``"csv"`` from the suffix; InputError naming the option otherwise."""
    p = Path(path)
    fmt = FRF_SUFFIXES.get(p.suffix.lower())
    if fmt is None:
        where = f"{option} {str(p)!r}" if option else str(p)
        raise InputError(f"{where}: unknown FRF file type {p.suffix.lower()!r}; use .uff/.unv (UFF58), "
                         ".h5/.hdf5 or .csv")
    return fmt


def read_frf_file(path: Path | str) -> FRF:
    """Read an FRF from UFF58 (``.uff``, ``.unv``), HDF5 (``.h5``, ``.hdf5``) or CSV by suffix.

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
        return io.read_frf_uff58(p)
    if fmt == "hdf5":
        return io.read_frf_hdf5(p)
    return io.read_frf_csv(p)


def write_frf_file(path: Path | str, frf: FRF, *, binary: bool = False, round_freq: bool = True,
                   option: str = "--out") -> Path:
    """Write an FRF as UFF58 / HDF5 / CSV chosen by the suffix (atomically).

    ``binary`` writes UFF58 as 58b (exact); ``round_freq`` lets ASCII UFF58
    round frequencies to its 6 significant digits (see :func:`jointdb.io.write_uff58`).
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
        spec = spec.replace(spindle=MeasuredSpindle(sp.file, sp.node, frf))
    elif isinstance(sp, ModelledSpindle) and isinstance(sp.model, str):
        model = read_json_file(p.parent / sp.model, "spindle model file")
        spec = spec.replace(spindle=ModelledSpindle(model, sp.point))
    return spec




def write_joint_file(path: Path, frf: FRF, meta: dict[str, Any]) -> None:
    """Write a joint FRF as the HDF5 exchange file of ``jointdb identify`` (readable by
    ``jointdb couple --joint`` and ``jointdb catalogue``), with ``meta`` as its metadata
    (its ``model_kind``, if any, is written as the file's ``joint_model``)."""
    from jointdb.io import write_frf_hdf5

    kinds = {v: k for k, v in MODEL_KINDS.items()}
    meta = dict(meta)
    meta = {"kind": "joint", "joint_model": kinds.get(meta.pop("model_kind", ""), ""), **meta}
    write_frf_hdf5(path, frf, json.loads(json.dumps(meta, default=str)))
