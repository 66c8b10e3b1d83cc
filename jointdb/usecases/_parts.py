"""Parts of stacks from the catalogue: read part files, catalogue them, and assemble a stack by reference.

A stack document may name a catalogued part where it otherwise carries the object inline::

    "tool":    {"part": "carbide-12mm@1"},
    "holder":  {"part": "er32-hsk63@released"},
    "spindle": {"part": "dmu50-spindle@2"}

:func:`resolve_stack_parts` replaces each reference by the part version's payload (its record
verified on read), so the stack reader sees exactly the document it would with the parts inline;
a measured spindle's FRF set comes from its verified blob. The parts used are recorded in the
stack's provenance (:attr:`jointdb.stack.StackSpec.parts`). :func:`part_from_files` reads what
``jointdb parts add`` is given: a beam-model file (:mod:`jointdb.fe._modelfile`), an FRF file
(:mod:`jointdb.io`), a stack file to take a part from, or a JSON file of the part's object.
"""

from __future__ import annotations

import hashlib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from jointdb._jsonfile import read_json_file
from jointdb.errors import InputError
from jointdb.frf import FRF

#: stack-document slot -> part kind
SLOTS = {"tool": "tool", "holder": "holder", "spindle": "spindle"}


def part_refs(doc: Any) -> dict[str, str]:
    """``slot -> reference`` of the slots of a stack document that name a part (``{"part": ref}``).

    Raises
    ------
    InputError
        A slot holding ``part`` beside other fields, or a reference that is not text.
    """
    out: dict[str, str] = {}
    if not isinstance(doc, Mapping):
        return out
    for slot in SLOTS:
        value = doc.get(slot)
        if isinstance(value, Mapping) and "part" in value:
            if set(value) != {"part"}:
                raise InputError(f"{slot}: a part reference is {{\"part\": \"name@version\"}} alone; got also "
                                 f"{', '.join(sorted(k for k in value if k != 'part'))[:80]}")
            if not isinstance(value["part"], str):
                raise InputError(f"{slot}.part: must be 'name@version' or 'name@label', got {value['part']!r}"[:200])
            out[slot] = value["part"]
    return out


def _open(store):
    """``(store, owned)``: a store as given, or a :class:`jointdb.store.Repository` on a URL / path / None."""
    if store is None or isinstance(store, (str, Path)):
        from jointdb.store import Repository

        return Repository(store), True
    return store, False


def resolve_stack_parts(doc: Mapping[str, Any], store=None) -> tuple[dict[str, Any], tuple[dict, ...], FRF | None]:
    """Replace the part references of a stack document by the parts' payloads.

    Parameters
    ----------
    doc
        A parsed stack document.
    store
        A joint store (:class:`jointdb.store.Repository`, :class:`jointdb.client.RemoteRepository`) or a
        database URL / path (``None``: the default database); opened only when the document names a part.

    Returns
    -------
    tuple
        ``(document, parts, spindle_frf)``: the document with every part inline, the provenance of
        each part used (one mapping per slot), and a measured spindle's FRF set (else None).

    Raises
    ------
    NotFoundError
        An unknown part, version or label.
    InputError
        A malformed reference, or a part of another kind than its slot (a holder as the tool).
    IntegrityError
        A part's record or blob that fails verification.
    """
    refs = part_refs(doc)
    if not refs:
        return dict(doc), (), None
    out = dict(doc)
    used: list[dict] = []
    frf = None
    handle, owned = _open(store)
    try:
        for slot, ref in refs.items():
            part = handle.resolve_part(ref)
            if part.kind != SLOTS[slot]:
                raise InputError(f"{slot}.part: {part.ref} is a {part.kind}, not a {SLOTS[slot]}")
            payload = dict(part.payload)
            if part.blob_sha256 is not None:  # a measured spindle: its FRF set from the verified blob
                frf = handle.load_part_frf(part)
                payload = {"file": f"part:{part.ref}", "node": payload["node"]}
            out[slot] = payload
            used.append({"slot": slot, "ref": ref, "part": part.ref, "kind": part.kind,
                         "record_sha256": part.record_sha256, "blob_sha256": part.blob_sha256})
    finally:
        if owned:
            handle.close()
    return out, tuple(used), frf


def stack_from_document(doc: Any, store=None):
    """A :class:`jointdb.stack.StackSpec` from a parsed stack document whose parts may be catalogued
    references (resolved with :func:`resolve_stack_parts`; recorded in ``spec.parts``).

    Raises
    ------
    InputError
        Naming the field, as :func:`jointdb.stack.stack_from_dict`.
    """
    from jointdb.stack import MeasuredSpindle, stack_from_dict

    inline, used, frf = resolve_stack_parts(doc, store) if isinstance(doc, Mapping) else (doc, (), None)
    spec = stack_from_dict(inline)
    if frf is not None:
        spec = spec.replace(spindle=MeasuredSpindle(spec.spindle.file, spec.spindle.node, frf))
    return spec.replace(parts=used) if used else spec


# ------------------------------------------------------------------ part files
def _sha256(path: Path) -> str:
    h = hashlib.sha256()
    with path.open("rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


@dataclass(frozen=True)
class PartInput:
    """What ``jointdb parts add`` catalogues: a payload, a measured spindle's FRF, the provenance."""

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
    from jointdb.usecases._files import read_frf_file

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
    from jointdb.usecases._files import read_frf_file

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
    """Read a part (:func:`part_from_files`) and catalogue it in ``store``; the :class:`PartVersion`."""
    part = part_from_files(kind, **files)
    return store.add_part(name, kind, part.payload, frf=part.frf, attributes=attributes,
                          provenance=part.provenance, author=author, label=label)
