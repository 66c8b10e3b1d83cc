"""Write routes (writer token): catalogue an uploaded joint file, label, deprecate.

Every write is made under the token's owner: the audit log's actor and the
version's author are the owner's name, whatever the request body says.
"""

from __future__ import annotations

import base64
import binascii
import hashlib
import json
import tempfile
from pathlib import Path as FsPath
from typing import Any, Optional

from fastapi import APIRouter, Depends, Header, Response

from jointdb.errors import InputError, JointdbError
from jointdb.server._deps import repo, version_json, writer
from jointdb.server._schemas import CatalogueIn, DeprecateIn, LabelIn
from jointdb.server._uploads import check_hdf5_self_contained, unpack_campaign
from jointdb.server.routes_joints import Name, joint_name

router = APIRouter(tags=["writes"])

UPLOAD_SUFFIXES = (".h5", ".hdf5", ".zip")


def upload_name(filename: str) -> str:
    """A plain file name (kept in the provenance): no directories, no '..', an HDF5 suffix."""
    name = str(filename)
    if not name or "/" in name or "\\" in name or name in (".", "..") or name.startswith(".") \
            or not name.isprintable() or "\x00" in name:
        raise InputError(f"filename {name[:60]!r} must be a plain file name without directories")
    if not name.lower().endswith(UPLOAD_SUFFIXES):
        raise InputError(f"filename {name[:60]!r}: upload an identified joint (.h5) or a campaign archive (.zip)")
    return name


def catalogue_upload(r, body: CatalogueIn, owner: str):
    """Decode, read and catalogue an uploaded joint file (shared by the API and the web form)."""
    from jointdb.usecases import catalogue_inputs
    from jointdb.store._types import check_label

    name = joint_name(body.name)
    label = check_label(body.label) if body.label is not None else None
    if (body.frf is None) == (body.file_b64 is None):
        raise InputError("give either file_b64 with filename (an identified joint file) or frf (JSON)")
    if body.frf is not None:
        return _catalogue_frf(r, body, name, label, owner)
    fname = upload_name(body.filename or "")
    try:
        data = base64.b64decode(body.file_b64, validate=True)
    except (binascii.Error, ValueError):
        raise InputError("file_b64 is not valid base64") from None
    if not data:
        raise InputError("file_b64 is empty")
    with tempfile.TemporaryDirectory(prefix="jointdb-upload-") as tmp:
        path = FsPath(tmp) / fname
        path.write_bytes(data)
        if fname.lower().endswith(".zip"):  # unpacked as data: see jointdb.server._uploads
            path = unpack_campaign(path, FsPath(tmp) / "campaign")
        else:
            check_hdf5_self_contained(path, fname)
        try:
            args = catalogue_inputs(path, body.conditions.to_conditions(), joint_type=body.joint_type,
                                    model_kind=body.model_kind, method=body.method, quality=dict(body.quality),
                                    author=owner, force=body.force, root=FsPath(tmp) / "campaign")
        except JointdbError as exc:  # name the upload, not the server's temporary directory
            raise type(exc)(str(exc).replace(f"{tmp}/", "")) from None
    return r.catalogue(name, parent=body.parent, author=owner, label=label, **args)


def _catalogue_frf(r, body: CatalogueIn, name: str, label: str | None, owner: str):
    """Catalogue an FRF sent as JSON (``jointdb --server URL catalogue`` reads the file locally)."""
    from jointdb.io import frf_from_json
    from jointdb.store import Provenance

    if not body.joint_type or not body.model_kind:
        raise InputError("an frf sent as JSON needs joint_type and model_kind")
    prov = Provenance(method=body.method or "imported-file", parameters=dict(body.parameters),
                      input_files=dict(body.input_files), author=owner)
    return r.catalogue(name, body.joint_type, frf_from_json(body.frf.model_dump()), body.conditions.to_conditions(),
                       body.model_kind, prov, dict(body.quality), body.parent, author=owner, label=label)


@router.post("/catalogue", status_code=201, summary="Catalogue an identified joint file as a new version",
             responses={200: {"description": "Identical to the joint's latest version: nothing written, that "
                                             "version returned (\"identical\": true)"}})
def catalogue(body: CatalogueIn, response: Response, r=Depends(repo), who=writer,
              idempotency_key: Optional[str] = Header(None, max_length=200, description=(
                  "Any unique text (e.g. a UUID) per logical request: a retry with the same key and body "
                  "returns the same answer and never makes a second version; the same key with another "
                  "body is refused (422). Keys are kept per token owner, in the database."))) -> dict[str, Any]:
    """Upload the HDF5 file of `jointdb identify` (base64) with conditions; the conditions
    recorded in the file are completed by those given (a contradiction is refused unless
    ``force``). A new version must be the same joint as the previous one (materials, preload,
    torque, geometry, model kind, DOFs; values it did not record may be filled in): a change is
    refused (409) unless ``force``, and the audit entry then lists it. Content identical to the
    latest version writes nothing: 200 with that version and ``"identical": true`` (201 and
    ``"identical": false`` for a new version). The version, its label and its idempotency
    record are written together or not at all."""
    idem = None
    if idempotency_key is not None:
        key = idempotency_key.strip()
        if not key or not key.isprintable():
            raise InputError("the Idempotency-Key header must be printable text of 1..200 characters")
        digest = hashlib.sha256(json.dumps(body.model_dump(mode="json"), sort_keys=True, separators=(",", ":"),
                                           ensure_ascii=True).encode()).hexdigest()
        idem = (who.name, key, digest)
    outcome = r.idempotent_answer(idem)
    if outcome is None:
        writes = _OutcomeOf(r, force=body.force, allow_identical=body.allow_identical, idempotency=idem)
        catalogue_upload(writes, body, who.name)
        outcome = writes.outcome
    response.status_code = 201 if outcome.created else 200
    return {**version_json(outcome.version), "identical": not outcome.created}


class _OutcomeOf:
    """The repository as :func:`catalogue_upload` sees it: its ``catalogue`` call is made with
    ``catalogue_outcome`` (force, identical content, idempotency key) and the outcome is kept."""

    def __init__(self, repository, **options):
        self._repository, self._options, self.outcome = repository, options, None

    def catalogue(self, *args, **kw):
        self.outcome = self._repository.catalogue_outcome(*args, **{**kw, **self._options})
        return self.outcome.version


@router.post("/joints/{name}/labels", summary="Point a label at a version (create or move it)")
def label(name: Name, body: LabelIn, r=Depends(repo), who=writer) -> dict[str, Any]:
    """A writer may label the joints they or their team catalogued; an admin any (else 403)."""
    from jointdb.server._deps import may_change

    may_change(r, who, joint_name(name), "label")
    return version_json(r.label(joint_name(name), body.version, body.label, author=who.name))


@router.post("/joints/{name}/deprecate", summary="Deprecate (or undo) a joint or one version")
def deprecate(name: Name, body: DeprecateIn, r=Depends(repo), who=writer) -> dict[str, Any]:
    """A writer may deprecate the joints they or their team catalogued; an admin any (else 403)."""
    from jointdb.server._deps import may_change

    may_change(r, who, joint_name(name), "deprecate")
    hist = r.deprecate(joint_name(name), body.version, reason=body.reason, author=who.name, undo=body.undo)
    return {"items": [version_json(v) for v in hist]}
