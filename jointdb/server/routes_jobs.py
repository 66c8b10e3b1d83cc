"""Job routes: long work answered at once with 202 and a job URL (issue 21; docs/service.md, Jobs).

``POST /api/v1/jobs/{kind}`` (predict, lobes, diagnose: JSON as the synchronous routes; optimize: an
optimize spec with its stack inline and parts and joints from the catalogue;
identify: a multipart upload of a campaign archive, or JSON with it in base64) checks the
input, queues the job and answers **202** with ``{"id", "url", "state"}`` and a ``Location``
header. ``GET /api/v1/jobs/{id}`` shows state, progress, message, one-line error and the
result; ``GET /api/v1/jobs`` lists the caller's jobs, newest first; ``POST
/api/v1/jobs/{id}/cancel`` cancels. An identify job's result is reviewed, then
``POST /api/v1/jobs/{id}/catalogue`` (writer) stores the joint as a new version, or
``POST /api/v1/jobs/{id}/discard`` drops it.

Who: a token (``Authorization: Bearer``) or a signed-in browser session; a session's POST
must come from this site and carry the page's CSRF token in ``X-CSRF-Token``. A job is
shown only to the one who submitted it, or to an admin. Identify and catalogue need writer.
"""

from __future__ import annotations

import base64
import binascii
import json
import tempfile
from pathlib import Path
from typing import Any, Optional

from fastapi import APIRouter, HTTPException, Query, Request, Response, Security
from pydantic import BaseModel, ConfigDict, Field

from jointdb.errors import InputError, NotFoundError
from jointdb.server._deps import need, version_json
from jointdb.server._schemas import DiagnoseIn, IdentifyIn, JobCatalogueIn, LobesJobIn, PredictIn

router = APIRouter(tags=["jobs"])
JobId = str
_ACCEPTED = {202: {"description": "Queued: the job's id, URL and state (and a Location header)."}}


#: Who asks: an API token, or a browser session (CSRF and same origin on POST); always someone, since a
#: job belongs to whoever submitted it (no anonymous reads even on an open-reads server).
reader = Security(need("reader", anonymous_reads=False))
writer = Security(need("writer", anonymous_reads=False))


def queue(request: Request):
    q = getattr(request.app.state, "jobs", None)
    if q is None:
        raise HTTPException(503, "the job queue is not running on this server")
    return q


def _own(request: Request, job_id: str, who):
    """The job's row when ``who`` submitted it or is an admin (404 otherwise: no oracle of other jobs)."""
    if not (0 < len(job_id) <= 32 and job_id.isalnum()):
        raise NotFoundError(f"no job {job_id[:40]}")
    row = queue(request).get(job_id)
    if row._mapping["owner"] != who.name and not who.allows("admin"):
        raise NotFoundError(f"no job {job_id}")
    return row


def _accepted(response: Response, job_id: str) -> dict[str, Any]:
    url = f"/api/v1/jobs/{job_id}"
    response.status_code = 202
    response.headers["Location"] = url
    return {"id": job_id, "url": url, "state": "queued"}


@router.post("/jobs/predict", status_code=202, responses=_ACCEPTED, summary="Predict a stack's tool tip (job)")
def submit_predict(body: PredictIn, request: Request, response: Response, who=reader) -> dict[str, Any]:
    """Body as ``POST /api/v1/predict``; the result as its answer (plus ``rigid_tip_frf``)."""
    from jointdb.usecases import stack_from_document

    # a bad stack, or a part that is not catalogued, is a 422 now, not a failed job later; the stack is
    # queued as sent (a hostile deep stack is refused by the reader, not by pydantic's serialiser)
    stack_from_document(body.stack, request.app.state.repo)
    return _accepted(response, queue(request).submit("predict", who.name, {"stack": body.stack}))


@router.post("/jobs/lobes", status_code=202, responses=_ACCEPTED, summary="Stability lobes (job; ZOA or SD)")
def submit_lobes(body: LobesJobIn, request: Request, response: Response, who=reader) -> dict[str, Any]:
    """Body as ``POST /api/v1/lobes``; the result holds summary, rows, best speeds and notes."""
    from jointdb.server.routes_query import check_lobes

    payload = check_lobes(body)
    return _accepted(response, queue(request).submit("lobes", who.name, payload))


@router.post("/jobs/diagnose", status_code=202, responses=_ACCEPTED, summary="Diagnose a model against recordings (job)")
def submit_diagnose(body: DiagnoseIn, request: Request, response: Response, who=reader) -> dict[str, Any]:
    """``jointdb diagnose``: model JSON, recorded FRFs (JSON), levels, point map."""
    from jointdb.fe import model_from_dict

    model_from_dict(body.model)
    return _accepted(response, queue(request).submit("diagnose", who.name, body.model_dump(mode="json")))


class OptimizeJobIn(BaseModel):
    model_config = ConfigDict(extra="forbid")

    spec: dict[str, Any] = Field(..., description="An optimize spec (format jointdb-optimize/1) with its stack "
                                 "inline: spindle, holders and tool as catalogued parts or inline, joints as "
                                 "catalogue queries; no file paths.")
    top: int = Field(20, ge=1, le=1000, description="Rows of the ranking in the result.")
    simulate: bool = Field(True, description="Check the best stack in the time domain.")


@router.post("/jobs/optimize", status_code=202, responses=_ACCEPTED,
             summary="The stack and cut of highest stable removal rate (job)")
def submit_optimize(body: OptimizeJobIn, request: Request, response: Response, who=reader) -> dict[str, Any]:
    """``jointdb optimize`` on a spec sent inline; the result as ``jointdb optimize --json`` prints it
    (ranking, best cut and binding constraint per candidate, joints, time-domain checks, figure data)."""
    from jointdb.usecases._optimize import enumerate_candidates, problem_from_document

    # a bad spec, an unknown part or family, or too many candidates is a 422 now, not a failed job later
    repo = request.app.state.repo
    enumerate_candidates(problem_from_document(body.spec, repo, where="spec", allow_files=False), repo)
    # the spec as sent (not model_dump: pydantic refuses to serialise a deeply nested body with a 500)
    payload = {"spec": body.spec, "top": body.top, "simulate": body.simulate}
    return _accepted(response, queue(request).submit("optimize", who.name, payload))


async def _identify_input(request: Request) -> tuple[dict[str, Any], bytes]:
    """The upload (multipart: ``file`` + form fields ``name``, ``conditions`` JSON; or JSON IdentifyIn)."""
    ctype = request.headers.get("content-type", "")
    if ctype.startswith("multipart/form-data"):
        form = await request.form(max_files=200, max_fields=20)
        uploads = [u for u in form.getlist("file") if not isinstance(u, str)]
        if not uploads:
            raise InputError("file: attach the campaign archive (.zip), or the campaign file and the files it "
                             "names, as form fields 'file'")
        upload = uploads[0]
        data = await upload.read() if len(uploads) == 1 else await _zip_of(uploads)
        raw_conditions = form.get("conditions") or "{}"
        try:
            conditions = json.loads(raw_conditions) if isinstance(raw_conditions, str) else {}
        except ValueError:
            raise InputError("conditions: must be a JSON object") from None
        body = IdentifyIn(filename=(upload.filename or "campaign.zip") if len(uploads) == 1 else "campaign.zip",
                          file_b64="", name=form.get("name") or None,
                          conditions=conditions if isinstance(conditions, dict) else {})
    else:
        try:
            body = IdentifyIn.model_validate_json(await request.body())
        except ValueError as exc:
            raise InputError(f"body: {' '.join(str(exc).split())[:200]}") from None
        try:
            data = base64.b64decode(body.file_b64, validate=True)
        except (binascii.Error, ValueError):
            raise InputError("file_b64 is not valid base64") from None
    return {"filename": Path(body.filename).name, "name": body.name,
            "conditions": body.conditions.to_conditions().to_dict()}, data


async def _zip_of(uploads) -> bytes:
    """Individual uploaded files (the campaign file and the files it names, side by side) as one
    archive, which then gets every check of an uploaded archive (names, sizes, one campaign file)."""
    import io
    import zipfile

    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as zf:
        for u in uploads:
            name = u.filename or ""
            if not name or "/" in name or "\\" in name or name.startswith(".") or not name.isprintable():
                raise InputError(f"file {name[:60]!r}: upload plain file names (no folders)")
            if name in zf.namelist():
                raise InputError(f"file {name[:60]!r} is uploaded twice")
            zf.writestr(name, await u.read())
    return buf.getvalue()


@router.post("/jobs/identify", status_code=202, responses=_ACCEPTED,
             summary="Identify an uploaded campaign (job; writer)")
async def submit_identify(request: Request, response: Response, who=writer) -> dict[str, Any]:
    """A campaign archive (.zip: the campaign file and the files it names); the archive is checked
    now (422 naming the member), identified by a worker; review the result, then catalogue."""
    from starlette.concurrency import run_in_threadpool

    payload, data = await _identify_input(request)
    if not data:
        raise InputError("file: the upload is empty")
    if not payload["filename"].lower().endswith(".zip"):
        raise InputError(f"filename {payload['filename'][:60]!r}: upload a campaign archive (.zip)")
    await run_in_threadpool(_check_archive, payload["filename"], data)
    job_id = await run_in_threadpool(queue(request).submit, "identify", who.name, payload, data)
    return _accepted(response, job_id)


def _check_archive(filename: str, data: bytes) -> None:
    from jointdb.jobs._review import unpack_upload

    with tempfile.TemporaryDirectory(prefix="jointdb-upload-") as tmp:
        unpack_upload(Path(tmp), filename, data)


@router.get("/jobs", summary="The caller's jobs, newest first")
def list_jobs(request: Request, who=reader, kind: Optional[str] = Query(None, max_length=20),
              state: Optional[str] = Query(None, max_length=20)) -> dict[str, Any]:
    from jointdb.jobs import job_json

    return {"items": [_scrubbed(request, job_json(r)) for r in queue(request).list(who.name, kind, state)]}


@router.get("/jobs/{job_id}", summary="A job: state, progress, message, error, result")
def get_job(job_id: JobId, request: Request, who=reader) -> dict[str, Any]:
    from jointdb.jobs import job_json

    return _scrubbed(request, job_json(_own(request, job_id, who)))


def _scrubbed(request: Request, job: dict[str, Any]) -> dict[str, Any]:
    """A job's JSON with no server folder or URL in its error (as every HTTP error, :mod:`._safety`)."""
    if job.get("error"):
        from jointdb.server._safety import hidden_dirs, scrub_message

        job["error"] = scrub_message(job["error"], hidden_dirs(request.app))
    return job


@router.post("/jobs/{job_id}/cancel", status_code=202, summary="Cancel a job")
def cancel_job(job_id: JobId, request: Request, who=reader) -> dict[str, Any]:
    """A queued job is cancelled at once; a running one stops at its next step."""
    _own(request, job_id, who)
    state = queue(request).cancel(job_id)
    return {"id": job_id, "url": f"/api/v1/jobs/{job_id}", "state": state}


def _reviewable(request: Request, job_id: str, who):
    row = _own(request, job_id, who)
    m = row._mapping
    if m["kind"] != "identify":
        raise InputError(f"job {job_id} is a {m['kind']} job; only identify jobs are catalogued")
    if m["state"] != "succeeded":
        raise InputError(f"job {job_id} is {m['state']}; catalogue it once it has succeeded")
    if m["outcome"]:
        from jointdb.errors import ConflictError

        raise ConflictError(f"job {job_id} was already {json.loads(m['outcome']).get('action', 'handled')}")
    return row


@router.post("/jobs/{job_id}/catalogue", status_code=201, summary="Catalogue an identify job's joint (writer)")
def catalogue_job(job_id: JobId, request: Request, response: Response, body: JobCatalogueIn | None = None,
                  who=writer) -> dict[str, Any]:
    """The identified joint as a new version (name, label, conditions may be given); 201, or 200 with
    ``"identical": true`` when the latest version holds the same joint."""
    from jointdb.jobs._review import catalogue_job as catalogue

    row = _reviewable(request, job_id, who)
    body = body or JobCatalogueIn()
    overrides = body.model_dump(mode="json")
    overrides["conditions"] = body.conditions.to_conditions().to_dict()
    outcome = catalogue(request.app.state.repo, row, overrides, who.name)
    v = outcome.version
    queue(request).rows.set(job_id, outcome=json.dumps({"action": "catalogued", "name": v.name,
                                                        "version": v.version}))
    response.status_code = 201 if outcome.created else 200
    return {**version_json(v), "identical": not outcome.created, "job": job_id}


@router.post("/jobs/{job_id}/discard", summary="Discard an identify job's joint")
def discard_job(job_id: JobId, request: Request, who=reader) -> dict[str, Any]:
    _reviewable(request, job_id, who)
    queue(request).rows.set(job_id, outcome=json.dumps({"action": "discarded"}), artifact=None, upload=None)
    return {"id": job_id, "discarded": True}
