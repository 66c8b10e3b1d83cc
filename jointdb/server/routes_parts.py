"""Parts of stacks (spindles, holders, tools): list, versions, one record, catalogue, label.

Reads need a reader token (or open reads); writes a writer token, made under the token's owner.
Every request is hostile: bodies are bounded by the service's upload limit, the payload by the
store's JSON limits (64 levels, 2 MiB per field, finite numbers), an uploaded FRF file is read
from a private temporary directory under a plain file name (HDF5 external links refused), and a
spindle model must be sent inline: nothing names a file on the server's disk.
"""

from __future__ import annotations

import base64
import binascii
import json
import tempfile
from pathlib import Path as FsPath
from typing import Annotated, Any, Literal, Optional

from fastapi import APIRouter, Depends, Path, Query, Request, Response
from pydantic import Field

from jointdb.errors import InputError, JointdbError, NotFoundError
from jointdb.server._deps import Page, page, reader, repo, writer
from jointdb.server._schemas import FrfIn, Strict

router = APIRouter(tags=["parts"])

PartName = Annotated[str, Path(min_length=1, max_length=200, description="Part name.")]
VersionOrLabel = Annotated[str, Path(min_length=1, max_length=100, description="Version number or label.")]
FRF_UPLOAD_SUFFIXES = (".uff", ".unv", ".uff58", ".h5", ".hdf5", ".csv")


class PartIn(Strict):
    name: str = Field(..., max_length=200, description="Part name (new part, or a new version of it).")
    kind: Literal["spindle", "holder", "tool"]
    payload: dict[str, Any] = Field(default_factory=dict, description=(
        "The part's object of a stack file: a tool or holder; a modelled spindle {model, point}; a measured "
        "spindle {node} with its FRF set in frf or file_b64."))
    attributes: dict[str, Any] = Field(default_factory=dict, description="machine (spindle, required), family, "
                                       "taper, bore_mm (holder), description.")
    frf: Optional[FrfIn] = Field(None, description="A measured spindle's nose FRF set as JSON.")
    file_b64: Optional[str] = Field(None, description="Or: the FRF file (.uff, .h5, .csv), base64, with filename.")
    filename: Optional[str] = Field(None, max_length=200)
    input_files: dict[str, str] = Field(default_factory=dict, description="File name -> SHA-256 (provenance).")
    method: Optional[str] = Field(None, max_length=200)
    label: Optional[str] = Field(None, max_length=100)


class PartLabelIn(Strict):
    label: str = Field(..., max_length=100)


def part_summary(p) -> dict[str, Any]:
    """A part version without its payload (lists)."""
    d = p.to_dict()
    d.pop("payload")
    d["measured"] = p.blob_sha256 is not None
    return d


def _name(name: str) -> str:
    from jointdb.store._parts import check_part_name

    return check_part_name(name)


def _get(r, name: str, version: str):
    from jointdb.store._types import check_label

    if version.isdigit() and len(version) <= 10:
        return r.get_part(_name(name), int(version))
    return r.get_part(_name(name), label=check_label(version))


@router.get("/parts", summary="Catalogued parts: the latest version of each")
def list_parts(page: Page = Depends(page),
               kind: Optional[Literal["spindle", "holder", "tool"]] = Query(None),
               family: Optional[str] = Query(None, max_length=100, description="Holder family, e.g. ER32."),
               machine: Optional[str] = Query(None, max_length=200, description="The spindle's machine."),
               r=Depends(repo), _who=reader) -> dict[str, Any]:
    """Name, kind, latest version, labels and attributes of every part (no payloads)."""
    return page.of([part_summary(p) for p in r.list_parts(kind, family=family or None, machine=machine or None)])


@router.get("/parts/{name}", summary="Every version of a part, oldest first")
def part_versions(name: PartName, page: Page = Depends(page), r=Depends(repo), _who=reader) -> dict[str, Any]:
    hist = r.part_history(_name(name))
    return {"name": hist[0].name, "kind": hist[0].kind, **page.of([part_summary(p) for p in hist])}


@router.get("/parts/{name}/{version}", summary="One part version: record and payload (verified on read)")
def part_version(name: PartName, version: VersionOrLabel, r=Depends(repo), _who=reader) -> dict[str, Any]:
    p = _get(r, name, version)
    return {**p.to_dict(), "measured": p.blob_sha256 is not None}


@router.get("/parts/{name}/{version}/frf", summary="A measured spindle's FRF set (JSON, verified on read)")
def part_frf(name: PartName, version: VersionOrLabel, r=Depends(repo), _who=reader) -> dict[str, Any]:
    from jointdb.io import frf_json

    return frf_json(r.load_part_frf(_get(r, name, version)))


def _upload_name(filename: str | None) -> str:
    name = str(filename or "")
    if not name or "/" in name or "\\" in name or name.startswith(".") or not name.isprintable():
        raise InputError(f"filename {name[:60]!r} must be a plain file name without directories")
    if not name.lower().endswith(FRF_UPLOAD_SUFFIXES):
        raise InputError(f"filename {name[:60]!r}: upload an FRF file (.uff, .unv, .h5, .hdf5 or .csv)")
    return name


def _frf_from_upload(data: bytes, filename: str | None):
    """An FRF read from uploaded bytes in a private temporary directory (never a server path in errors)."""
    from jointdb.server._uploads import check_hdf5_self_contained
    from jointdb.usecases import read_frf_file

    fname = _upload_name(filename)
    if not data:
        raise InputError("the FRF file is empty")
    with tempfile.TemporaryDirectory(prefix="jointdb-part-") as tmp:
        path = FsPath(tmp) / fname
        path.write_bytes(data)
        try:
            if fname.lower().endswith((".h5", ".hdf5")):
                check_hdf5_self_contained(path, fname)
            return read_frf_file(path)
        except JointdbError as exc:
            raise type(exc)(str(exc).replace(f"{tmp}/", "")) from None


def _add(r, response: Response, owner: str, *, name, kind, payload, attributes, frf, label, provenance):
    from jointdb.store._types import check_label

    name = _name(name)
    label = check_label(label) if label is not None else None
    try:
        before = r.get_part(name).version
    except NotFoundError:
        before = 0
    p = r.add_part(name, kind, payload, frf=frf, attributes=attributes, provenance=provenance, author=owner,
                   label=label)
    created = p.version > before
    response.status_code = 201 if created else 200
    return {**p.to_dict(), "measured": p.blob_sha256 is not None, "identical": not created}


@router.post("/parts", status_code=201, summary="Catalogue a part as a new version (JSON or multipart)",
             responses={200: {"description": "Identical to the part's latest version: nothing written"}},
             openapi_extra={"requestBody": {"content": {
                 "application/json": {"schema": PartIn.model_json_schema(ref_template="#/components/schemas/{model}")},
                 "multipart/form-data": {"schema": {"type": "object", "properties": {
                     "name": {"type": "string"}, "kind": {"type": "string"},
                     "payload": {"type": "string", "description": "the payload as JSON text"},
                     "attributes": {"type": "string", "description": "the attributes as JSON text"},
                     "label": {"type": "string"},
                     "frf": {"type": "string", "format": "binary", "description": "FRF file of a measured spindle"},
                     "payload_file": {"type": "string", "format": "binary",
                                      "description": "JSON file of the payload"}}}}}}})
async def add_part(request: Request, response: Response, r=Depends(repo), who=writer) -> dict[str, Any]:
    """A tool, holder or spindle (see ``PartIn``); content identical to the latest version writes
    nothing (200, ``"identical": true``). The author is the token's owner."""
    from starlette.concurrency import run_in_threadpool

    if request.headers.get("content-type", "").lower().startswith("multipart/form-data"):
        fields = await _multipart(request)
    else:
        fields = await run_in_threadpool(_json_fields, await request.body())
    return await run_in_threadpool(lambda: _add(r, response, who.name, **fields))


def _json_fields(raw: bytes) -> dict[str, Any]:
    from pydantic import ValidationError

    from jointdb.schemas._limits import check_json_text
    from jointdb.io import frf_from_json

    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise InputError("the body must be UTF-8 JSON") from None
    check_json_text(text, "body")  # size and nesting depth before parsing
    try:
        body = PartIn.model_validate_json(text)
    except ValidationError as exc:
        err = exc.errors()[0]
        where = ".".join(str(x) for x in err.get("loc", ())) or "body"
        raise InputError(f"{where}: {err.get('msg', 'invalid')}"[:300]) from None
    if body.frf is not None and body.file_b64 is not None:
        raise InputError("give the FRF set as frf (JSON) or file_b64, not both")
    frf = frf_from_json(body.frf.model_dump()) if body.frf is not None else None
    files = dict(body.input_files)
    if body.file_b64 is not None:
        try:
            data = base64.b64decode(body.file_b64, validate=True)
        except (binascii.Error, ValueError):
            raise InputError("file_b64 is not valid base64") from None
        frf = _frf_from_upload(data, body.filename)
        files.setdefault(_upload_name(body.filename), _sha256(data))
    return {"name": body.name, "kind": body.kind, "payload": body.payload, "attributes": body.attributes,
            "frf": frf, "label": body.label,
            "provenance": {"method": body.method or "api-upload", "input_files": files}}


def _sha256(data: bytes) -> str:
    import hashlib

    return hashlib.sha256(data).hexdigest()


def _json_text(value: Any, field: str) -> Any:
    from jointdb.schemas._limits import check_json_text

    if value is None:
        return None
    text = value if isinstance(value, str) else None
    if text is None:
        raise InputError(f"{field}: must be a text field holding JSON")
    check_json_text(text, field)
    try:
        return json.loads(text)
    except ValueError:
        raise InputError(f"{field}: is not JSON") from None


async def _multipart(request: Request) -> dict[str, Any]:
    """The fields of a multipart form: name, kind, payload (JSON text) or payload_file, attributes
    (JSON text), label, node (measured spindle) and frf (its FRF file)."""
    from starlette.concurrency import run_in_threadpool

    async with request.form(max_files=2, max_fields=20) as form:
        known = {"name", "kind", "payload", "payload_file", "attributes", "label", "node", "frf"}
        extra = sorted(set(form.keys()) - known)
        if extra:
            raise InputError(f"unknown form field {extra[0][:40]!r}; expected one of {', '.join(sorted(known))}")
        text = {k: form.get(k) for k in ("name", "kind", "payload", "attributes", "label", "node")}
        for k, v in text.items():
            if v is not None and not isinstance(v, str):
                raise InputError(f"{k}: must be a text field")
        payload = _json_text(text["payload"], "payload")
        files: dict[str, str] = {}
        pfile = form.get("payload_file")
        if pfile is not None:
            if isinstance(pfile, str) or payload is not None:
                raise InputError("payload_file: send one JSON file, or the payload field, not both")
            data = await pfile.read()
            payload = _json_text(data.decode("utf-8", "replace"), "payload_file")
            files[_plain(pfile.filename)] = _sha256(data)
        frf = None
        ffile = form.get("frf")
        if ffile is not None:
            if isinstance(ffile, str):
                raise InputError("frf: must be a file")
            data = await ffile.read()
            frf = await run_in_threadpool(_frf_from_upload, data, ffile.filename)
            files[_upload_name(ffile.filename)] = _sha256(data)
    if text["node"] is not None:
        if not text["node"].isdigit() or len(text["node"]) > 9:
            raise InputError("node: must be a non-negative whole number")
        payload = {**(payload or {}), "node": int(text["node"])}
    if text["kind"] not in ("spindle", "holder", "tool"):
        raise InputError("kind: must be spindle, holder or tool")
    return {"name": text["name"] or "", "kind": text["kind"], "payload": payload if payload is not None else {},
            "attributes": _json_text(text["attributes"], "attributes") or {}, "frf": frf, "label": text["label"],
            "provenance": {"method": "api-upload", "input_files": files}}


def _plain(filename: str | None) -> str:
    name = FsPath(str(filename or "payload.json")).name
    return name if name.isprintable() and name not in ("", ".", "..") else "payload.json"


@router.post("/parts/{name}/{version}/labels", summary="Point a label of a part at a version")
def label_part(name: PartName, version: Annotated[int, Path(ge=1, le=2**31 - 1)], body: PartLabelIn,
               r=Depends(repo), who=writer) -> dict[str, Any]:
    """Create or move the label (audited under the token's owner)."""
    p = r.label_part(_name(name), version, body.label, author=who.name)
    return {**p.to_dict(), "measured": p.blob_sha256 is not None}
