"""Logging of ``jointdb serve``: one JSON object per line on stderr.

The formatter and the configuration live in :mod:`jointdb.io._jsonlog`, below both
shells, so the CLI (which configures the parent process) does not import the server.
"""

from jointdb.io._jsonlog import JsonFormatter, configure, event, log_config, redact_secrets

__all__ = ["JsonFormatter", "configure", "event", "log_config", "redact_secrets"]
