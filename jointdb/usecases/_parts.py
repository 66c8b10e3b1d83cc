"""Parts of stacks from the catalogue: read part files, catalogue them, and assemble a stack by reference.

A stack document may name a catalogued part where it otherwise carries the object inline::

    "tool":    {"part": "carbide-12mm@1"},
    "holder":  {"part": "er32-hsk63@released"},
    "spindle": {"part": "dmu50-spindle@2"}

:func:`resolve_stack_parts` replaces each reference by the part version's payload (its record
verified on read), so the stack reader sees exactly the document it would with the parts inline;
a measured spindle's FRF set comes from its verified blob. The parts used are recorded in the
stack's provenance (:attr:`jointdb.stack.StackSpec.parts`). Reading part files for
``jointdb parts add`` is :mod:`jointdb.usecases._partfiles`.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

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
    """``(store, owned)``: a store as given, or a :class:`jointdb.store.Repository` on a URL / path / None
    (an existing database: reading a stack never creates one)."""
    if store is None or isinstance(store, (str, Path)):
        from jointdb.store import Repository

        return Repository(store, auto_create=False), True
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
