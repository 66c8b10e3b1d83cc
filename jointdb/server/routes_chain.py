"""The history chain's signed checkpoints (``jointdb serve --checkpoint-key KEY``).

With a key, every worker signs a checkpoint (tree size, head, time; :mod:`jointdb.store._chain`)
of the history when it has grown, at most every ``--checkpoint-interval`` seconds: a
background thread after writes, and ``GET /api/v1/checkpoint`` when the latest is older.
Before signing, the chain is recomputed from the rows and must extend the worker's previous
checkpoint, so a rewritten history is never signed (503 instead). Clients keep the
checkpoints they fetch and verify them later with ``jointdb db check --checkpoint FILE
--trust KEY.pub``.
"""

from __future__ import annotations

import logging
import os
import threading
import time
from typing import Any

from fastapi import APIRouter, Depends, FastAPI, HTTPException

from jointdb.errors import IntegrityError, JointdbError
from jointdb.server._deps import reader, repo

router = APIRouter(tags=["history"])
log = logging.getLogger("jointdb.server")
_lock = threading.Lock()
_state: dict[str, Any] = {"checkpoint": None, "at": 0.0, "key": None}


def _settings() -> tuple[str | None, float]:
    return os.environ.get("JOINTDB_CHECKPOINT_KEY") or None, float(os.environ.get("JOINTDB_CHECKPOINT_INTERVAL_S", "60"))


def _refresh(r, force: bool = False) -> dict | None:
    """The latest checkpoint, signing a new one when the chain grew and the interval has passed."""
    from jointdb.store._chain import chain_head, signed_checkpoint
    from jointdb.store._maintenance import snapshot
    from jointdb.store._signing import load_private_key

    key_path, interval = _settings()
    if key_path is None:
        return None
    with _lock:
        cp = _state["checkpoint"]
        if cp is not None and not force and time.monotonic() - _state["at"] < interval:
            return cp
        if _state["key"] is None:
            _state["key"] = load_private_key(key_path)
        with snapshot(r) as s:
            conn = s.connection()
            if cp is None or chain_head(conn)[0] != cp["tree_size"]:
                cp = signed_checkpoint(conn, _state["key"], since=cp)
        _state.update(checkpoint=cp, at=time.monotonic())
        return cp


@router.get("/checkpoint", summary="The latest signed checkpoint of the history chain")
def checkpoint(r=Depends(repo), who=reader) -> dict[str, Any]:
    """Tree size, head hash and time, signed with the service's Ed25519 key (``public_key``,
    ``key_fingerprint``); verify with ``jointdb db check --checkpoint FILE --trust KEY.pub``."""
    try:
        cp = _refresh(r)
    except IntegrityError:
        log.error('{"event": "checkpoint-refused", "reason": "history chain does not verify"}')
        raise HTTPException(503, "the history chain does not verify; nothing signed (run jointdb db check)") from None
    if cp is None:
        raise HTTPException(404, "this service signs no checkpoints (start it with jointdb serve --checkpoint-key KEY)")
    return cp


def _signer(app: FastAPI, interval: float) -> None:  # pragma: no cover - timing; the route is tested
    while True:
        time.sleep(interval)
        r = getattr(app.state, "repo", None)
        if r is None:
            continue
        try:
            _refresh(r, force=True)
        except (JointdbError, OSError) as exc:
            log.warning('{"event": "checkpoint-failed", "error": "%s"}', type(exc).__name__)
        except Exception:  # noqa: BLE001 - a background thread must not die silently on a database hiccup
            log.warning('{"event": "checkpoint-failed", "error": "unexpected"}')


def install(app: FastAPI) -> None:
    """Add the route; with a checkpoint key, start the worker's background signer."""
    app.include_router(router, prefix="/api/v1")
    key_path, interval = _settings()
    if key_path is not None:
        threading.Thread(target=_signer, args=(app, interval), name="jointdb-checkpoints", daemon=True).start()
