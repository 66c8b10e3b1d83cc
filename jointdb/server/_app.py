"""The FastAPI application: settings, repository lifetime, error mapping, routes.

Every error becomes a JSON body ``{"error": "<one line>", "request_id": ...}``:
jointdb's own errors with their ``http_status`` (input 422, not found 404,
conflict 409), request validation 422 naming the field, anything unexpected 500
with only the request id (the traceback goes to the server log, never to the
client).
"""

from __future__ import annotations

import logging
from contextlib import asynccontextmanager

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from starlette.exceptions import HTTPException as StarletteHTTPException

from jointdb.errors import JointdbError
from jointdb.server._middleware import ServiceMiddleware
from jointdb.server._settings import Settings

log = logging.getLogger("jointdb.server")


def _one_line(text: object, limit: int = 300) -> str:
    line = " ".join(str(text).split())
    return line if len(line) <= limit else line[: limit - 3] + "..."


def _error(request: Request, status: int, message: str, headers=None) -> JSONResponse:
    rid = request.scope.get("state", {}).get("request_id")
    return JSONResponse({"error": _one_line(message), "request_id": rid}, status_code=status, headers=headers)


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

    @asynccontextmanager
    async def lifespan(app: FastAPI):
        own = repo is None
        if own:
            from jointdb.store import Repository

            app.state.repo = Repository(settings.url, blobs=settings.blobs, auto_create=False)
        log.info('{"event": "startup", "database": "%s"}', _safe(app.state.repo.url))
        try:
            yield
        finally:
            if own:
                app.state.repo.close()
            log.info('{"event": "shutdown"}')

    app = FastAPI(
        title="jointdb",
        version=__version__,
        summary="Catalogue of machine-tool joint dynamics: versioned joints, FRFs, nearest-joint queries.",
        lifespan=lifespan,
    )
    app.state.settings = settings
    if repo is not None:
        app.state.repo = repo

    @app.exception_handler(JointdbError)
    async def _jointdb_error(request: Request, exc: JointdbError):
        status = exc.http_status if exc.http_status != 500 else 500
        if status >= 500:
            log.error("request %s: %s: %s", request.scope.get("state", {}).get("request_id"),
                      type(exc).__name__, _one_line(exc))
        return _error(request, status, str(exc))

    @app.exception_handler(RequestValidationError)
    async def _validation(request: Request, exc: RequestValidationError):
        return _error(request, 422, _validation_message(exc))

    @app.exception_handler(StarletteHTTPException)
    async def _http(request: Request, exc: StarletteHTTPException):
        return _error(request, exc.status_code, str(exc.detail), getattr(exc, "headers", None))

    @app.exception_handler(Exception)
    async def _unexpected(request: Request, exc: Exception):
        rid = request.scope.get("state", {}).get("request_id")
        log.exception("request %s failed", rid)
        return _error(request, 500, f"internal error (request id {rid}); the server log has the details")

    from jointdb.server import routes_admin, routes_frf, routes_joints, routes_query, routes_writes, web

    for module in (routes_joints, routes_frf, routes_query, routes_writes, routes_admin):
        app.include_router(module.router, prefix="/api/v1")
    web.mount(app)
    from jointdb.server.routes_chain import install as install_checkpoints  # GET /api/v1/checkpoint

    install_checkpoints(app)

    @app.get("/healthz", tags=["service"])
    def healthz() -> dict:
        """The process is up (no database access)."""
        return {"status": "ok"}

    @app.get("/readyz", tags=["service"])
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

    app.add_middleware(ServiceMiddleware, max_upload_bytes=settings.max_upload_bytes,
                       request_timeout_s=settings.request_timeout_s)
    return app


def _safe(url: str) -> str:
    from jointdb.store._db import safe_url

    return safe_url(url)


def app_from_env() -> FastAPI:
    """Factory for ``uvicorn --factory jointdb.server:app_from_env`` (each worker builds one)."""
    return create_app(Settings.from_env())
