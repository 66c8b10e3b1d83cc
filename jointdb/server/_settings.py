"""Settings of the HTTP service, from arguments or the environment (so that every
uvicorn worker process builds the same app)."""

from __future__ import annotations

import os
from dataclasses import dataclass

from jointdb.errors import InputError


def _env_bool(name: str, default: bool) -> bool:
    text = os.environ.get(name)
    if text is None or text == "":
        return default
    if text.lower() in ("1", "true", "yes", "on"):
        return True
    if text.lower() in ("0", "false", "no", "off"):
        return False
    raise InputError(f"${name} must be true or false, got {text!r}")


def _env_float(name: str, default: float) -> float:
    text = os.environ.get(name)
    if text is None or text == "":
        return default
    try:
        value = float(text)
    except ValueError:
        raise InputError(f"${name} must be a number, got {text!r}") from None
    if not value > 0:
        raise InputError(f"${name} must be > 0, got {text!r}")
    return value


def _env_count(name: str, default: int, lowest: int = 0) -> int:
    text = os.environ.get(name)
    if text is None or text == "":
        return default
    if not text.strip().isdigit() or not lowest <= int(text) <= 10_000:
        raise InputError(f"${name} must be a whole number {lowest}..10000, got {text!r}")
    return int(text)


LOOPBACK_HOSTS = frozenset({"127.0.0.1", "::1", "localhost"})


def _env_secure(name: str) -> bool | None:
    text = os.environ.get(name)
    if text is None or text.strip().lower() in ("", "auto"):
        return None
    return _env_bool(name, False)


@dataclass(frozen=True)
class Settings:
    """What ``jointdb serve`` runs with.

    ``url``/``blobs``: the repository (as :class:`jointdb.store.Repository`);
    ``open_reads``: reads without a token (default: every request needs one);
    ``max_upload_bytes``: largest request body; ``request_timeout_s``: longest
    time a request may take before the client gets 503 (the work itself is not
    interrupted: a write either commits whole or not at all).

    Web catalogue: ``secure_cookies`` True/False forces the cookies' ``Secure``
    flag (and HSTS); None (default, "auto") sets it unless ``bind_host`` is a
    loopback address (``jointdb serve`` on 127.0.0.1 or ::1 without TLS); an
    unknown ``bind_host`` counts as not loopback. ``session_idle_s`` and
    ``session_lifetime_s``: a sign-in ends after this long without a page
    view, and after this long at the latest.

    Load: ``concurrency`` requests are handled at once per worker process (the
    PostgreSQL connection pool is sized to it); up to ``max_queued`` more wait
    for a turn; beyond that a request is answered 429 with ``Retry-After`` at once
    instead of waiting for a connection that may never come (back-pressure).
    ``/healthz`` and ``/readyz`` are never queued.

    ``cache_dir``: the folder of encoded FRF downloads shared by the workers
    (:mod:`jointdb.server._encoded`); None: the default per-user cache folder;
    ``""``: memory only.
    """

    url: str | None = None
    blobs: str | None = None
    open_reads: bool = False
    max_upload_bytes: int = 64 * 2**20
    request_timeout_s: float = 60.0
    secure_cookies: bool | None = None
    bind_host: str | None = None
    session_idle_s: float = 30 * 60.0
    session_lifetime_s: float = 12 * 3600.0
    concurrency: int = 16
    max_queued: int = 64
    cache_dir: str | None = None

    @property
    def cookie_secure(self) -> bool:
        """Whether cookies carry ``Secure`` (and responses ``Strict-Transport-Security``)."""
        if self.secure_cookies is not None:
            return self.secure_cookies
        host = (self.bind_host or "").strip().strip("[]").lower()
        return host not in LOOPBACK_HOSTS

    @classmethod
    def from_env(cls) -> "Settings":
        """``JOINTDB_URL``, ``JOINTDB_BLOBS``, ``JOINTDB_OPEN_READS``, ``JOINTDB_MAX_UPLOAD_MB``,
        ``JOINTDB_REQUEST_TIMEOUT_S``, ``JOINTDB_SECURE_COOKIES`` (true, false or auto),
        ``JOINTDB_BIND_HOST`` (set by ``jointdb serve``), ``JOINTDB_SESSION_IDLE_MIN`` (30),
        ``JOINTDB_SESSION_HOURS`` (12), ``JOINTDB_CONCURRENCY`` (16), ``JOINTDB_MAX_QUEUED`` (64), ``JOINTDB_CACHE_DIR``."""
        return cls(
            url=os.environ.get("JOINTDB_URL") or None,
            blobs=os.environ.get("JOINTDB_BLOBS") or None,
            open_reads=_env_bool("JOINTDB_OPEN_READS", False),
            max_upload_bytes=int(_env_float("JOINTDB_MAX_UPLOAD_MB", 64.0) * 2**20),
            request_timeout_s=_env_float("JOINTDB_REQUEST_TIMEOUT_S", 60.0),
            secure_cookies=_env_secure("JOINTDB_SECURE_COOKIES"),
            bind_host=os.environ.get("JOINTDB_BIND_HOST") or None,
            session_idle_s=_env_float("JOINTDB_SESSION_IDLE_MIN", 30.0) * 60,
            session_lifetime_s=_env_float("JOINTDB_SESSION_HOURS", 12.0) * 3600,
            concurrency=_env_count("JOINTDB_CONCURRENCY", 16, lowest=1),
            max_queued=_env_count("JOINTDB_MAX_QUEUED", 64),
            cache_dir=os.environ.get("JOINTDB_CACHE_DIR"),
        )
