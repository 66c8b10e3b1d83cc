"""The web pages under ``/ui`` do not block the event loop (issue 23): they call the
synchronous repository, so they run in the thread pool, and another request is
answered while one page waits for a slow database."""

from __future__ import annotations

import asyncio
import threading

import httpx

from jointdb.errors import NotFoundError


class _SlowRepo:
    """A repository whose ``get`` waits (up to ``hold`` seconds) until released."""

    url = "sqlite:///slow"

    def __init__(self, hold: float) -> None:
        self.hold, self.entered, self.release = hold, threading.Event(), threading.Event()
        self.returned = False

    def get(self, name, version=None):
        self.entered.set()
        self.release.wait(self.hold)
        self.returned = True
        raise NotFoundError(f"joint {name!r} not found")


async def _while_a_page_waits(repo: _SlowRepo) -> tuple[bool, int, int]:
    from jointdb.server import create_app
    from jointdb.server import Settings

    app = create_app(Settings(bind_host="127.0.0.1", open_reads=True), repo=repo)
    transport = httpx.ASGITransport(app=app)
    async with httpx.AsyncClient(transport=transport, base_url="http://127.0.0.1") as client:
        page = asyncio.create_task(client.get("/ui/joints/slow-joint"))
        for _ in range(200):  # until the page is inside the repository (or the loop was blocked)
            if repo.entered.is_set():
                break
            await asyncio.sleep(0.01)
        other = await client.get("/healthz")
        answered_while_waiting = not repo.returned
        repo.release.set()
        return answered_while_waiting, other.status_code, (await page).status_code


def test_a_slow_page_does_not_hold_up_other_requests():
    repo = _SlowRepo(hold=3.0)
    answered_while_waiting, other, page = asyncio.run(_while_a_page_waits(repo))
    assert repo.entered.is_set()
    assert answered_while_waiting, "GET /healthz waited for a /ui page's database call: the page blocks the event loop"
    assert other == 200
    assert page == 404  # the page's error is still rendered as a page
