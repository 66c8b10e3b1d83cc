"""The HTTP protocol ``jointdb serve`` runs uvicorn with: uvicorn's own, with ``TCP_NODELAY``
set on every accepted connection.

With ``--workers N > 1`` uvicorn binds the listening socket itself (``proto`` 0), and
asyncio then leaves Nagle's algorithm on for the accepted connections (it sets
``TCP_NODELAY`` only for sockets whose ``proto`` is ``IPPROTO_TCP``). A response written
in two parts on a kept-alive connection then waits for the client's delayed ACK: about
40 ms per request (measured: ``/healthz`` p50 0.7 ms with one worker, 44 ms with two).
Setting the option per connection removes the penalty whatever the worker count
(``bench/bench_keepalive.py`` measures it).
"""

from __future__ import annotations

import asyncio
import socket

from uvicorn.protocols.http.auto import AutoHTTPProtocol

#: What ``uvicorn.run(http=...)`` is given (an import string: each worker process imports it).
PROTOCOL = "jointdb.server._protocol:NoDelayHTTPProtocol"


def set_nodelay(transport: asyncio.BaseTransport) -> None:
    """Turn Nagle's algorithm off on a TCP transport's socket (nothing for other sockets)."""
    sock = transport.get_extra_info("socket")
    if sock is None or sock.family not in (socket.AF_INET, socket.AF_INET6):
        return
    try:
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    except OSError:  # a socket that is already closing: nothing to speed up
        pass


class NoDelayHTTPProtocol(AutoHTTPProtocol):  # type: ignore[misc, valid-type]
    """uvicorn's HTTP/1.1 protocol with ``TCP_NODELAY`` on each connection."""

    def connection_made(self, transport):  # type: ignore[override]
        set_nodelay(transport)
        super().connection_made(transport)
