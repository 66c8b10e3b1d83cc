"""TCP_NODELAY on every accepted connection (issue 26, item 4): with several uvicorn
workers the listening socket is uvicorn's own (proto 0) and asyncio leaves Nagle on;
:class:`jointdb.server._protocol.NoDelayHTTPProtocol` sets it per connection, and
``jointdb serve`` runs uvicorn with it. The latency effect is measured in
``bench/bench_keepalive.py``."""

from __future__ import annotations

import socket
import sys
from pathlib import Path

import httpx

from jointdb.server._protocol import NoDelayHTTPProtocol, set_nodelay

sys.path.insert(0, str(Path(__file__).resolve().parent))
from server_helpers import start_server, stop_server  # noqa: E402


class _Transport:
    def __init__(self, sock):
        self.sock = sock

    def get_extra_info(self, key, default=None):
        return self.sock if key == "socket" else default


def _accepted_pair():
    """A listening socket made as uvicorn makes it for several workers (proto 0) and one accepted connection."""
    listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    listener.bind(("127.0.0.1", 0))
    listener.listen(1)
    client = socket.create_connection(listener.getsockname())
    accepted, _ = listener.accept()
    return listener, client, accepted


def test_set_nodelay_turns_nagle_off_on_an_accepted_connection():
    listener, client, accepted = _accepted_pair()
    try:
        assert accepted.proto == 0  # the case asyncio does not cover
        assert accepted.getsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY) == 0
        set_nodelay(_Transport(accepted))
        assert accepted.getsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY) != 0
    finally:
        for s in (client, accepted, listener):
            s.close()


def test_set_nodelay_ignores_non_tcp_sockets():
    a, b = socket.socketpair()  # AF_UNIX: no TCP option to set, and no error
    try:
        set_nodelay(_Transport(a))
        set_nodelay(_Transport(None))
    finally:
        a.close()
        b.close()


def test_protocol_is_uvicorns_http_protocol():
    from uvicorn.protocols.http.auto import AutoHTTPProtocol

    assert issubclass(NoDelayHTTPProtocol, AutoHTTPProtocol)


def test_two_worker_server_answers_on_a_kept_alive_connection(tmp_path):
    """``jointdb serve --workers 2`` starts with the protocol and serves repeated keep-alive requests."""
    from jointdb.store import upgrade

    db = f"sqlite:///{tmp_path / 'j.sqlite'}"
    upgrade(db)
    server = start_server(db, tmp_path / "blobs", tmp_path / "log", "--open-reads", workers=2)
    try:
        with httpx.Client(base_url=server.url, timeout=10) as client:
            answers = [client.get("/healthz").status_code for _ in range(20)]
        assert answers == [200] * 20
    finally:
        assert stop_server(server) == 0
