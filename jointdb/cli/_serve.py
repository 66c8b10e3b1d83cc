"""CLI: ``jointdb serve`` (the HTTP service) and ``jointdb tokens create|list|revoke``."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Annotated, Optional

import typer

from jointdb.cli._output import emit, message
from jointdb.cli._target import BlobsOpt, DbOpt, JsonOpt, check_db_target, open_repo
from jointdb.errors import InputError


def serve(
    host: Annotated[str, typer.Option("--host", help="Address to listen on.")] = "127.0.0.1",
    port: Annotated[int, typer.Option("--port", help="TCP port.")] = 8000,
    workers: Annotated[int, typer.Option("--workers", help="Worker processes (share the database).")] = 1,
    open_reads: Annotated[bool, typer.Option("--open-reads", help="Allow reads without a token (default: token-only).")] = False,
    max_upload_mb: Annotated[float, typer.Option("--max-upload-mb", help="Largest request body [MiB].")] = 64.0,
    timeout: Annotated[float, typer.Option("--timeout", help="Longest request time [s] before 503.")] = 60.0,
    concurrency: Annotated[int, typer.Option("--concurrency", help="Requests handled at once per worker (the PostgreSQL pool holds as many connections, plus half again in a burst).")] = 16,
    max_queued: Annotated[int, typer.Option("--max-queued", help="Requests that may wait for a turn per worker; more are answered 429 with Retry-After.")] = 64,
    log_level: Annotated[str, typer.Option("--log-level", help="debug, info, warning, error.")] = "info",
    secure_cookies: Annotated[Optional[bool], typer.Option(
        "--secure-cookies/--insecure-cookies",
        help="Force the web cookies' Secure flag on or off (default: on unless --host is loopback).")] = None,
    allow_owner: Annotated[bool, typer.Option("--allow-owner", help="Serve even as the tables' owner or a superuser (PostgreSQL).")] = False,
    checkpoint_key: Annotated[Optional[Path], typer.Option("--checkpoint-key", help="Ed25519 key: sign history checkpoints (GET /api/v1/checkpoint).")] = None,
    checkpoint_interval: Annotated[float, typer.Option("--checkpoint-interval", help="Sign a new checkpoint at most every N seconds.")] = 60.0,
    db: DbOpt = None,
    blobs: BlobsOpt = None,
) -> None:
    """Run the HTTP API and web catalogue (FastAPI + uvicorn) over the joint database.

    Tokens: `jointdb tokens create --name NAME --role writer`. PostgreSQL: run
    `jointdb db upgrade --db URL` first. Jobs (POST /api/v1/jobs/...: identify,
    predict, lobes, diagnose): on SQLite this server runs them itself (threads:
    $JOINTDB_JOB_THREADS, default 1); on PostgreSQL it only queues them and one or
    more `jointdb worker` processes (any host, same database) run them. Stops gracefully on SIGTERM/SIGINT (requests
    in flight finish; a write either commits whole or not at all).
    Example: jointdb serve --db postgresql+psycopg://host/jointdb --blobs /srv/blobs --workers 4 --port 8000
    """
    try:
        import uvicorn
    except ImportError:
        raise InputError("jointdb serve needs the server extra: pip install 'jointdb[server]'") from None
    _check_limits(port, workers, max_upload_mb, timeout, log_level)
    if not (1 <= concurrency <= 1000 and 0 <= max_queued <= 10_000):
        raise InputError(f"--concurrency must be 1..1000 and --max-queued 0..10000, got {concurrency}, {max_queued}")
    check_db_target(db)  # a missing SQLite file is refused here, never created by the server
    from jointdb.store._chain import check_serve_options

    env = check_serve_options(db, allow_owner, checkpoint_key, checkpoint_interval)  # roles: docs/service.md
    env |= {"JOINTDB_OPEN_READS": "1" if open_reads else "0", "JOINTDB_MAX_UPLOAD_MB": str(max_upload_mb),
            "JOINTDB_REQUEST_TIMEOUT_S": str(timeout), "JOINTDB_BIND_HOST": host,
            "JOINTDB_CONCURRENCY": str(concurrency), "JOINTDB_MAX_QUEUED": str(max_queued)}
    os.environ.update(env | _store_env(db, blobs, secure_cookies))  # every worker reads its settings from here
    import logging

    from jointdb.io._jsonlog import configure, event, log_config

    configure(log_level.lower())  # from here on every line on stderr is JSON, uvicorn's too
    event(logging.getLogger("jointdb.server"), "serve", url=f"http://{host}:{port}", workers=workers)
    uvicorn.run("jointdb.server:app_from_env", factory=True, host=host, port=port, workers=workers,
                log_config=log_config(log_level.lower()), access_log=False, timeout_graceful_shutdown=30,
                proxy_headers=False, server_header=False,
                http="jointdb.server._protocol:NoDelayHTTPProtocol")  # TCP_NODELAY with any worker count


def _check_limits(port: int, workers: int, max_upload_mb: float, timeout: float, log_level: str) -> None:
    """Refuse a port, worker count, upload limit [MiB], timeout [s] or log level out of range."""
    if not (1 <= port <= 65535):
        raise InputError(f"--port must be 1..65535, got {port}")
    if not (1 <= workers <= 64):
        raise InputError(f"--workers must be 1..64, got {workers}")
    if not max_upload_mb > 0 or not timeout > 0:
        raise InputError("--max-upload-mb and --timeout must be > 0")
    if log_level.lower() not in ("debug", "info", "warning", "error"):
        raise InputError(f"--log-level must be debug, info, warning or error, got {log_level!r}")


def _store_env(db: str | None, blobs: Path | None, secure_cookies: bool | None) -> dict[str, str]:
    """The environment that tells each worker its database, blob store and cookie flag."""
    env = {}
    if secure_cookies is not None:
        env["JOINTDB_SECURE_COOKIES"] = "1" if secure_cookies else "0"
    if db is not None:
        env["JOINTDB_URL"] = db
    if blobs is not None:
        env["JOINTDB_BLOBS"] = "database" if str(blobs) == "database" else str(Path(blobs).resolve())
    return env


def tokens_create(
    name: Annotated[str, typer.Option("--name", help="Owner: the audit log names them for the token's writes.")],
    role: Annotated[str, typer.Option("--role", help="reader | writer | admin.")],
    expires: Annotated[Optional[str], typer.Option("--expires", help="ISO time or lifetime (30d, 12h, 90m).")] = None,
    team: Annotated[Optional[str], typer.Option(
        "--team", help="Team: its writers may label and deprecate each other's joints.")] = None,
    db: DbOpt = None, blobs: BlobsOpt = None, as_json: JsonOpt = False,
) -> None:
    """Create an API token; it is printed once and stored only as its SHA-256.

    A writer may label and deprecate the joints they catalogued, or that a member of
    their --team catalogued; an admin any joint.
    Example: jointdb tokens create --name alice --role writer --team spindles --expires 90d
    """
    from jointdb.store._tokens import check_owner, check_role, check_team, create_token, parse_expiry

    check_owner(name), check_role(role), check_team(team), parse_expiry(expires)  # before the database is opened
    token, info = create_token(open_repo(db, blobs), name, role, expires, team=team)
    message("store this token now: it is not shown again")
    emit({"token": token, **info.to_dict()}, as_json=as_json)


def tokens_list(db: DbOpt = None, blobs: BlobsOpt = None, as_json: JsonOpt = False) -> None:
    """List tokens: id, owner, role, status, expiry (never the token)."""
    from jointdb.store._tokens import list_tokens

    emit([t.to_dict() for t in list_tokens(open_repo(db, blobs))], as_json=as_json, title="tokens",
         columns=["token_id", "name", "role", "team", "status", "created_at", "expires_at"])


def tokens_revoke(
    token_id: Annotated[str, typer.Argument(help="Token id (12 hex digits, from `jointdb tokens list`).")],
    db: DbOpt = None, blobs: BlobsOpt = None, as_json: JsonOpt = False,
) -> None:
    """Revoke a token at once (every worker refuses it on its next request)."""
    from jointdb.store._tokens import revoke_token

    emit(revoke_token(open_repo(db, blobs), token_id).to_dict(), as_json=as_json)


def register(app: typer.Typer) -> None:
    """Add ``serve`` and ``tokens ...`` to the app."""
    tokens = typer.Typer(help="API tokens of the HTTP service: create, list, revoke.", no_args_is_help=True)
    app.add_typer(tokens, name="tokens")

    app.command("serve")(serve)
    tokens.command("create")(tokens_create)
    tokens.command("list")(tokens_list)
    tokens.command("revoke")(tokens_revoke)
