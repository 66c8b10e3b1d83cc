"""Campaign archives uploaded to the service: unpacked as data, never as paths.

A campaign archive is a ``.zip`` holding one campaign file (``"format":
"jointdb-campaign/1"``) and the files it names, either flat or in folders (e.g.
``campaigns/th-1/campaign.json`` beside ``models/tool.json`` so that the
campaign's ``../../models/tool.json`` stays inside the archive). Everything is
checked before or while it is unpacked, and every refusal is an
:class:`~jointdb.errors.InputError` (422) of one line naming the archive's own
member, never a server path:

- member names: relative, UTF-8, printable, no ``..``/``.``/empty part, no
  absolute path, drive letter or backslash, no hidden file, no duplicate (also
  not by case), no file that is also a folder;
- member kinds: regular files and folders only (no symlink, device or pipe),
  not encrypted, stored or deflated (no other compression method);
- sizes, counted on the bytes actually unpacked (the header is not trusted):
  at most :data:`MAX_MEMBERS` members, :data:`MAX_TOTAL_BYTES` in all, a
  compression ratio of at most :data:`MAX_RATIO` beyond the first
  :data:`RATIO_FREE_BYTES` of a member, and exactly the size and CRC-32 the
  archive records.

The campaign is then read confined to the unpacked folder
(``load_campaign(..., root=...)``): a file it names outside the archive is
refused before it is opened.

An uploaded HDF5 joint file is checked likewise
(:func:`check_hdf5_self_contained`): no external link, external raw storage or
virtual dataset, each of which would make the server read a file it names.
"""

from __future__ import annotations

import json
import stat
import struct
import unicodedata
import zipfile
import zlib
from pathlib import Path

from jointdb.errors import InputError, JointdbError

MAX_MEMBERS = 200
MAX_TOTAL_BYTES = 256 * 2**20
MAX_RATIO = 100
RATIO_FREE_BYTES = 2**20
MAX_DEPTH = 8
MAX_NAME_CHARS = 255
CHUNK = 2**16
#: compression methods accepted (what every zip tool writes)
METHODS = {zipfile.ZIP_STORED: "stored", zipfile.ZIP_DEFLATED: "deflated"}
#: members that archivers add on their own; skipped, not unpacked
_IGNORED_DIRS = ("__MACOSX",)
_IGNORED_FILES = (".DS_Store", "Thumbs.db")
_EOCD = b"PK\x05\x06"

_READ_ERRORS = (zipfile.BadZipFile, zipfile.LargeZipFile, EOFError, zlib.error, NotImplementedError,
                RuntimeError, ValueError, struct.error, UnicodeDecodeError)


def _refuse(archive: str, what: str) -> InputError:
    return InputError(f"{archive}: {what}")


def _declared_members(data: bytes) -> int | None:
    """Number of members the end-of-central-directory record declares (None when absent),
    read before the central directory is parsed, so that a huge directory is never loaded."""
    at = data.rfind(_EOCD, max(0, len(data) - 65557))
    if at < 0 or len(data) - at < 22:
        return None
    return struct.unpack("<H", data[at + 10:at + 12])[0]


def _member_name(archive: str, info: zipfile.ZipInfo) -> str:
    """The member's name as UTF-8 text, or a refusal (names the zip did not mark as UTF-8 are
    accepted when their bytes are valid UTF-8 anyway, as many archivers write them)."""
    name = info.orig_filename
    if not info.flag_bits & 0x800 and not name.isascii():
        try:
            name = name.encode("cp437").decode("utf-8")
        except (UnicodeEncodeError, UnicodeDecodeError):
            raise _refuse(archive, f"member {name[:60]!r} does not have a UTF-8 name") from None
    return name


def _member_parts(archive: str, name: str) -> tuple[str, ...] | None:
    """The path parts of a member inside the archive; None for a member to skip."""
    shown = repr(name[:60])
    if any(unicodedata.category(ch) == "Cc" for ch in name):
        raise _refuse(archive, f"member {shown} has a control character in its name")
    if "\\" in name or name.startswith("/") or (len(name) > 1 and name[1] == ":"):
        raise _refuse(archive, f"member {shown} must be a plain file name or a relative path inside the "
                               "archive (no absolute path, drive or backslash)")
    parts = tuple(name.rstrip("/").split("/")) if name.rstrip("/") else ("",)
    if parts[0] in _IGNORED_DIRS or parts[-1] in _IGNORED_FILES:
        return None
    if any(p in ("", ".", "..") for p in parts):
        raise _refuse(archive, f"member {shown} must be a plain file name or a relative path inside the "
                               "archive (no '..', '.' or empty part)")
    if any(p.startswith(".") for p in parts):
        raise _refuse(archive, f"member {shown}: hidden files and folders are not accepted")
    if len(parts) > MAX_DEPTH or any(len(p) > MAX_NAME_CHARS for p in parts):
        raise _refuse(archive, f"member {shown} is nested deeper than {MAX_DEPTH} folders or has a part "
                               f"longer than {MAX_NAME_CHARS} characters")
    return parts


def _check_kind(archive: str, info: zipfile.ZipInfo, shown: str) -> None:
    """Regular files and folders only, not encrypted, a supported compression method."""
    mode = info.external_attr >> 16
    if info.create_system == 3 and mode:  # Unix attributes
        if stat.S_ISLNK(mode):
            raise _refuse(archive, f"member {shown} is a symbolic link; put the file itself in the archive")
        if stat.S_IFMT(mode) not in (0, stat.S_IFREG, stat.S_IFDIR):  # 0: permissions only
            raise _refuse(archive, f"member {shown} is not a regular file")
    if info.flag_bits & 0x1:
        raise _refuse(archive, f"member {shown} is encrypted; upload an archive without a password")
    if info.compress_type not in METHODS:
        raise _refuse(archive, f"member {shown} uses compression method {info.compress_type}; "
                               f"use {' or '.join(METHODS.values())}")


def _plan(archive: str, zf: zipfile.ZipFile) -> list[tuple[zipfile.ZipInfo, tuple[str, ...]]]:
    """The members to unpack with their parts, after every check that needs no decompression."""
    infos = zf.infolist()
    if len(infos) > MAX_MEMBERS:
        raise _refuse(archive, f"has {len(infos)} members; the limit is {MAX_MEMBERS}")
    plan, seen, folders, declared = [], set(), set(), 0
    for info in infos:
        name = _member_name(archive, info)
        parts = _member_parts(archive, name)
        if parts is None:
            continue
        shown = repr(name[:60])
        _check_kind(archive, info, shown)
        key = "/".join(parts).casefold()
        if key in seen:
            raise _refuse(archive, f"member {shown} appears more than once")
        seen.add(key)
        folders.update("/".join(parts[:k]).casefold() for k in range(1, len(parts)))
        if info.is_dir():
            continue
        declared += info.file_size
        if declared > MAX_TOTAL_BYTES:
            raise _refuse(archive, f"unpacks to more than {MAX_TOTAL_BYTES // 2**20} MiB")
        plan.append((info, parts))
    for info, parts in plan:
        if "/".join(parts).casefold() in folders:
            raise _refuse(archive, f"member {'/'.join(parts)[:60]!r} is both a file and a folder")
    return plan


def _unpack_member(archive: str, zf: zipfile.ZipFile, info: zipfile.ZipInfo, dest: Path, total: int) -> int:
    """Stream one member to ``dest`` counting the bytes really unpacked; the new total."""
    shown = repr(info.orig_filename[:60])
    n = 0
    try:
        with zf.open(info) as src, open(dest, "xb") as dst:
            while True:
                chunk = src.read(CHUNK)
                if not chunk:
                    break
                n += len(chunk)
                if total + n > MAX_TOTAL_BYTES:
                    raise _refuse(archive, f"unpacks to more than {MAX_TOTAL_BYTES // 2**20} MiB")
                if n > RATIO_FREE_BYTES and n > MAX_RATIO * max(info.compress_size, 1):
                    raise _refuse(archive, f"member {shown} expands more than {MAX_RATIO} times "
                                           "(a zip bomb?)")
                if n > info.file_size:
                    raise _refuse(archive, f"member {shown} is larger than the size the archive records")
                dst.write(chunk)
    except JointdbError:
        raise
    except _READ_ERRORS as exc:
        what = "bad CRC-32" if "crc" in str(exc).lower() else type(exc).__name__
        raise _refuse(archive, f"member {shown} cannot be unpacked ({what}): the archive is damaged or "
                               "records a wrong size") from None
    if n != info.file_size:
        raise _refuse(archive, f"member {shown} unpacks to {n} bytes but the archive records {info.file_size}")
    return total + n


def _find_campaign(archive: str, into: Path, files: list[Path]) -> Path:
    """The one campaign file among the unpacked JSON files."""
    from jointdb._limits import MAX_JSON_BYTES

    campaigns = []
    for p in files:
        if p.suffix.lower() != ".json" or p.stat().st_size > MAX_JSON_BYTES:
            continue
        try:
            raw = json.loads(p.read_text(encoding="utf-8"))
        except (ValueError, UnicodeDecodeError, RecursionError):
            continue
        if isinstance(raw, dict) and str(raw.get("format", "")).startswith("jointdb-campaign"):
            campaigns.append(p)
    if len(campaigns) != 1:
        names = ", ".join(p.relative_to(into).as_posix() for p in campaigns[:4])
        raise _refuse(archive, f"needs exactly one campaign file (format jointdb-campaign/1), found "
                               f"{len(campaigns)}{': ' + names if names else ''}")
    return campaigns[0]


def check_hdf5_self_contained(path: Path, label: str) -> None:
    """Refuse an uploaded HDF5 file that would make the server read another file: an external
    link, a dataset with external raw storage, or a virtual dataset (all three name files of
    the server). Anything that is not HDF5 is left to the reader's own message.

    Raises
    ------
    InputError
        One line naming the object and what it refers to (never the file it names).
    """
    import h5py

    try:
        f = h5py.File(path, "r", locking=False)
    except OSError:
        return
    with f:
        seen: set = set()
        todo: list[tuple[str, h5py.Group]] = [("", f)]
        while todo:
            prefix, group = todo.pop()
            for name in list(group):
                where = f"{prefix}/{name}"
                link = group.get(name, getlink=True)
                if isinstance(link, h5py.ExternalLink):
                    raise _refuse(label, f"{where[:80]} is an external link to another file; upload a file "
                                         "that holds its data itself")
                if isinstance(link, h5py.SoftLink):
                    continue  # inside this file: its target is reached through its own hard link
                obj = group[name]
                info = h5py.h5o.get_info(obj.id)
                key = (info.fileno, info.addr)  # an object hard-linked twice is visited once
                if key in seen:
                    continue
                seen.add(key)
                if len(seen) > 10_000:
                    raise _refuse(label, "has more than 10000 HDF5 objects")
                if isinstance(obj, h5py.Dataset):
                    if obj.is_virtual or obj.external:
                        raise _refuse(label, f"dataset {where[:80]} keeps its data in another file (external "
                                             "or virtual storage); upload a file that holds its data itself")
                elif isinstance(obj, h5py.Group):
                    todo.append((where, obj))


def unpack_campaign(archive: Path, into: Path) -> Path:
    """Unpack an uploaded campaign archive into the new folder ``into`` and return its campaign file.

    Parameters
    ----------
    archive
        The uploaded ``.zip`` (its name is used in messages).
    into
        A folder that does not exist yet (created here); read the campaign with
        ``root=into`` so that it cannot name files outside it.

    Raises
    ------
    InputError
        One line naming the member and what is wrong with it (see the module's docstring).
    """
    label = archive.name
    data = archive.read_bytes()
    declared = _declared_members(data)
    if declared is not None and declared > MAX_MEMBERS:
        raise _refuse(label, f"declares {declared} members; the limit is {MAX_MEMBERS}")
    del data
    try:
        zf = zipfile.ZipFile(archive)
    except _READ_ERRORS as exc:
        what = "member names are not valid UTF-8" if isinstance(exc, UnicodeDecodeError) else "not a zip archive"
        raise _refuse(label, f"{what} (or the archive is damaged)") from None
    with zf:
        plan = _plan(label, zf)
        into.mkdir()
        root = into.resolve()
        total, files = 0, []
        for info, parts in plan:
            dest = root.joinpath(*parts)
            dest.parent.mkdir(parents=True, exist_ok=True)
            if dest.parent.resolve() != dest.parent or not dest.parent.is_relative_to(root):
                raise _refuse(label, f"member {'/'.join(parts)[:60]!r} leaves the archive")  # defensive
            total = _unpack_member(label, zf, info, dest, total)
            files.append(dest)
    return _find_campaign(label, root, sorted(files))
