"""What the service says must not reveal the server: scrubbing of error messages and log
lines, and refusal of control characters in query and path parameters.

- :func:`scrub_message` (error bodies): database and other URLs become ``<url>``,
  absolute paths (POSIX and Windows; the temporary, blob and database folders
  first) become their last part, so a message may still name the file the user
  sent but never where the server keeps it. It is the last line of defence; the
  messages are meant not to carry paths in the first place.
- log lines are redacted by :func:`jointdb.io._jsonlog.redact_secrets` (shared with
  the CLI, which configures the log of ``jointdb serve``).
- :class:`ControlCharacterGuard` (ASGI): a NUL or other control character in a
  query parameter or in the path is a 422 naming the parameter, before any route
  or database sees it.
"""

from __future__ import annotations

import json
import os
import re
import tempfile
from urllib.parse import parse_qsl

_URL = re.compile(r"\b[A-Za-z][A-Za-z0-9+.\-]*://[^\s'\"<>]*[^\s'\"<>/.,;:)]")
_POSIX_PATH = re.compile(r"(?<![\w.~:/\-])(?:/[^\s/'\"(),;:<>\[\]{}|]+){2,}/?")
_WINDOWS_PATH = re.compile(r"(?<![\w])[A-Za-z]:\\[^\s'\"(),;<>|]*")
_UPLOAD_DIR = re.compile(r"\bjointdb-upload-[^/\\\s]+[/\\](?:campaign[/\\])?")


def _last_part(match: re.Match) -> str:
    text = match.group(0).rstrip("/\\")
    return re.split(r"[/\\]", text)[-1] or "<path>"


def _known_dirs(extra: tuple[str, ...]) -> list[str]:
    dirs = {tempfile.gettempdir(), os.path.realpath(tempfile.gettempdir()), *extra}
    dirs = {d.rstrip("/\\") for d in dirs if d and os.path.isabs(d)}
    return sorted((d for d in dirs if len(d) > 1), key=len, reverse=True)


def scrub_message(text: str, dirs: tuple[str, ...] = ()) -> str:
    """``text`` without URLs or server paths (see the module's docstring).

    Parameters
    ----------
    text
        An error message meant for a client.
    dirs
        Folders of the server to hide first (blob folder, database file's folder).
    """
    for d in _known_dirs(dirs):
        text = text.replace(d + "/", "").replace(d + "\\", "").replace(d, "<server folder>")
    text = _UPLOAD_DIR.sub("", text)
    text = _URL.sub("<url>", text)
    text = _WINDOWS_PATH.sub(_last_part, text)
    return _POSIX_PATH.sub(_last_part, text)


def client_error(exc: BaseException, request_id: str | None, dirs: tuple[str, ...] = ()) -> tuple[int, str]:
    """Status and one-line message a client may see for a jointdb error (API and web pages).

    Damaged stored data (:class:`~jointdb.errors.IntegrityError`) keeps its status and says
    what failed; any other server-side error (status >= 500: database, driver) is only
    "internal error" with the request id, its text staying in the log; a client error
    (4xx) keeps its message. Every message is scrubbed (:func:`scrub_message`).
    """
    from jointdb.errors import IntegrityError, JointdbError

    status = int(getattr(exc, "http_status", 500)) if isinstance(exc, JointdbError) else 500
    if isinstance(exc, IntegrityError):
        text = f"stored data failed its integrity check: {exc} (request id {request_id})"
    elif status >= 500:
        status, text = 500, f"internal error (request id {request_id}); the server log has the details"
    else:
        text = str(exc)
    return status, " ".join(scrub_message(text, dirs).split())


#: Unicode's category Cc (control) is exactly U+0000-U+001F and U+007F-U+009F.
_CONTROL = re.compile("[\x00-\x1f\x7f-\x9f]")


def _has_control(text: str) -> bool:
    return _CONTROL.search(text) is not None


class ControlCharacterGuard:
    """ASGI middleware: 422 for a control character (NUL, newline, escape, ...) in a query
    parameter's name or value, or in the path (naming the route's path parameter)."""

    def __init__(self, app, openapi=None):
        self.app = app
        self.openapi = openapi
        self._templates: list[tuple[re.Pattern, str]] | None = None

    def _path_parameter(self, path: str) -> str:
        """Which path parameter of the API holds the control character (its OpenAPI template)."""
        if self._templates is None:
            try:
                paths = list((self.openapi() if self.openapi else {}).get("paths", {}))
            except Exception:  # noqa: BLE001 - no schema: name the path only
                paths = []
            self._templates = [(re.compile("^" + re.sub(r"\\\{(\w+)\\\}", r"(?P<\1>[^/]*)", re.escape(t)) + "$"), t)
                               for t in paths if "{" in t]
        for pattern, _ in self._templates:
            m = pattern.match(path)
            if m:
                for name, value in m.groupdict().items():
                    if _has_control(value):
                        return f"path parameter {name!r}"
        return "the path"

    def _offender(self, scope) -> str | None:
        if _has_control(scope.get("path", "")):
            return self._path_parameter(scope["path"])
        query = scope.get("query_string", b"").decode("latin-1")
        if query:
            for name, value in parse_qsl(query, keep_blank_values=True):
                if _has_control(name):
                    return "a query parameter name"
                if _has_control(value):
                    return f"query parameter {name[:40]!r}"
        return None

    async def __call__(self, scope, receive, send):
        if scope["type"] == "http":
            where = self._offender(scope)
            if where is not None:
                rid = scope.get("state", {}).get("request_id")
                body = json.dumps({"error": f"{where} contains a control character (such as NUL); remove it",
                                   "request_id": rid}).encode()
                await send({"type": "http.response.start", "status": 422,
                            "headers": [(b"content-type", b"application/json"),
                                        (b"content-length", str(len(body)).encode())]})
                await send({"type": "http.response.body", "body": body})
                return
        await self.app(scope, receive, send)


def hidden_dirs(app) -> tuple[str, ...]:
    """Server folders no message may show: the blob folder and the SQLite file's folder."""
    dirs = getattr(app.state, "hidden_dirs", None)
    if dirs is None:
        found = []
        blobs = getattr(app.state.settings, "blobs", None)
        if blobs and blobs != "database":
            found += [str(blobs), os.path.realpath(blobs)]
        repo = getattr(app.state, "repo", None)
        root = getattr(getattr(repo, "blobs", None), "root", None)
        if isinstance(root, (str, os.PathLike)) and os.path.isdir(root):
            found += [str(root), os.path.realpath(root)]
        try:
            from sqlalchemy.engine import make_url

            database = make_url(repo.url).database if repo is not None else None
            if database and "/" in database:
                found += [os.path.dirname(database), os.path.dirname(os.path.realpath(database))]
        except Exception:  # noqa: BLE001 - no URL to parse: nothing more to hide
            pass
        dirs = app.state.hidden_dirs = tuple(d for d in found if len(d) > 1)
    return dirs
