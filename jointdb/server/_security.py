"""Security headers on every response of the service: pages, API answers, errors (500s
and the refusals of the service middleware included), static files.

- ``Content-Security-Policy``: everything from this server only, no inline script or
  style, no plugins, no framing, forms post only here (the pages have no inline code;
  ``/docs`` starts Swagger UI from a file of its own).
- ``X-Frame-Options: DENY``, ``X-Content-Type-Options: nosniff``,
  ``Referrer-Policy: same-origin`` (with ``no-referrer`` a browser sends ``Origin: null``
  on every form POST, which the CSRF origin check must refuse), and
  ``Cross-Origin-Opener-Policy`` / ``Cross-Origin-Resource-Policy: same-origin``.
- ``Cache-Control: no-store`` on every answer that does not set its own caching: pages
  and API answers carry catalogue data behind a token. The FRF downloads of the API keep
  theirs (a strong ETag; ``private`` with ``Vary: Authorization`` behind a token, a pinned
  version never changes); the web catalogue's downloads are ``no-store`` when signed in.
  Static files (CSS, Swagger UI) are public: ``no-cache`` (revalidated with their ETag).
- ``Strict-Transport-Security`` when the cookies are ``Secure`` (:attr:`Settings.cookie_secure`).

Headers a response already carries are kept.
"""

from __future__ import annotations

CSP = ("default-src 'self'; script-src 'self'; style-src 'self'; img-src 'self' data:; font-src 'self'; "
       "connect-src 'self'; object-src 'none'; base-uri 'none'; form-action 'self'; frame-ancestors 'none'")
STATIC_PREFIXES = ("/ui/static/",)
HSTS = "max-age=31536000"


def security_headers(path: str, secure: bool) -> list[tuple[bytes, bytes]]:
    """The headers every response to ``path`` gets (unless it sets them itself)."""
    cache = "no-cache" if path.startswith(STATIC_PREFIXES) else "no-store"
    headers = [("content-security-policy", CSP), ("x-frame-options", "DENY"),
               ("x-content-type-options", "nosniff"), ("referrer-policy", "same-origin"),
               ("cross-origin-opener-policy", "same-origin"), ("cross-origin-resource-policy", "same-origin"),
               ("cache-control", cache)]
    if secure:
        headers.append(("strict-transport-security", HSTS))
    return [(k.encode(), v.encode()) for k, v in headers]


class SecurityHeadersMiddleware:
    """ASGI middleware adding :func:`security_headers` to every HTTP response."""

    def __init__(self, app, secure: bool):
        self.app = app
        self.secure = bool(secure)
        self._static = security_headers(STATIC_PREFIXES[0], self.secure)  # built once, not per request
        self._other = security_headers("/", self.secure)

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        extra = self._static if scope.get("path", "").startswith(STATIC_PREFIXES) else self._other

        async def send_with_headers(message):
            if message["type"] == "http.response.start":
                headers = list(message.get("headers") or [])
                present = {k.lower() for k, _ in headers}
                headers += [(k, v) for k, v in extra if k not in present]
                message = {**message, "headers": headers}
            await send(message)

        await self.app(scope, receive, send_with_headers)


def install(app, settings) -> None:
    """Wrap ``app``'s whole middleware stack in :class:`SecurityHeadersMiddleware`.

    Outside Starlette's own error middleware (which answers unexpected exceptions with
    500 *outside* every ``add_middleware`` middleware), so that 500s get the headers too.
    """
    build = app.build_middleware_stack

    def build_with_security_headers():
        return SecurityHeadersMiddleware(build(), settings.cookie_secure)

    app.build_middleware_stack = build_with_security_headers
