"""JSON log lines (used by ``jointdb serve``): every line on stderr is one JSON object.

jointdb's own lines (the request log of :mod:`jointdb.server._middleware`, start-up,
errors) and uvicorn's (``uvicorn.error``: start, shutdown, worker processes;
``uvicorn.access`` when enabled) and any other library's go through
:class:`JsonFormatter`: ``{"time", "level", "logger", ...}`` where a message that is
itself a JSON object contributes its fields (``{"event": "request", ...}`` keeps its
keys first) and any other message is ``"message"``. A traceback is one string field
(``"traceback"``), never extra lines. Passwords in URLs, API tokens, bearer
credentials and cookie values are replaced by ``***`` in every field
(:func:`redact_secrets`).

It sits below the CLI and the HTTP service so that both configure the same logging
without importing each other: ``jointdb serve`` applies it in the parent process and
hands :func:`log_config` to uvicorn for the workers.
"""

from __future__ import annotations

import json
import logging
import logging.config
import re
import traceback
from datetime import datetime, timezone
from typing import Any

_LEVELS = ("debug", "info", "warning", "error")
_URL_PASSWORD = re.compile(r"(://[^:/@\s]*:)[^@\s]*@")
_TOKEN = re.compile(r"\b(jdb_[0-9a-f]{12}_)[A-Za-z0-9_\-]+")
_BEARER = re.compile(r"(?i)\b(bearer|basic)(\s+)[^\s'\",]+")
_HEADER_SECRET = re.compile(r"(?i)\b(authorization|cookie|set-cookie|x-api-key)(['\"]?\s*[:=,]\s*['\"]?)[^'\"\n]+")

def redact_secrets(text: str) -> str:
    """``text`` with URL passwords, API tokens, bearer credentials and cookie values hidden."""
    text = _URL_PASSWORD.sub(r"\1***@", text)
    text = _TOKEN.sub(r"\1***", text)
    text = _BEARER.sub(r"\1\2***", text)
    return _HEADER_SECRET.sub(r"\1\2***", text)


def _redacted(value: Any) -> Any:
    if isinstance(value, str):
        return redact_secrets(value)
    if isinstance(value, dict):
        return {k: _redacted(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_redacted(v) for v in value]
    return value


def _fields(record: logging.LogRecord) -> dict[str, Any]:
    """The record's own fields: a JSON-object message's keys, uvicorn's access tuple, or the message."""
    if record.name == "uvicorn.access" and isinstance(record.args, tuple) and len(record.args) == 5:
        client, method, path, _, status = record.args  # never the query string
        return {"event": "access", "client": str(client), "method": str(method),
                "path": str(path).split("?", 1)[0], "status": status}
    try:
        text = record.getMessage()
    except (TypeError, ValueError):  # a message whose arguments do not fit its format
        text = f"{record.msg!s} {record.args!r}"
    if text.startswith("{"):
        try:
            parsed = json.loads(text)
        except ValueError:
            parsed = None
        if isinstance(parsed, dict):
            return parsed
    return {"message": text}


class JsonFormatter(logging.Formatter):
    """One JSON object per record (see the module's docstring)."""

    def format(self, record: logging.LogRecord) -> str:
        out = _fields(record)
        out.setdefault("time", datetime.fromtimestamp(record.created, timezone.utc).isoformat(timespec="milliseconds"))
        out.setdefault("level", record.levelname)
        out.setdefault("logger", record.name)
        if record.exc_info and record.exc_info[0] is not None:
            out["traceback"] = "".join(traceback.format_exception(*record.exc_info))
        if record.stack_info:
            out["stack"] = str(record.stack_info)
        return json.dumps(_redacted(out), default=str, ensure_ascii=False)


def log_config(level: str = "info") -> dict:
    """A :func:`logging.config.dictConfig` (for uvicorn's ``log_config`` and the parent
    process): every logger, uvicorn's included, writes JSON lines to stderr."""
    lvl = level.upper()
    handler = {"handlers": ["json"], "level": lvl, "propagate": False}
    return {
        "version": 1,
        "disable_existing_loggers": False,
        "formatters": {"json": {"()": "jointdb.io._jsonlog.JsonFormatter"}},
        "handlers": {"json": {"class": "logging.StreamHandler", "formatter": "json", "stream": "ext://sys.stderr"}},
        "loggers": {name: dict(handler) for name in
                    ("jointdb", "jointdb.server", "jointdb.server.access", "uvicorn", "uvicorn.error",
                     "uvicorn.access", "py.warnings")},
        "root": {"handlers": ["json"], "level": "WARNING"},
    }


def configure(level: str = "info") -> None:
    """Apply :func:`log_config` in this process and route warnings through it."""
    if level.lower() not in _LEVELS:
        level = "info"
    logging.config.dictConfig(log_config(level))
    logging.captureWarnings(True)


def event(logger: logging.Logger, name: str, level: int = logging.INFO, **fields: Any) -> None:
    """Log ``{"event": name, **fields}`` as one JSON line."""
    logger.log(level, json.dumps({"event": name, **fields}, default=str))
