"""FRF downloads of a pinned version: UFF58, HDF5 exchange file, CSV or JSON.

A catalogued version never changes, so its FRF in a given format never does:
the response carries a strong ETag (record hash + format) and may be cached for
a year (``immutable``); ``If-None-Match`` gets 304 without reading the blob. The
encoded bytes are kept by the same key (:mod:`jointdb.server._encoded`: memory,
then a folder all workers share), so a version is read and encoded once.
"""

from __future__ import annotations

import json
import tempfile
from pathlib import Path as FsPath
from typing import Annotated, Literal

from fastapi import APIRouter, Depends, Path, Query, Request, Response

from jointdb.io import frf_json
from jointdb.server._deps import reader, repo
from jointdb.server.routes_joints import Name, joint_name

router = APIRouter(tags=["frf"])

FORMATS = {
    "uff58": ("application/octet-stream", ".uff"),
    "hdf5": ("application/x-hdf5", ".h5"),
    "csv": ("text/csv; charset=utf-8", ".csv"),
    "json": ("application/json", ".json"),
}
YEAR = 365 * 24 * 3600


def _exchange_file(jv, frf, path: FsPath) -> None:
    from jointdb.usecases import write_joint_file

    write_joint_file(path, frf, {
        "model_kind": jv.model_kind, "joint_type": jv.joint_type, "conditions": jv.conditions.to_dict(),
        "catalogue": {"name": jv.name, "version": jv.version, "uuid": jv.uuid, "blob_sha256": jv.blob_sha256},
        "quality": dict(jv.quality)})


def render(jv, frf, fmt: str) -> bytes:
    """The bytes of one version's FRF in ``fmt`` (the writers of :mod:`jointdb.io`, via a temporary file)."""
    if fmt == "json":
        return json.dumps({"name": jv.name, "version": jv.version, "blob_sha256": jv.blob_sha256,
                           **frf_json(frf)}).encode()
    from jointdb.usecases import write_frf_file

    with tempfile.TemporaryDirectory(prefix="jointdb-dl-") as tmp:
        path = FsPath(tmp) / f"frf{FORMATS[fmt][1]}"
        if fmt == "hdf5":
            _exchange_file(jv, frf, path)
        else:
            write_frf_file(path, frf, binary=True) if fmt == "uff58" else write_frf_file(path, frf)
        return path.read_bytes()


def encoded_cache(request: Request):
    """The app's :class:`~jointdb.server._encoded.EncodedCache` (made on first use)."""
    cache = getattr(request.app.state, "encoded_cache", None)
    if cache is None:
        from jointdb import __version__
        from jointdb.server._encoded import EncodedCache, default_cache_dir

        folder = request.app.state.settings.cache_dir
        folder = default_cache_dir() if folder is None else (FsPath(folder) if folder else None)
        cache = EncodedCache(folder, tag=__version__)
        request.app.state.encoded_cache = cache
    return cache


def encoded_frf(request: Request, r, jv, fmt: str) -> bytes:
    """The bytes of version ``jv``'s FRF in ``fmt``: from the app's cache of encoded files, encoded on a miss."""
    return encoded_cache(request).get(jv.record_sha256, fmt, lambda: render(jv, r.load_frf(jv), fmt))


def etag(record_sha256: str, fmt: str) -> str:
    return f'"{record_sha256[:40]}-{fmt}"'


@router.get("/joints/{name}/versions/{version}/frf", summary="Download a version's FRF",
            responses={200: {"content": {t: {} for t, _ in FORMATS.values()}}, 304: {"description": "Not modified"}})
def download(request: Request, name: Name, version: Annotated[int, Path(ge=1, le=2**31 - 1)],
             format: Literal["uff58", "hdf5", "csv", "json"] = Query("hdf5"),  # noqa: A002 - the field's word
             r=Depends(repo), _who=reader) -> Response:
    name = joint_name(name)
    jv = r.get(name, version)
    tag = etag(jv.record_sha256, format)
    scope = "public" if request.app.state.settings.open_reads else "private"
    headers = {"ETag": tag, "Cache-Control": f"{scope}, max-age={YEAR}, immutable", "Vary": "Authorization"}
    wanted = [t.strip() for t in request.headers.get("if-none-match", "").split(",")]
    if tag in wanted or "*" in wanted:
        return Response(status_code=304, headers=headers)
    body = encoded_frf(request, r, jv, format)
    media, suffix = FORMATS[format]
    safe = "".join(ch if ch.isalnum() or ch in "-_." else "_" for ch in name)
    headers["Content-Disposition"] = f'attachment; filename="{safe}-v{version}{suffix}"'
    return Response(body, media_type=media, headers=headers)
