"""One ASGI middleware: request id, admission (back-pressure), upload-size limit,
request time limit and one structured (JSON) log line per request.

Admission: at most ``concurrency`` requests run in the app at once, at most
``max_queued`` wait for a turn; one more is answered 429 with ``Retry-After`` at
once (no database connection is taken, nothing waits for a pool that is empty).
The probes (``/healthz``, ``/readyz``) are never queued.

The log line holds method, path (never the query string or any header, so a
token can never reach it), status, duration, body size, the token owner and a
request id (also sent back as ``X-Request-ID``); for a failure (status 500) also
``error`` (one line) and, for an exception no route handled, ``traceback`` (one
string). Such an exception is answered here with a 500 carrying only the request
id, so it is logged once, with its status.
"""

from __future__ import annotations

import asyncio
import json
import logging
import time
import traceback
import uuid

log = logging.getLogger("jointdb.server.access")


#: Paths that bypass admission: a load balancer's probes must answer while the service is busy.
UNQUEUED = frozenset({"/healthz", "/readyz"})
RETRY_AFTER_S = 1
#: The HTTP versions served (uvicorn's httptools parser also accepts HTTP/0.9, which has no headers).
HTTP_VERSIONS = frozenset({"1.0", "1.1"})


def _json_response(status: int, message: str, request_id: str) -> tuple[dict, dict]:
    body = json.dumps({"error": message, "request_id": request_id}).encode()
    headers = [(b"content-type", b"application/json"), (b"content-length", str(len(body)).encode())]
    if status in (429, 503):
        headers.append((b"retry-after", str(RETRY_AFTER_S).encode()))
    start = {"type": "http.response.start", "status": status, "headers": headers}
    return start, {"type": "http.response.body", "body": body}


class Busy(Exception):
    """More requests are waiting than the queue holds."""


class Admission:
    """At most ``concurrency`` holders at once; at most ``max_queued`` waiting (else :class:`Busy`).

    Runs on one event loop (one per worker process), so the counters need no lock.
    """

    def __init__(self, concurrency: int, max_queued: int):
        if concurrency < 1 or max_queued < 0:
            raise ValueError(f"concurrency must be >= 1 and max_queued >= 0, got {concurrency}, {max_queued}")
        self.concurrency, self.max_queued = int(concurrency), int(max_queued)
        self.running = 0
        self.waiting = 0
        self._turns: asyncio.Semaphore | None = None  # made on the loop that uses it

    async def enter(self) -> None:
        if self._turns is None:
            self._turns = asyncio.Semaphore(self.concurrency)
        if self._turns.locked() and self.waiting >= self.max_queued:
            raise Busy
        self.waiting += 1
        try:
            await self._turns.acquire()  # a cancelled wait (request time limit) gives no turn away
        finally:
            self.waiting -= 1
        self.running += 1

    def leave(self) -> None:
        self.running -= 1
        self._turns.release()


class ServiceMiddleware:
    def __init__(self, app, max_upload_bytes: int, request_timeout_s: float,
                 concurrency: int = 16, max_queued: int = 64):
        self.app = app
        self.max_upload = int(max_upload_bytes)
        self.timeout = float(request_timeout_s)
        self.admission = Admission(concurrency, max_queued)

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        if scope.get("http_version", "1.1") not in HTTP_VERSIONS:  # HTTP/0.9 (httptools parses it): refused
            start, body = _json_response(400, "HTTP/1.0 or HTTP/1.1 requests only", "")
            await send(start)
            await send(body)
            return
        request_id = uuid.uuid4().hex[:16]
        scope.setdefault("state", {})["request_id"] = request_id
        t0 = time.perf_counter()
        status = {"code": 0, "started": False}
        received = {"n": 0}
        limit = self.max_upload

        async def send_wrapped(message):
            if message["type"] == "http.response.start":
                status["code"] = message["status"]
                status["started"] = True
                message.setdefault("headers", [])
                message["headers"] = list(message["headers"]) + [(b"x-request-id", request_id.encode())]
            await send(message)

        async def read_body() -> list[dict] | None:
            """The whole request body (at most ``limit`` bytes), or None when it is larger."""
            messages = []
            while True:
                message = await receive()
                messages.append(message)
                if message["type"] != "http.request":
                    return messages
                received["n"] += len(message.get("body", b""))
                if received["n"] > limit:
                    return None
                if not message.get("more_body", False):
                    return messages

        async def refuse(code: int, text: str):
            if not status["started"]:
                start, body = _json_response(code, text, request_id)
                await send_wrapped(start)
                await send(body)

        headers = dict(scope.get("headers") or [])
        try:
            declared = int(headers.get(b"content-length", b"0"))
        except ValueError:
            declared = -1
        try:
            if declared < 0:
                await refuse(400, "Content-Length is not a number")
            elif declared > limit:
                await refuse(413, f"request body of {declared} bytes exceeds the limit of {limit} bytes")
            else:
                async with asyncio.timeout(self.timeout):  # in this task (wait_for would start one per call)
                    buffered = await read_body()
                if buffered is None:
                    await refuse(413, f"request body exceeds the limit of {limit} bytes")
                else:
                    async def replay():
                        return buffered.pop(0) if buffered else await receive()

                    async with asyncio.timeout(self.timeout):
                        await self._admitted(scope, replay, send_wrapped)
        except Busy:
            await refuse(429, f"the service is busy ({self.admission.concurrency} requests running, "
                              f"{self.admission.waiting} waiting); retry in {RETRY_AFTER_S} s")
        except asyncio.TimeoutError:
            await refuse(503, f"request took longer than {self.timeout:g} s; try again or narrow the request")
        except Exception as exc:  # noqa: BLE001 - unhandled: one 500 and one log line with the traceback
            state = scope.setdefault("state", {})
            state["error"] = f"{type(exc).__name__}: {' '.join(str(exc).split())[:500]}"
            state["traceback"] = "".join(traceback.format_exception(type(exc), exc, exc.__traceback__))
            await refuse(500, f"internal error (request id {request_id}); the server log has the details")
            status["code"] = max(status["code"], 500)  # also when a streamed response broke off
        finally:
            state = scope.get("state", {})
            line = {
                "event": "request", "request_id": request_id, "method": scope.get("method"),
                "path": scope.get("path"), "status": status["code"],
                "duration_ms": round((time.perf_counter() - t0) * 1e3, 2), "bytes_in": received["n"],
                "actor": state.get("actor"), "client": (scope.get("client") or [None])[0],
            }
            line.update({k: state[k] for k in ("error", "traceback") if state.get(k)})
            log.log(logging.ERROR if status["code"] >= 500 else logging.INFO, json.dumps(line))

    async def _admitted(self, scope, receive, send) -> None:
        """Run the app for one request once admission lets it in (probes at once)."""
        if scope.get("path") in UNQUEUED:
            await self.app(scope, receive, send)
            return
        await self.admission.enter()
        try:
            await self.app(scope, receive, send)
        finally:
            self.admission.leave()
