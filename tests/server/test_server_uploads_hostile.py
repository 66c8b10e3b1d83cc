"""Hostile uploads and parameters against a live ``jointdb serve`` (SQLite and PostgreSQL):
a campaign archive is data, never a path on the server; a bad archive is a 4xx of one line;
no error body names a server path or URL."""

from __future__ import annotations

import base64
import io
import json
import stat
import struct
import tempfile
import warnings
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
CAMPAIGN = ROOT / "fixtures" / "campaigns" / "th-steel-30nm"
CATALOGUE = ROOT / "jointdb" / "data" / "catalogue"

# where the fields of the first member's headers are (local file header, central directory entry)
_FIELDS = {"flags": (6, 8, "<H"), "method": (8, 10, "<H"), "crc": (14, 16, "<I"), "size": (22, 24, "<I")}


def _campaign_files(**substructures) -> dict[str, bytes]:
    """The fixture campaign's files, campaign.json first, with substructure specs replaced."""
    spec = json.loads((CAMPAIGN / "campaign.json").read_text())
    spec["substructures"].update(substructures)
    files = {"campaign.json": json.dumps(spec).encode()}
    files.update({p.name: p.read_bytes() for p in sorted(CAMPAIGN.iterdir()) if p.name != "campaign.json"})
    return files


def _zip(files, method=zipfile.ZIP_STORED) -> bytes:
    buf = io.BytesIO()
    with warnings.catch_warnings(), zipfile.ZipFile(buf, "w", method) as zf:
        warnings.simplefilter("ignore")  # duplicate names on purpose
        for name, data in (files.items() if isinstance(files, dict) else files):
            if isinstance(name, zipfile.ZipInfo):
                name.compress_type = method
            zf.writestr(name, data)
    return buf.getvalue()


def _patch(data: bytes, field: str, value: int) -> bytes:
    """The archive with one header field of its first member changed (in both of its headers)."""
    local, central, fmt = _FIELDS[field]
    out = bytearray(data)
    at = out.index(b"PK\x01\x02")
    struct.pack_into(fmt, out, local, value)
    struct.pack_into(fmt, out, at + central, value)
    return bytes(out)


def _field(data: bytes, field: str) -> int:
    return struct.unpack_from(_FIELDS[field][2], data, _FIELDS[field][0])[0]


def _post(server, data: bytes, name: str = "HOSTILE"):
    body = {"name": name, "filename": "campaign.zip", "file_b64": base64.b64encode(data).decode()}
    with server.client("writer") as c:
        return c.post("/api/v1/catalogue", json=body)


def _clean(server, text: str) -> None:
    """No server path, URL or file content in a response body."""
    for secret in (str(ROOT), tempfile.gettempdir() + "/", "jointdb-upload", str(server.blobs), "postgresql",
                   "sqlite:", server.db):
        assert secret not in text, (secret, text)


def _refused(server, r, *words: str) -> str:
    assert 400 <= r.status_code < 500, (r.status_code, r.text[:300])
    message = r.json()["error"]
    assert "\n" not in message and len(message) <= 300
    _clean(server, r.text)
    for word in words:
        assert word in message, (word, message)
    return message


def test_campaign_naming_an_absolute_server_path_is_refused(server):
    real = str(CAMPAIGN / "holder.uff")  # exists on the server: today it is catalogued from there
    files = _campaign_files(holder={"uff58": real, "dofs": ["3x", "3ry"]})
    del files["holder.uff"]
    m = _refused(server, _post(server, _zip(files)), "absolute path")
    files = _campaign_files(holder={"uff58": "/etc/passwd", "dofs": ["3x", "3ry"]})
    m2 = _refused(server, _post(server, _zip(files)), "absolute path")
    assert m == m2  # nothing tells whether a path exists on the server
    with server.repo() as repo:
        assert "HOSTILE" not in [j.name for j in repo.list_joints()]


def test_campaign_path_climbing_out_of_the_archive_is_refused(server):
    climb = "../" * 12 + str(CAMPAIGN / "holder.uff").lstrip("/")
    files = _campaign_files(holder={"uff58": climb, "dofs": ["3x", "3ry"]})
    del files["holder.uff"]
    _refused(server, _post(server, _zip(files)), "outside the uploaded archive")
    files = _campaign_files(tool={"model": "../../models/test-tool-carbide.json"})
    _refused(server, _post(server, _zip(files)), "outside the uploaded archive")
    # out and back in through the name of the folder the server unpacked into: still outside
    files = _campaign_files(holder={"uff58": "../campaign/holder.uff", "dofs": ["3x", "3ry"]})
    _refused(server, _post(server, _zip(files)), "outside the uploaded archive")


def test_symlink_member_is_refused(server):
    link = zipfile.ZipInfo("holder.uff")
    link.create_system = 3
    link.external_attr = (stat.S_IFLNK | 0o777) << 16
    files = [(k, v) for k, v in _campaign_files().items() if k != "holder.uff"]
    files.append((link, str(CAMPAIGN / "holder.uff").encode()))
    _refused(server, _post(server, _zip(files)), "symbolic link")


def test_member_names_must_stay_inside_the_archive(server):
    for bad in ("../escape.json", "/abs.json", "a\\b.json", "C:/x.json", "a/../../b.json", ".hidden.json"):
        _refused(server, _post(server, _zip({**_campaign_files(), bad: b"{}"})))
    dup = list(_campaign_files().items()) + [("campaign.json", b"{}")]
    _refused(server, _post(server, _zip(dup)), "more than once")
    data = _zip({**_campaign_files(), "xx.uff": b"1"})  # a name that is not UTF-8 (nor flagged as UTF-8)
    data = data.replace(b"xx.uff", b"\xff\xfe.uff")
    _refused(server, _post(server, data), "UTF-8")
    _refused(server, _post(server, _zip({f"f{i}.txt": b"x" for i in range(201)})), "limit")


def test_bad_crc_is_a_422(server):
    data = _zip(_campaign_files())
    _refused(server, _post(server, _patch(data, "crc", _field(data, "crc") ^ 0xFFFF)), "CRC")


def test_encrypted_member_is_a_422(server):
    data = _zip(_campaign_files())
    _refused(server, _post(server, _patch(data, "flags", _field(data, "flags") | 0x1)), "encrypted")


def test_unknown_compression_method_is_a_422(server):
    _refused(server, _post(server, _patch(_zip(_campaign_files()), "method", 99)), "compression method 99")


def test_size_lies_are_a_422(server):
    data = _zip(_campaign_files(), zipfile.ZIP_DEFLATED)
    size = _field(data, "size")
    _refused(server, _post(server, _patch(data, "size", size - 100)))  # understated
    _refused(server, _post(server, _patch(data, "size", size + 100)), "records")  # overstated


def test_zip_bomb_is_refused_while_unpacking(server):
    bomb = {"padding.uff": bytes(48 * 2**20), **_campaign_files()}
    data = _zip(bomb, zipfile.ZIP_DEFLATED)
    assert len(data) < 2**20
    _refused(server, _post(server, data), "expands")
    # the header understates the bomb's size: what is unpacked is counted, not what is declared
    _refused(server, _post(server, _patch(data, "size", 1000)))


def test_bundled_campaign_zipped_with_its_models(server):
    """The bundled campaigns name ../../models/...: zipped with that layout they are catalogued."""
    camp = CATALOGUE / "campaigns" / "th-er32-carbide-080nm"
    spec = json.loads((camp / "campaign.json").read_text())
    models = [s["model"] for s in spec["substructures"].values() if "model" in s]
    flat = {p.name: p.read_bytes() for p in sorted(camp.iterdir())}
    _refused(server, _post(server, _zip(flat, zipfile.ZIP_DEFLATED)), "outside the uploaded archive")
    nested = {f"campaigns/{camp.name}/{k}": v for k, v in flat.items()}
    nested.update({m.replace("../../", ""): (camp / m).read_bytes() for m in models})
    r = _post(server, _zip(nested, zipfile.ZIP_DEFLATED), name="BUNDLED-1")
    assert r.status_code == 201, r.text
    v = r.json()
    assert v["conditions"]["torque_nm"] == 80.0
    # by path relative to the campaign file (inside the archive): the same keys as `jointdb catalogue campaign.json`
    assert {"campaign.json", "assembly.uff", "../../models/test-tool-carbide.json"} <= set(v["provenance"]["input_files"])
    _clean(server, r.text)


def test_nul_in_label_is_a_422_without_the_database_url(server, tmp_path):
    """On PostgreSQL this was a 500 whose body held the database URL."""
    from server_helpers import joint_upload

    with server.client("writer") as c:
        assert c.post("/api/v1/catalogue", json=joint_upload(tmp_path, "NUL-1", k=2.7e6)).status_code == 201
        for path in ("/api/v1/joints", "/api/v1/joints/NUL-1", "/api/v1/audit"):
            r = c.get(path, params={"label": "\x00", "joint": "\x00"})
            assert r.status_code == 422, (path, r.status_code, r.text[:300])
            assert "'label'" in _refused(server, r, "control character") or path == "/api/v1/audit"
        for v in (2**63, 10**20):  # a version beyond the database's integers: 4xx, not 500
            _refused(server, c.get(f"/api/v1/joints/NUL-1/versions/{v}"))
            _refused(server, c.get(f"/api/v1/joints/NUL-1/versions/{v}/frf"))


def test_control_characters_in_parameters_are_a_422(server):
    with server.client("reader") as c:
        for path, params, where in (("/api/v1/joints", {"label": "\x00"}, "'label'"),
                                    ("/api/v1/joints", {"q": "a\x1bb"}, "'q'"),
                                    ("/api/v1/joints/a%00b", None, "'name'"),
                                    ("/api/v1/joints/TH/versions/1/frf", {"format": "json\x00"}, "'format'")):
            r = c.get(path, params=params)
            assert r.status_code == 422, (path, r.status_code, r.text)
            assert where in _refused(server, r, "control character")


def test_corrupt_blob_error_has_no_server_path(server, tmp_path):
    from server_helpers import joint_upload

    with server.client("writer") as c:
        r = c.post("/api/v1/catalogue", json=joint_upload(tmp_path, "CORRUPT-1", k=3.3e6))
        assert r.status_code == 201, r.text
    with server.repo() as repo:
        digest = repo.get("CORRUPT-1").blob_sha256
    path = Path(server.blobs) / digest[:2] / f"{digest}.h5"
    raw = bytearray(path.read_bytes())
    for k in range(len(raw) // 2, len(raw) // 2 + 64):
        raw[k] ^= 0x5A
    path.write_bytes(bytes(raw))
    with server.client("reader") as c:
        for fmt in ("json", "hdf5"):
            r = c.get("/api/v1/joints/CORRUPT-1/versions/1/frf", params={"format": fmt})
            assert r.status_code >= 400, r.status_code
            assert "\n" not in r.json()["error"]
            _clean(server, r.text)
        path.unlink()  # a missing blob: 404 or 5xx, never where it was expected
        r = c.get("/api/v1/joints/CORRUPT-1/versions/1/frf", params={"format": "json"})
        assert r.status_code >= 400 and "\n" not in r.json()["error"]
        _clean(server, r.text)


def test_hdf5_upload_cannot_make_the_server_read_its_files(server, tmp_path):
    """An identified joint file whose values live in a server file (external storage), or that
    links to one (external link, virtual dataset), is refused: today the file's bytes are
    catalogued as the FRF and anyone can download them."""
    import h5py
    import numpy as np
    from server_helpers import joint_upload

    body = joint_upload(tmp_path, "H5-EVIL")
    src = tmp_path / "ok.h5"
    src.write_bytes(base64.b64decode(body["file_b64"]))
    secret = tmp_path / "server-secret.bin"  # a file on the server
    secret.write_bytes(np.arange(2**12, dtype="<f8").tobytes())

    def variant(kind: str) -> bytes:
        out = tmp_path / f"{kind}.h5"
        with h5py.File(src) as f, h5py.File(out, "w") as g:
            for k, v in f.attrs.items():
                g.attrs[k] = v
            for n in f:
                if n != "values" or kind == "link":
                    f.copy(n, g)
            shape = f["values"].shape
            if kind == "external":
                g.create_dataset("values", shape=shape, dtype="<f8", external=[(str(secret), 0, h5py.h5f.UNLIMITED)])
            elif kind == "virtual":
                layout = h5py.VirtualLayout(shape=shape, dtype="<f8")
                layout[...] = h5py.VirtualSource(str(src), "values", shape=shape)
                g.create_virtual_dataset("values", layout)
            else:
                g["extra"] = h5py.ExternalLink(str(src), "/values")
        return out.read_bytes()

    with server.client("writer") as c:
        for kind in ("external", "virtual", "link"):
            r = c.post("/api/v1/catalogue", json={**body, "file_b64": base64.b64encode(variant(kind)).decode()})
            _refused(server, r, "another file")
        assert c.get("/api/v1/joints/H5-EVIL").status_code == 404
