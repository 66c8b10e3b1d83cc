"""Logging of ``jointdb serve``: one JSON object per line on stderr (access log and errors)."""

from __future__ import annotations


def log_config(level: str = "info") -> dict:
    """A :func:`logging.config.dictConfig` for uvicorn: plain messages (already JSON for
    requests) prefixed by nothing, so that every line can be parsed."""
    fmt = '{"time": "%(asctime)s", "level": "%(levelname)s", "logger": "%(name)s", "message": %(message)r}'
    return {
        "version": 1,
        "disable_existing_loggers": False,
        "formatters": {"plain": {"format": "%(message)s"}, "wrapped": {"format": fmt}},
        "handlers": {
            "access": {"class": "logging.StreamHandler", "formatter": "plain", "stream": "ext://sys.stderr"},
            "other": {"class": "logging.StreamHandler", "formatter": "wrapped", "stream": "ext://sys.stderr"},
        },
        "loggers": {
            "jointdb.server.access": {"handlers": ["access"], "level": level.upper(), "propagate": False},
            "jointdb.server": {"handlers": ["other"], "level": level.upper(), "propagate": False},
            "uvicorn": {"handlers": ["other"], "level": level.upper(), "propagate": False},
            "uvicorn.error": {"handlers": ["other"], "level": level.upper(), "propagate": False},
        },
    }
