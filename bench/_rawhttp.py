"""A cheap HTTP/1.1 client for load benches: one kept-alive socket, requests built before the
clock starts, every response read whole (status line, headers, ``Content-Length`` body).

The load generator shares the machine's cores with the server, so its own CPU per request
is kept small (no httpx, no header objects); it still reads every byte of every response
and returns the status, so a failure is counted, never hidden. A chunked or length-less
response is refused (the service always sends ``Content-Length``).
"""

from __future__ import annotations

import json
import socket


def build(method: str, path: str, host: str, token: str | None = None, body: dict | None = None) -> bytes:
    """The bytes of one request (keep-alive; JSON body when given)."""
    lines = [f"{method} {path} HTTP/1.1", f"Host: {host}", "Connection: keep-alive"]
    if token:
        lines.append(f"Authorization: Bearer {token}")
    data = b""
    if body is not None:
        data = json.dumps(body).encode()
        lines += ["Content-Type: application/json", f"Content-Length: {len(data)}"]
    return ("\r\n".join(lines) + "\r\n\r\n").encode() + data


class RawClient:
    """One kept-alive connection to ``host:port``."""

    def __init__(self, host: str, port: int, timeout: float = 60.0):
        self.sock = socket.create_connection((host, port), timeout=timeout)
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.buf = b""

    def _fill(self) -> None:
        chunk = self.sock.recv(262144)
        if not chunk:
            raise ConnectionError("server closed the connection")
        self.buf += chunk

    def send(self, request: bytes) -> tuple[int, bytes]:
        """Send one pre-built request; its status and whole body."""
        self.sock.sendall(request)
        while b"\r\n\r\n" not in self.buf:
            self._fill()
        head, _, self.buf = self.buf.partition(b"\r\n\r\n")
        lines = head.split(b"\r\n")
        status = int(lines[0].split(b" ", 2)[1])
        length = None
        for line in lines[1:]:
            name, _, value = line.partition(b":")
            name = name.strip().lower()
            if name == b"content-length":
                length = int(value)
            elif name == b"transfer-encoding":
                raise ValueError("chunked response: this client reads Content-Length bodies only")
        if length is None:
            raise ValueError(f"response {status} without Content-Length")
        while len(self.buf) < length:
            self._fill()
        body, self.buf = self.buf[:length], self.buf[length:]
        return status, body

    def close(self) -> None:
        self.sock.close()
