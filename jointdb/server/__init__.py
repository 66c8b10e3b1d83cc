"""The joint database as an HTTP service (``jointdb serve``): FastAPI + uvicorn over
:class:`jointdb.store.Repository` — the same rules, the same transactions.

- :func:`create_app` (``settings``, optional open ``repo``) -> ASGI app;
  :func:`app_from_env` for ``uvicorn --factory`` (each worker builds its own).
- API under ``/api/v1`` (OpenAPI at ``/openapi.json``, docs at ``/docs``):
  reads need a reader token unless the server has open reads; writes a writer
  token (the audit log names the token's owner); ``/api/v1/admin`` an admin
  token. Tokens: :mod:`jointdb.store._tokens` (stored as SHA-256 only).
- Web catalogue under ``/ui`` (:mod:`jointdb.server.web`).
- ``/healthz`` (process up), ``/readyz`` (database reachable, schema current).

See docs/service.md.
"""

from __future__ import annotations

from jointdb.server._app import app_from_env, create_app
from jointdb.server._settings import Settings

__all__ = ["create_app", "app_from_env", "Settings"]
