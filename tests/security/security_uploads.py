"""Hostile uploads: campaign archives (.zip) whose members or campaign JSON point outside the
archive, malformed and lying archives, bombs; hostile base64, file names and HDF5 files.

Every archive is built from the valid fixture campaign (fixtures/campaigns/th-steel-30nm), so
that the one defect under test is the only thing wrong with it."""

from __future__ import annotations

import base64
import functools
import io as bytesio
import json
import struct
import zipfile
import zlib

from security_run import JSON, Attack, json_body

API = "/api/v1"


def _zip(members: list[tuple[str | zipfile.ZipInfo, bytes]], method=zipfile.ZIP_DEFLATED) -> bytes:
    buf = bytesio.BytesIO()
    with zipfile.ZipFile(buf, "w", method) as zf:
        for name, data in members:
            zf.writestr(name, data)
    return buf.getvalue()


def _patch(data: bytes, member: str, local: dict[int, bytes], central: dict[int, bytes]) -> bytes:
    """Overwrite bytes at offsets of ``member``'s local header and central directory entry."""
    out = bytearray(data)
    name = member.encode()
    for sig, fields, name_at in ((b"PK\x03\x04", local, 30), (b"PK\x01\x02", central, 46)):
        at = 0
        while (at := out.find(sig, at)) >= 0:
            n = struct.unpack_from("<H", out, at + (26 if sig == b"PK\x03\x04" else 28))[0]
            if bytes(out[at + name_at:at + name_at + n]) == name:
                for off, value in fields.items():
                    out[at + off:at + off + len(value)] = value
            at += 4
    return bytes(out)


def _upload(name: str, data: bytes, filename: str = "campaign.zip", echo: str = "", cls: str = "archives",
            expect: str = "4xx") -> Attack:
    body = {"name": f"ZIP-{zlib.crc32((name + filename).encode())}", "filename": filename,
            "file_b64": base64.b64encode(data).decode()}
    return Attack(cls, name, "POST", f"{API}/catalogue", "writer", JSON, json_body(body), expect=expect, echo=echo)


def _campaign_with(target, where: str, value) -> tuple[dict[str, bytes], str]:
    files = dict(target.campaign)
    c = json.loads(files["campaign.json"])
    obj = c
    keys = where.split(".")
    for k in keys[:-1]:
        obj = obj[int(k)] if isinstance(obj, list) else obj[k]
    last = keys[-1]
    if isinstance(obj, list):
        obj[int(last)] = value
    else:
        obj[last] = value
    files["campaign.json"] = json.dumps(c).encode()
    return files, files["campaign.json"].decode()


CAMPAIGN_FIELDS = ("substructures.holder.uff58", "substructures.tool.model", "measurements.0",
                   "validation.measurements.0", "validation.substructures.tool.model")


def campaign_paths(target) -> list[Attack]:
    """Campaign JSON naming files outside the archive (absolute, ``..``, the server's own fixtures)."""
    d = target.campaign_dir
    own = {"substructures.holder.uff58": d / "holder.uff", "substructures.tool.model": d / "tool.json",
           "measurements.0": d / "assembly.uff", "validation.measurements.0": d / "validation.uff",
           "validation.substructures.tool.model": d / "tool_short.json"}
    paths = ["/etc/passwd", "/proc/self/environ", "../../../../../../etc/passwd", "../campaign/holder.uff",
             "subdir/holder.uff", "\\etc\\passwd", "file:///etc/passwd", "~/.bashrc", "holder.uff\x00.json", "",
             str(d / "truth.json")]
    out = []
    for where in CAMPAIGN_FIELDS:  # the validation files are read last: only the server's own files there
        for p in [*(paths if not where.startswith("validation") else paths[:1]), str(own[where])]:
            files, text = _campaign_with(target, where, p)
            out.append(_upload(f"campaign {where} = {p[:40]}", _zip(list(files.items())), echo=text,
                               cls="campaign paths"))
    return out


def existence_oracle(target) -> list[tuple[Attack, Attack, str, str]]:
    """Pairs of uploads that differ only in naming an existing or a missing server file: the
    answers must not tell them apart."""
    d = target.campaign_dir
    pairs = [("/etc/hostname", "/etc/hostname-missing-7f3a"), ("/etc/passwd", "/etc/no-such-file"),
             (str(d / "truth.json"), str(d / "truth-missing.json")), ("/root", "/no-such-dir"),
             ("../../../../../../etc/passwd", "../../../../../../etc/no-such-file")]
    out = []
    for where in ("substructures.tool.model", "substructures.holder.uff58"):
        for yes, no in pairs:
            fa, ta = _campaign_with(target, where, yes)
            fb, tb = _campaign_with(target, where, no)
            out.append((_upload(f"oracle {where} = {yes}", _zip(list(fa.items())), echo=ta, cls="existence oracle"),
                        _upload(f"oracle {where} = {no}", _zip(list(fb.items())), echo=tb, cls="existence oracle"),
                        yes, no))
    return out


def _symlink(name: str, target_path: str) -> zipfile.ZipInfo:
    info = zipfile.ZipInfo(name)
    info.create_system = 3
    info.external_attr = (0o120777 << 16)
    return info


def archives(target) -> list[Attack]:
    files = target.campaign
    valid = list(files.items())
    echo = " ".join(files) + " " + files["campaign.json"].decode()
    out = []
    for bad in ("/etc/cron.d/x", "../x.json", "..\\x.json", "a/../../x.json", "C:\\x.json", "x\x00.json",
                ".", "..", ".hidden", "dir/", "a/b.json", "n" * 300, "/campaign.json", "campaign.json/",
                "\u00f8.json", "x\r\n.json", "../holder.uff\x00"):
        placeholder = "Q" * len(bad.encode())  # zipfile itself cuts a name at NUL: write it byte by byte
        data = _zip(valid + [(placeholder, b"{}")]).replace(placeholder.encode(), bad.encode())
        # a directory entry, a unicode name, a member in a folder (campaigns may keep their layout)
        harmless = bad in ("dir/", "campaign.json/", "\u00f8.json", "a/b.json")
        out.append(_upload(f"member named {bad[:30]!r}", data, echo=echo + bad, expect="ok" if harmless else "4xx"))
    # the campaign itself under a path-like name
    out.append(_upload("campaign member ../campaign.json", _zip([("../campaign.json", files["campaign.json"])]
                                                                + valid[1:]), echo=echo))
    for name, link in (("holder.uff", "/etc/passwd"), ("tool.json", "../../../../etc/hostname"),
                       ("campaign.json", str(target.campaign_dir / "campaign.json")), ("extra.txt", "/")):
        members = [(m, d) for m, d in valid if m != name] + [(_symlink(name, link), link.encode())]
        out.append(_upload(f"symlink member {name} -> {link[:30]}", _zip(members), echo=echo + link))
    z = _zip(valid, zipfile.ZIP_STORED)
    info = {i.filename: i for i in zipfile.ZipFile(bytesio.BytesIO(z)).infolist()}
    for m in ("campaign.json", "holder.uff"):
        crc = struct.pack("<I", info[m].CRC ^ 0xFFFFFFFF)
        out.append(_upload(f"bad CRC in {m}", _patch(z, m, {14: crc}, {16: crc}), echo=echo))
        out.append(_upload(f"encrypted flag on {m}", _patch(z, m, {6: b"\x01\x00"}, {8: b"\x01\x00"}), echo=echo))
        for method in (99, 1, 6, 97):
            meth = struct.pack("<H", method)
            out.append(_upload(f"compression method {method} on {m}", _patch(z, m, {8: meth}, {10: meth}), echo=echo))
        size = info[m].file_size
        for what, n in (("understated", size // 2), ("overstated", size * 2), ("zero", 0), ("huge", 2**32 - 1)):
            packed = struct.pack("<I", n)
            out.append(_upload(f"{what} size of {m}", _patch(z, m, {18: packed, 22: packed}, {20: packed, 24: packed}),
                               echo=echo))
    out += _bombs_and_oddities(target, valid, echo)
    return out


def _bombs_and_oddities(target, valid, echo) -> list[Attack]:
    out = []
    big, comp, crc = _bomb()
    bomb = _raw_deflated_member("bomb.uff", comp, big, crc)
    out.append(_upload("zip bomb: 100 MiB of zeros in 100 KiB", _zip_with_raw(valid, [bomb]), echo=echo))
    lie = _raw_deflated_member("bomb.uff", comp, 1000, crc)
    out.append(_upload("zip bomb with understated size", _zip_with_raw(valid, [lie]), echo=echo))
    out.append(_upload("5000 members", _zip(valid + [(f"f{i}.txt", b"") for i in range(5000)]), echo=echo))
    out.append(_upload("201 members", _zip(valid + [(f"f{i}.txt", b"") for i in range(201 - len(valid))]), echo=echo))
    out.append(_upload("duplicate campaign.json (second names /etc/passwd)", _zip(valid + [(
        "campaign.json", files_with(target, "substructures.holder.uff58", "/etc/passwd"))]), echo=echo + "/etc/passwd"))
    out.append(_upload("duplicate holder.uff", _zip(valid + [("holder.uff", b"garbage")]), echo=echo, expect="ok"))
    cp437 = zipfile.ZipInfo("x.json")
    raw_name = _zip(valid + [(cp437, b"{}")]).replace(b"x.json", b"\x81\xffjson")
    out.append(_upload("non-UTF-8 member name", raw_name, echo=echo, expect="ok"))
    z = _zip(valid)
    out.append(_upload("huge comment", z[:-2] + struct.pack("<H", 65535) + b"c" * 65535, echo=echo, expect="ok"))
    for what, data in {"not a zip": b"this is not a zip", "empty": b"", "PK header only": b"PK\x03\x04",
                       "truncated": z[:-30], "first half": z[: len(z) // 2], "gzip": zlib.compress(z),
                       "HDF5 named .zip": target.h5, "zip in a zip": _zip([("inner.zip", z)]),
                       "end record only": b"PK\x05\x06" + b"\0" * 18}.items():
        out.append(_upload(what, data, echo=echo))
    for fname in ("../../x.zip", "/etc/x.zip", "x.zip\x00.h5", "x" * 300 + ".zip", ".zip", "x.zip/", "x.exe",
                  "x.h5.zip.sh"):
        out.append(_upload(f"filename {fname[:30]!r}", z, fname, echo=echo + fname, cls="file names and encodings"))
    for fname in ("x.ZIP", "con.zip"):
        out.append(_upload(f"filename {fname}", z, fname, echo=echo, cls="file names and encodings", expect="ok"))
    for what, b64 in {"not base64": "@@@@", "urlsafe alphabet": base64.urlsafe_b64encode(b"\xfb\xff" * 30).decode(),
                      "missing padding": base64.b64encode(target.h5).decode().rstrip("="),
                      "data URI": "data:application/zip;base64," + base64.b64encode(z).decode(),
                      "newlines": base64.encodebytes(target.h5).decode(), "NUL": "AA\x00A"}.items():
        body = {"name": "B64", "filename": "joint.h5", "file_b64": b64}
        out.append(Attack("file names and encodings", f"file_b64 {what}", "POST", f"{API}/catalogue", "writer", JSON,
                          json_body(body), expect="ok" if what == "newlines" else "4xx"))
    out += _hdf5(target)
    return out


def files_with(target, where: str, value) -> bytes:
    return _campaign_with(target, where, value)[0]["campaign.json"]


@functools.lru_cache(maxsize=1)
def _bomb() -> tuple[int, bytes, int]:
    """100 MiB of zeros, deflated to about 100 KiB (a ratio of about 1000), and their CRC (made once)."""
    big, chunk = 100 * 2**20, b"\0" * 2**20
    zeros, crc, parts = zlib.compressobj(9, zlib.DEFLATED, -15), 0, []
    for _ in range(big // 2**20):
        parts.append(zeros.compress(chunk))
        crc = zlib.crc32(chunk, crc)
    return big, b"".join(parts) + zeros.flush(), crc


def _raw_deflated_member(name: str, comp: bytes, size: int, crc: int) -> tuple[bytes, bytes, bytes]:
    n = name.encode()
    local = struct.pack("<4sHHHHHIIIHH", b"PK\x03\x04", 20, 0, 8, 0, 0, crc, len(comp), size, len(n), 0) + n
    central = lambda off: struct.pack("<4sHHHHHHIIIHHHHHII", b"PK\x01\x02", 20, 20, 0, 8, 0, 0, crc, len(comp),  # noqa: E731
                                      size, len(n), 0, 0, 0, 0, 0, off) + n
    return local, comp, central


def _zip_with_raw(valid, raw_members) -> bytes:
    """A zip of the valid members plus members written byte by byte (sizes and CRC as given)."""
    base = _zip(valid)
    end = base.rfind(b"PK\x05\x06")
    cd_size, cd_off = struct.unpack_from("<II", base, end + 12)
    count = struct.unpack_from("<H", base, end + 10)[0]
    body, central = bytearray(base[:cd_off]), bytearray(base[cd_off:cd_off + cd_size])
    for local, comp, cent in raw_members:
        off = len(body)
        body += local + comp
        central += cent(off)
        count += 1
    end_rec = struct.pack("<4sHHHHIIH", b"PK\x05\x06", 0, 0, count, count, len(central), len(body), 0)
    return bytes(body + central + end_rec)


def _hdf5(target) -> list[Attack]:
    """Identified joint files (.h5) that point outside themselves or lie about their sizes."""
    import tempfile
    from pathlib import Path

    import h5py
    import numpy as np

    out = []
    with tempfile.TemporaryDirectory() as tmp:
        def variant(what: str, edit) -> None:
            p = Path(tmp) / f"{len(out)}.h5"
            p.write_bytes(target.h5)
            with h5py.File(p, "r+") as f:
                edit(f)
            out.append(_h5_upload(what, p.read_bytes()))

        server_h5 = target.server_h5 or "/etc/passwd"

        def external(f):
            del f["values"]
            f["values"] = h5py.ExternalLink(str(server_h5), "/values")

        def soft(f):
            del f["values"]
            f["values"] = h5py.SoftLink("/freq")

        def big_chunked(f):
            del f["values"]
            f.create_dataset("values", shape=(2**20, 2, 2, 2), dtype="f8", chunks=(2**14, 2, 2, 2),
                             compression="gzip", fillvalue=0.0)

        def nan(f):
            v = f["values"][...]
            v[0] = np.nan
            f["values"][...] = v

        def metadata_deep(f):
            f.attrs["metadata"] = '{"a":' * 2000 + "1" + "}" * 2000

        variant("HDF5 external link to a server file", external)
        variant("HDF5 soft link in place of the data", soft)
        variant("HDF5 64 MiB of zeros compressed (a bomb)", big_chunked)
        variant("HDF5 NaN in the FRF", nan)
        variant("HDF5 metadata nested 2000 deep", metadata_deep)
    h = target.h5
    out.append(_h5_upload("HDF5 truncated", h[: len(h) // 2]))
    out.append(_h5_upload("HDF5 with flipped bytes", h[:2000] + bytes(b ^ 0xFF for b in h[2000:2400]) + h[2400:]))
    out.append(_h5_upload("zip bytes named .h5", _zip(list(target.campaign.items()))))
    return out


def _h5_upload(what: str, data: bytes) -> Attack:
    body = {"name": f"H5-{zlib.crc32(what.encode())}", "filename": "joint.h5", "file_b64": base64.b64encode(data).decode()}
    return Attack("HDF5 files", what, "POST", f"{API}/catalogue", "writer", JSON, json_body(body))
