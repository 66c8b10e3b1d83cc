"""The FastAPI application: settings, repository lifetime, error mapping, routes.

Every error becomes a JSON body ``{"error": "<one line>", "request_id": ...}``:
jointdb's own errors with their ``http_status`` (input 422, not found 404,
conflict 409), request validation 422 naming the field, a control character in a
query or path parameter 422 naming it, damaged stored data (IntegrityError) its
status with the message, any other server-side failure 500 with only the request
id (the error goes to the server log, never to the client). Every message is
scrubbed of URLs and server paths last (:func:`jointdb.server._safety.scrub_message`).
"""

from __future__ import annotations

import json
import logging
import os
from contextlib import asynccontextmanager

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from sqlalchemy.exc import DataError
from sqlalchemy.exc import TimeoutError as PoolTimeout
from starlette.exceptions import HTTPException as StarletteHTTPException

from jointdb.errors import IntegrityError, JointdbError
from jointdb.server._middleware import ServiceMiddleware
from jointdb.server._safety import ControlCharacterGuard, client_error, scrub_message
from jointdb.server._safety import hidden_dirs
from jointdb.server._security import install as install_security_headers
from jointdb.server._settings import Settings

log = logging.getLogger("jointdb.server")


def _one_line(text: object, limit: int = 300) -> str:
    line = " ".join(str(text).split())
    return line if len(line) <= limit else line[: limit - 3] + "..."


def _error(request: Request, status: int, message: str, headers=None) -> JSONResponse:
    rid = request.scope.get("state", {}).get("request_id")
    text = _one_line(scrub_message(str(message), hidden_dirs(request.app)))
    return JSONResponse({"error": text, "request_id": rid}, status_code=status, headers=headers)


def _note_failure(request: Request, exc: BaseException) -> None:
    """Put the failure on the request's log line (secrets are redacted by the log formatter)."""
    request.scope.setdefault("state", {})["error"] = f"{type(exc).__name__}: {_one_line(exc, 500)}"


def _value_fault(exc: BaseException) -> str | None:
    """A client's message when ``exc`` (or what it was translated from) is the database refusing
    a value the request sent: an integer too large for SQLite, or a PostgreSQL "data exception"
    (SQLSTATE class 22: a number out of range, NUL in text). None for anything else."""
    seen: BaseException | None = exc
    for _ in range(4):
        if seen is None:
            return None
        if isinstance(seen, OverflowError):
            return "a number in the request is too large for the database"
        if isinstance(seen, DataError) or str(getattr(seen, "sqlstate", "") or "").startswith("22"):
            return "a value in the request cannot be stored or compared (out of range or not valid text)"
        seen = seen.__cause__ or seen.__context__
    return None


def _validation_message(exc: RequestValidationError) -> str:
    parts = []
    for err in exc.errors()[:3]:
        where = ".".join(str(x) for x in err.get("loc", ()) if x != "body") or "body"
        msg = err.get("msg", "invalid")
        if err.get("type") == "json_invalid":
            ctx = err.get("ctx", {}) or {}
            return f"malformed JSON in the request body: {ctx.get('error', msg)}"
        parts.append(f"{where}: {msg}")
    return "; ".join(parts)


def _lifespan(settings: Settings, repo):
    """The app's lifespan: open the repository at start-up unless one was given (and close it)."""

    @asynccontextmanager
    async def lifespan(app: FastAPI):
        own = repo is None
        if own:
            from jointdb.store import Repository

            app.state.repo = Repository(settings.url, blobs=settings.blobs, auto_create=False,
                                        pool_size=settings.concurrency)  # one connection per admitted request
        log.info(json.dumps({"event": "startup", "database": _safe(app.state.repo.url)}))
        _start_jobs(app)
        try:
            yield
        finally:
            if getattr(app.state, "jobs", None) is not None:
                app.state.jobs.stop()
            if own:
                app.state.repo.close()
            log.info(json.dumps({"event": "shutdown"}))

    return lifespan


def _start_jobs(app: FastAPI) -> None:
    """The job queue (:mod:`jointdb.jobs`): in-process worker threads on SQLite (``JOINTDB_JOB_THREADS``,
    default 1; 0: none, jobs wait for a server that runs them), procrastinate on PostgreSQL (the jobs run
    in ``jointdb worker`` processes). A queue that cannot start leaves the job routes answering 503."""
    from jointdb.jobs import open_queue

    try:
        threads = int(os.environ.get("JOINTDB_JOB_THREADS", "1"))
        q = open_queue(app.state.repo, concurrency=max(threads, 1))
        if threads > 0 or q.backend != "in-process":
            q.start()
        else:
            from jointdb.jobs._table import ensure_table

            ensure_table(app.state.repo.write_engine)
        app.state.jobs = q
        import jointdb.stack  # noqa: F401 - checked at submission; loaded now, not by the first request

        log.info(json.dumps({"event": "jobs", "backend": q.backend, "threads": threads}))
    except Exception as exc:  # noqa: BLE001 - the catalogue still serves; the job routes say 503
        app.state.jobs = None
        log.error(json.dumps({"event": "jobs_unavailable", "error": _one_line(f"{type(exc).__name__}: {exc}")}))


async def _jointdb_error(request: Request, exc: JointdbError):
    rid = request.scope.get("state", {}).get("request_id")
    if exc.http_status >= 500 and _value_fault(exc):  # the database refused a value of the request
        return _error(request, 422, _value_fault(exc))
    status, text = client_error(exc, rid, hidden_dirs(request.app))  # 5xx: no URL, SQL or path
    if status >= 500 or isinstance(exc, IntegrityError):
        _note_failure(request, exc)  # the full text goes to the request's log line
    return _error(request, status, text)


async def _pool_timeout(request: Request, exc: PoolTimeout):
    """Every database connection stayed busy for the pool's whole wait: 503, try again (never a 500)."""
    _note_failure(request, exc)
    return _error(request, 503, "the service is busy (no database connection free); retry shortly",
                  headers={"Retry-After": "1"})


async def _overflow(request: Request, exc: OverflowError):
    return _error(request, 422, _value_fault(exc) or "a number in the request is out of range")


async def _data_error(request: Request, exc: DataError):  # a database error no store method translated
    return _error(request, 422, _value_fault(exc))


async def _validation(request: Request, exc: RequestValidationError):
    return _error(request, 422, _validation_message(exc))


async def _http(request: Request, exc: StarletteHTTPException):
    return _error(request, exc.status_code, str(exc.detail), getattr(exc, "headers", None))


async def _unexpected(request: Request, exc: Exception):  # only outside ServiceMiddleware, which
    rid = request.scope.get("state", {}).get("request_id")  # answers every route's exception itself
    log.error(json.dumps({"event": "error", "request_id": rid, "status": 500,
                          "error": f"{type(exc).__name__}: {_one_line(exc, 500)}"}), exc_info=exc)
    return _error(request, 500, f"internal error (request id {rid}); the server log has the details")


#: Each error type and its handler (see the module's docstring).
_ERROR_HANDLERS = ((JointdbError, _jointdb_error), (PoolTimeout, _pool_timeout), (OverflowError, _overflow), (DataError, _data_error),
                   (RequestValidationError, _validation), (StarletteHTTPException, _http), (Exception, _unexpected))


def healthz() -> dict:
    """The process is up (no database access)."""
    return {"status": "ok"}


def readyz(request: Request):
    """The database answers and has this jointdb's schema."""
    from jointdb.store import head_revision
    from jointdb.store._db import current_revision

    try:  # through the app's own engine: never open and close the SQLite file beside it
        current = current_revision(request.app.state.repo.read_engine)
    except Exception as exc:  # noqa: BLE001 - any failure means: not ready
        return _error(request, 503, f"database not ready: {type(exc).__name__}")
    head = head_revision()
    if current != head:
        return _error(request, 503, f"database schema is at {current}, this jointdb needs {head}")
    return {"status": "ready", "revision": current}


def _install_routes(app: FastAPI) -> None:
    """The API under ``/api/v1``, the web pages, the checkpoint and the health probes."""
    from jointdb.server import (routes_admin, routes_frf, routes_jobs, routes_joints, routes_parts, routes_query,
                                routes_writes, web)

    for module in (routes_joints, routes_frf, routes_query, routes_writes, routes_parts, routes_admin, routes_jobs):
        app.include_router(module.router, prefix="/api/v1")
    web.mount(app)
    from jointdb.server.routes_chain import install as install_checkpoints  # GET /api/v1/checkpoint

    install_checkpoints(app)
    app.get("/healthz", tags=["service"])(healthz)
    app.get("/readyz", tags=["service"])(readyz)


def create_app(settings: Settings | None = None, repo=None) -> FastAPI:
    """The jointdb service as an ASGI app.

    Parameters
    ----------
    settings
        :class:`Settings` (default: from the environment).
    repo
        An open :class:`jointdb.store.Repository` to serve (default: opened from
        ``settings.url`` / ``settings.blobs`` at start-up, closed at shutdown).
    """
    from jointdb import __version__

    settings = settings or Settings.from_env()
    app = FastAPI(
        title="jointdb",
        version=__version__,
        summary="Catalogue of machine-tool joint dynamics: versioned joints, FRFs, nearest-joint queries.",
        lifespan=_lifespan(settings, repo),
    )
    app.state.settings = settings
    if repo is not None:
        app.state.repo = repo
    for error, handler in _ERROR_HANDLERS:
        app.add_exception_handler(error, handler)
    _install_routes(app)
    install_security_headers(app, settings)
    app.add_middleware(ControlCharacterGuard, openapi=app.openapi)  # inside ServiceMiddleware: logged
    app.add_middleware(ServiceMiddleware, max_upload_bytes=settings.max_upload_bytes,
                       request_timeout_s=settings.request_timeout_s, concurrency=settings.concurrency,
                       max_queued=settings.max_queued)
    return app


def _safe(url: str) -> str:
    from jointdb.store._db import safe_url

    return safe_url(url)


def app_from_env() -> FastAPI:
    """Factory for ``uvicorn --factory jointdb.server:app_from_env`` (each worker builds one)."""
    logging.captureWarnings(True)  # a warning is a JSON log line too, not free text on stderr
    return create_app(Settings.from_env())
