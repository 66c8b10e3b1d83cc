"""Part files for ``jointdb parts add``: a beam-model file (:mod:`jointdb.fe._modelfile`), an FRF file
(:mod:`jointdb.io`, by suffix), a stack file to take a part from, or a JSON file of the part's object."""

from __future__ import annotations

import hashlib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from jointdb.schemas._jsonfile import read_json_file
from jointdb.errors import InputError, NotFoundError
from jointdb.frf import FRF
from jointdb.usecases._files import read_frf_file


# ------------------------------------------------------------------ part files
def _sha256(path: Path) -> str:
    h = hashlib.sha256()
    with path.open("rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


@dataclass(frozen=True)
class PartInput:
    """What ``jointdb parts add`` catalogues: a payload, a measured spindle's FRF, the provenance.

    Parameters
    ----------
    kind
        ``spindle``, ``holder`` or ``tool``.
    payload
        The part's object of a stack file (lengths in m); a measured spindle: ``{"node": N}``.
    frf
        A measured spindle's nose FRF set (receptance, ``(n_freq, n_out, n_in)``); None otherwise.
    provenance
        ``method`` (``parts-add``), ``input_files`` (name -> SHA-256 of each file read) and, for a
        part taken from a stack file, ``parameters``.
    """

    kind: str
    payload: Mapping[str, Any]
    frf: FRF | None = None
    provenance: Mapping[str, Any] = field(default_factory=dict)


def part_from_files(kind: str, *, model: Path | None = None, point: str | None = None, frf: Path | None = None,
                    node: int | None = None, from_stack: Path | None = None, file: Path | None = None) -> PartInput:
    """Read a part from the files ``jointdb parts add`` is given (exactly one source).

    Parameters
    ----------
    kind
        spindle / holder / tool.
    model, point
        A spindle: a beam-model file (``jointdb-beam-model/1``) and the point the holder sits on.
    frf, node
        A spindle: a measured FRF file of its nose (UFF58, HDF5, CSV; DOFs ``Nx``, ``Nry``,
        optionally ``Ny``, ``Nrx``) and that node ``N``.
    from_stack
        A stack file: the part of that kind it holds (a spindle model file it names is read too).
    file
        A JSON file of the part's stack-file object (a tool or a holder; a spindle ``{model, point}``).

    Returns
    -------
    PartInput
        With provenance: input file names and their SHA-256, the method ``parts-add``.

    Raises
    ------
    InputError, NotFoundError
        No source or more than one, or a file that cannot be read (naming it).
    """
    given = [n for n, v in (("--model", model), ("--frf", frf), ("--from-stack", from_stack), ("--file", file))
             if v is not None]
    if len(given) != 1:
        raise InputError(f"give exactly one of --model, --frf, --from-stack, --file (got {', '.join(given) or 'none'})")
    if (model is not None or frf is not None) and kind != "spindle":
        raise InputError(f"{given[0]} is for a spindle; a {kind} is read with --from-stack or --file")
    src = Path(model or frf or from_stack or file)
    inputs = {src.name: _sha256(src)} if src.is_file() else {}
    prov: dict[str, Any] = {"method": "parts-add", "input_files": inputs}
    if frf is not None:
        if node is None:
            raise InputError("--frf needs --node (the node number of the spindle nose in the file)")
        return PartInput(kind, {"node": int(node)}, read_frf_file(src), prov)
    if model is not None:
        if not point:
            raise InputError("--model needs --point (the model point the holder sits on)")
        return PartInput(kind, {"model": read_json_file(src, "model file"), "point": point}, None, prov)
    doc = read_json_file(src, "stack file" if from_stack is not None else "part file")
    if from_stack is not None:
        if not isinstance(doc, Mapping) or not isinstance(doc.get(kind), Mapping):
            raise InputError(f"{src.name}: has no {kind} object")
        payload = dict(doc[kind])
        if kind == "spindle":
            payload = _stack_spindle(src, payload, prov)
        prov["parameters"] = {"from_stack": src.name}
        return PartInput(kind, payload, None if "node" not in payload else payload.pop("_frf"), prov)
    if not isinstance(doc, Mapping):
        raise InputError(f"{src.name}: must hold the {kind}'s JSON object")
    return PartInput(kind, dict(doc), None, prov)


def _stack_spindle(stack: Path, payload: dict, prov: dict) -> dict:
    """A stack file's spindle as a part payload: a model file it names is read (relative to the stack)."""
    if "file" in payload:  # measured: the FRF file beside the stack
        path = stack.parent / str(payload["file"])
        prov["input_files"][path.name] = _sha256(path) if path.is_file() else ""
        return {"node": payload.get("node"), "_frf": read_frf_file(path)}
    if isinstance(payload.get("model"), str):
        path = stack.parent / payload["model"]
        prov["input_files"][path.name] = _sha256(path) if path.is_file() else ""
        return {**payload, "model": read_json_file(path, "spindle model file")}
    return payload


def add_part_from_files(store, name: str, kind: str, *, attributes: Mapping[str, Any] | None = None,
                        label: str | None = None, author: str | None = None, **files):
    """Read a part (:func:`part_from_files`) and catalogue it in ``store``.

    Parameters
    ----------
    store
        The joint store (:class:`jointdb.store.Repository` or :class:`jointdb.client.RemoteRepository`).
    name, kind
        The part's name and kind (spindle / holder / tool).
    attributes, label, author
        As :meth:`jointdb.store.Repository.add_part`.
    **files
        The source, exactly one: ``model`` and ``point``, ``frf`` and ``node``, ``from_stack`` or
        ``file`` (see :func:`part_from_files`).

    Returns
    -------
    PartVersion
        The part as catalogued: a new version, or the latest one when the files give identical content.

    Raises
    ------
    InputError, NotFoundError
        A bad or missing source file, or a part the store refuses (naming the field).
    """
    part = part_from_files(kind, **files)
    return store.add_part(name, kind, part.payload, frf=part.frf, attributes=attributes,
                          provenance=part.provenance, author=author, label=label)


#: The parts of the bundled example stack (``jointdb/data/catalogue``), as the demo catalogues them:
#: ``(name, kind, source, attributes)``; source: ``stack:<slot>`` of demo-stack.json or ``model:<file>:<point>``.
BUNDLED_PARTS = (
    ("carbide-end-mill-12mm-4fl", "tool", "stack:tool",
     {"description": "12 mm 4-flute carbide end mill, 90 mm long, 30 mm fluted"}),
    ("er32-collet-chuck-hsk63", "holder", "stack:holder",
     {"family": "ER32", "taper": "HSK-A63", "bore_mm": 12.0,
      "description": "steel ER32 collet chuck on HSK-A63, 70 mm (12 mm bore, 40 mm deep)"}),
    ("demo-mill-spindle", "spindle", "stack:spindle",
     {"machine": "demo-mill", "taper": "HSK-A63",
      "description": "spindle shaft on two bearing sets, y 25 % softer than x (3-D frame model)"}),
    ("test-rig-spindle", "spindle", "model:models/spindle-alone.json:nose",
     {"machine": "holder-spindle test rig", "description": "the test rig's spindle shaft alone (planar model)"}),
)


def catalogue_bundled_parts(store, catalogue_dir: Path | str, *, author: str | None = None) -> list:
    """Catalogue the bundled example parts (:data:`BUNDLED_PARTS`) from ``catalogue_dir`` (the bundled
    ``catalogue`` folder, or ``DIR`` of ``jointdb examples DIR`` with its ``stacks``/``models``).

    Identical content adds nothing, so running it again is harmless.

    Parameters
    ----------
    store
        The joint store (:class:`jointdb.store.Repository` or :class:`jointdb.client.RemoteRepository`).
    catalogue_dir
        The folder holding ``demo-stack.json`` (or ``stacks/demo-stack.json``) and ``models/``.
    author
        Who catalogues them (default: ``JOINTDB_AUTHOR`` or the login; a server records the token's owner).

    Returns
    -------
    list of tuple
        ``(PartVersion, created)`` per entry of :data:`BUNDLED_PARTS`, in that order; ``created`` is
        False when the part's latest version already had this content.
    """
    root = Path(catalogue_dir)
    stack = root / "demo-stack.json"
    if not stack.is_file():
        stack = root / "stacks" / "demo-stack.json"
    out = []
    for name, kind, source, attributes in BUNDLED_PARTS:
        what, _, rest = source.partition(":")
        if what == "stack":
            part = part_from_files(kind, from_stack=stack)
        else:
            file, _, point = rest.rpartition(":")
            part = part_from_files(kind, model=root / file, point=point)
        try:
            before = store.get_part(name).version
        except NotFoundError:
            before = 0
        pv = store.add_part(name, kind, part.payload, frf=part.frf, attributes=attributes,
                            provenance=part.provenance, author=author)
        out.append((pv, pv.version > before))
    return out
