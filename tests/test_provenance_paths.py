"""One catalogue path: the CLI (``jointdb catalogue campaign.json``), the HTTP API
(``POST /api/v1/catalogue`` with the campaign zipped with its layout) and the demo's use case
(:func:`jointdb.usecases.catalogue_campaign`) record byte-identical provenance for the same
campaign — method, parameters, input files (SHA-256 by path relative to the campaign file)
and software version."""

from __future__ import annotations

import base64
import io
import json
import zipfile
from pathlib import Path

import pytest
from typer.testing import CliRunner

from jointdb.store import Repository, file_sha256, upgrade

CATALOGUE = Path(__file__).resolve().parents[1] / "jointdb" / "data" / "catalogue"
CAMPAIGN = CATALOGUE / "campaigns" / "th-er32-carbide-080nm" / "campaign.json"
FIELDS = ("method", "parameters", "input_files", "software_version")


def _provenance(url: str, blobs: Path, name: str) -> bytes:
    """The stored provenance of ``name``'s latest version, as canonical JSON bytes (author aside)."""
    with Repository(url, blobs=blobs, auto_create=False) as repo:
        prov = repo.get(name).provenance
    return json.dumps({f: getattr(prov, f) for f in FIELDS}, sort_keys=True, ensure_ascii=True).encode()


def _database(tmp_path: Path, which: str) -> tuple[str, Path]:
    url = f"sqlite:///{tmp_path / f'{which}.sqlite'}"
    upgrade(url)
    return url, tmp_path / f"{which}-blobs"


def _by_cli(tmp_path: Path) -> bytes:
    from jointdb.cli import app

    url, blobs = _database(tmp_path, "cli")
    r = CliRunner().invoke(app, ["catalogue", str(CAMPAIGN), "--name", "th-080", "--db", url, "--blobs", str(blobs),
                                 "--json"])
    assert r.exit_code == 0, (r.output, r.exception)
    return _provenance(url, blobs, "th-080")


def _archive() -> bytes:
    """The campaign zipped with its layout (docs/service.md, "Campaign archives")."""
    spec = json.loads(CAMPAIGN.read_text(encoding="utf-8"))
    members = {f"campaigns/{CAMPAIGN.parent.name}/{p.name}": p for p in sorted(CAMPAIGN.parent.iterdir())}
    for sub in spec["substructures"].values():
        if "model" in sub:
            members[sub["model"].replace("../../", "")] = (CAMPAIGN.parent / sub["model"]).resolve()
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as zf:
        for arcname, path in members.items():
            zf.write(path, arcname)
    return buf.getvalue()


def _by_api(tmp_path: Path) -> bytes:
    pytest.importorskip("fastapi")
    pytest.importorskip("httpx")
    from fastapi.testclient import TestClient

    from jointdb.server import create_app
    from jointdb.server import Settings
    from jointdb.store._tokens import create_token

    url, blobs = _database(tmp_path, "api")
    with Repository(url, blobs=blobs, auto_create=False) as repo:
        token, _ = create_token(repo, "writer-owner", "writer")
        body = {"name": "th-080", "filename": "th-080.zip", "file_b64": base64.b64encode(_archive()).decode()}
        with TestClient(create_app(Settings(bind_host="127.0.0.1"), repo=repo)) as c:
            r = c.post("/api/v1/catalogue", json=body, headers={"Authorization": f"Bearer {token}"})
    assert r.status_code == 201, r.text
    return _provenance(url, blobs, "th-080")


def _by_demo(tmp_path: Path) -> bytes:
    from jointdb.usecases import catalogue_campaign

    url, blobs = _database(tmp_path, "demo")
    with Repository(url, blobs=blobs, auto_create=False) as repo:
        outcome = catalogue_campaign(repo, CAMPAIGN)
    assert not outcome.reused
    return _provenance(url, blobs, outcome.version.name)


def test_cli_api_and_demo_record_byte_identical_provenance(tmp_path):
    cli, api, demo = _by_cli(tmp_path), _by_api(tmp_path), _by_demo(tmp_path)
    assert cli == demo, (cli, demo)
    assert api == demo, (api, demo)
    files = json.loads(demo)["input_files"]
    # every file the campaign names, by its path relative to the campaign file; nothing else
    want = {"campaign.json": CAMPAIGN, "assembly.uff": CAMPAIGN.parent / "assembly.uff",
            "../../models/holder-on-spindle-carbide-shank.json":
                CATALOGUE / "models" / "holder-on-spindle-carbide-shank.json",
            "../../models/test-tool-carbide.json": CATALOGUE / "models" / "test-tool-carbide.json"}
    assert files == {k: file_sha256(p) for k, p in want.items()}
