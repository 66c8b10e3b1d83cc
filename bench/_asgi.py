"""One HTTP request straight into an ASGI app: a hand-built scope, the body collected from the
``send`` messages. No socket and no HTTP client, so what a bench times is the app's own work
(middleware, routing, dependencies, the route, JSON); an HTTP client's request building and
response parsing is not in it."""

from __future__ import annotations


async def call(app, method: str, path: str, query: str = "", body: bytes = b"", token: str = "") -> tuple[int, bytes]:
    """One request through the ASGI app; its status and whole body."""
    headers = [(b"host", b"bench")] + ([(b"authorization", f"Bearer {token}".encode())] if token else [])
    if body:
        headers += [(b"content-type", b"application/json"), (b"content-length", str(len(body)).encode())]
    scope = {"type": "http", "asgi": {"version": "3.0"}, "http_version": "1.1", "method": method,
             "scheme": "http", "path": path, "raw_path": path.encode(), "query_string": query.encode(),
             "root_path": "", "headers": headers, "client": ("127.0.0.1", 1), "server": ("bench", 80)}
    sent = [{"type": "http.request", "body": body, "more_body": False}]
    out = {"status": 0, "body": []}

    async def receive():
        return sent.pop(0) if sent else {"type": "http.disconnect"}

    async def send(message):
        if message["type"] == "http.response.start":
            out["status"] = message["status"]
        elif message["type"] == "http.response.body":
            out["body"].append(message.get("body", b""))

    await app(scope, receive, send)
    return out["status"], b"".join(out["body"])
