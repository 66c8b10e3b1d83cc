"""A joint database behind ``jointdb serve``, used like :class:`jointdb.store.Repository`.

:class:`RemoteRepository` implements the store protocol :class:`jointdb.store.JointStore`
over HTTP (it lives in the store package, :mod:`jointdb.store._remote`, and imports no
server code); :func:`jointdb.store.open_store` opens it for an ``http(s)://`` address.
:func:`version_from_json` reads the API's JSON form of a version; :data:`RETRIES` is how many
times a request is retried.
"""

from __future__ import annotations

from jointdb.store._remote import RETRIES, RemoteRepository, version_from_json

__all__ = ["RETRIES", "RemoteRepository", "version_from_json"]
