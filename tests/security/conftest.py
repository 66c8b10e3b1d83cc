"""A live ``jointdb serve`` to attack, on SQLite and (with ``JOINTDB_TEST_PG_URL``) PostgreSQL.

The server, its tokens and the PostgreSQL schema come from the server tests' helpers
(tests/server/server_helpers.py, imported by putting that directory on ``sys.path``). Two
writers each catalogue a joint, so that ownership can be attacked; the target records every
secret the attacks must never see (tokens, server directories, database URL).
"""

from __future__ import annotations

import base64
import io as bytesio
import sys
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import pytest

pytest.importorskip("fastapi", reason="the server extra (fastapi, uvicorn, httpx) is not installed")
pytest.importorskip("httpx", reason="the server extra (httpx) is not installed")

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests" / "server"))

from server_helpers import (_pg_schema, drop_pg_schema, joint_upload, make_tokens,  # noqa: E402
                            pg_base_url, start_server, stop_server)

CAMPAIGN = ROOT / "fixtures" / "campaigns" / "th-steel-30nm"


@dataclass
class Target:
    """The server under attack and what it must keep to itself."""

    url: str
    db: str
    log: Path
    tokens: dict[str, str]
    secrets: dict[str, str]  # what -> text that must never reach a client or a log line
    joints: dict[str, str]  # owner role -> a joint that owner catalogued
    frf: dict  # a valid FRF as JSON (the download format)
    h5: bytes  # a valid identified joint file
    campaign: dict[str, bytes] = field(default_factory=dict)  # the files of a valid campaign
    campaign_dir: Path = CAMPAIGN
    server_h5: Path | None = None  # an HDF5 file of the server's (a blob)
    backend: str = "sqlite"


def _secrets(db: str, tmp: Path, blobs: Path, schema: str | None, tokens: dict[str, str]) -> dict[str, str]:
    import jointdb

    out = {"server tmp directory": str(tmp), "blob directory": str(blobs),
           "package directory": str(Path(jointdb.__file__).resolve().parent),
           "python prefix": sys.prefix, "upload temporary directory": "jointdb-upload-",
           "repository directory": str(ROOT), "database URL": db.split("?")[0]}
    if db.startswith("sqlite"):
        out["database file"] = db.split("///", 1)[1]
    else:
        out["database host"] = db.split("@", 1)[1].split("/", 1)[0]
        out["database schema"] = schema
        out["search_path"] = "search_path"
    for role, tok in tokens.items():
        out[f"{role} token"] = tok
        secret = tok.split("_", 2)[-1]  # jdb_<12 hex id>_<secret>; the secret may itself hold '_'
        if len(secret) >= 16:
            out[f"{role} token secret"] = secret
    return out


def _seed(srv, tokens: dict[str, str], tmp: Path) -> tuple[dict[str, str], dict, bytes]:
    joints = {}
    body = joint_upload(tmp, "SEC-A")
    for role, name in (("writer", "SEC-A"), ("writer2", "SEC-B")):
        with srv.client(token=tokens[role]) as c:
            for torque in (40.0, 41.0):
                r = c.post("/api/v1/catalogue", json={**body, "name": name, "conditions": {"torque_nm": torque},
                                                      "force": True})
                assert r.status_code == 201, r.text
        joints[role] = name
    with srv.client(token=tokens["reader"]) as c:
        frf = c.get("/api/v1/joints/SEC-A/versions/1/frf", params={"format": "json"})
        assert frf.status_code == 200, frf.text
    fields = ("freq_hz", "outputs", "inputs", "real", "imag", "quantity", "units")  # the API's FRF input
    return joints, {k: v for k, v in frf.json().items() if k in fields}, base64.b64decode(body["file_b64"])


@pytest.fixture(scope="module", params=["sqlite", pytest.param("postgresql", marks=pytest.mark.postgres)])
def target(request, tmp_path_factory):
    """A migrated database, tokens per role (and a second writer), two joints, a running server."""
    from jointdb.store import Repository, upgrade
    from jointdb.store._tokens import create_token

    tmp = tmp_path_factory.mktemp(f"security-{request.param}")
    cleanup, schema = None, None
    if request.param == "sqlite":
        db = f"sqlite:///{tmp / 'j.sqlite'}"
    else:
        engine, schema, db = _pg_schema(pg_base_url())
        cleanup = (engine, schema)
    srv = None
    try:
        upgrade(db)
        blobs = tmp / "blobs"
        tokens = make_tokens(db, blobs)
        with Repository(db, blobs=blobs, auto_create=False) as repo:
            tokens["writer2"] = create_token(repo, "writer2-owner", "writer")[0]
        srv = start_server(db, blobs, tmp / "server.log")
        joints, frf, h5 = _seed(srv, tokens, tmp)
        yield Target(srv.url, db, srv.log, tokens, _secrets(db, tmp, blobs, schema, tokens), joints, frf, h5,
                     {p.name: p.read_bytes() for p in sorted(CAMPAIGN.iterdir())}, backend=request.param,
                     server_h5=next((p for p in sorted(blobs.rglob("*")) if p.is_file()), None))
    finally:
        if srv is not None:
            stop_server(srv)
        if cleanup:
            drop_pg_schema(*cleanup)
            cleanup[0].dispose()


def campaign_zip(files: dict[str, bytes]) -> bytes:
    """A flat zip of ``files`` (name -> content)."""
    buf = bytesio.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as zf:
        for name, data in files.items():
            zf.writestr(name, data)
    return buf.getvalue()
