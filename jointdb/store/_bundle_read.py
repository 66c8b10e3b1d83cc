"""Reading, validating and verifying a bundle before anything touches a database.

Everything a bundle carries is checked with the rules a new catalogue entry,
label or state change must pass (names, types, conditions, provenance, quality,
model kind against the FRF, label names, states, times parsed strictly as ISO
8601 with a time zone), every record and FRF hash is recomputed, and the
bundle hash (format version 2: over joints, labels, states and every record
hash, see :func:`manifest_sha256`) is compared. When any trusted public key is
given (or a signature is required) the bundle must carry a signature that
verifies with one of them; without trusted keys the signature is not checked
and no signer is reported. Any failure is one
:class:`InputError` (malformed) or :class:`IntegrityError` (altered or
damaged) line naming the bundle and the place; nothing has been written.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import uuid as uuidlib
from dataclasses import dataclass, field
from datetime import datetime
from typing import Any

import numpy as np

from jointdb.schemas._limits import check_text
from jointdb.errors import InputError, IntegrityError, JointdbError, NotFoundError
from jointdb.frf import FRF
from jointdb.store._blobformat import frf_sha256, read_frf_group
from jointdb.store._records import record_sha256
from jointdb.store._types import (
    Conditions,
    Provenance,
    as_quality,
    check_joint_type,
    check_label,
    check_model_kind,
    check_name,
)
from jointdb.store._vocabulary import dof_strings

FORMAT = "jointdb-bundle"
FORMAT_VERSION = 2
MAX_STATES = 100_000
_HEX64 = re.compile(r"[0-9a-f]{64}")
_RAW_KEY = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,99}")


@dataclass
class Bundle:
    """A bundle read and verified completely (no database access)."""

    path: str
    joints: list[dict[str, Any]]
    digest: str | None  # bundle hash (None for format version 1 bundles)
    signer: str | None = None  # fingerprint of the trusted key whose signature verified (never unchecked)
    signature_verified: bool = False
    notes: list[str] = field(default_factory=list)


def parse_time(value: Any, what: str) -> datetime:
    """An ISO 8601 time with a time zone, e.g. ``2026-01-31T12:00:00+00:00``; InputError otherwise."""
    if not isinstance(value, str) or len(value) > 64:
        raise InputError(f"{what}: {str(value)[:40]!r} is not an ISO 8601 time")
    try:
        at = datetime.fromisoformat(value)
    except ValueError:
        raise InputError(f"{what}: {value!r} is not an ISO 8601 time (e.g. 2026-01-31T12:00:00+00:00)") from None
    if at.tzinfo is None:
        raise InputError(f"{what}: {value!r} has no time zone")
    return at


def _text(value: Any, what: str, limit: int = 200) -> str:
    if not isinstance(value, str) or len(value) > limit or not value.isprintable():
        raise InputError(f"{what} must be printable text of at most {limit} characters, got {str(value)[:40]!r}")
    return value


def _int(value: Any, what: str, lo: int, hi: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
        raise InputError(f"{what} must be a whole number in {lo}..{hi}, got {str(value)[:40]!r}")
    return value


def manifest(joints: list[dict[str, Any]]) -> dict[str, Any]:
    """What the bundle hash covers: every joint's identity, labels, states and record hashes."""
    return {
        "format": FORMAT,
        "format_version": FORMAT_VERSION,
        "joints": [
            {
                "name": j["name"], "joint_type": j["joint_type"], "created_at": j["created_at"],
                "created_by": j["created_by"], "labels": j["labels"], "states": j["states"],
                "versions": [{"version": v["record"]["version"], "record_sha256": v["digest"]} for v in j["versions"]],
            }
            for j in joints
        ],
    }


def manifest_sha256(joints: list[dict[str, Any]]) -> str:
    text = json.dumps(manifest(joints), sort_keys=True, separators=(",", ":"), allow_nan=False, ensure_ascii=True)
    return hashlib.sha256(text.encode()).hexdigest()


def _attr(obj, key: str, where: str) -> str:
    if key not in obj.attrs:
        raise InputError(f"{where}: attribute {key!r} is missing")
    value = obj.attrs[key]
    if isinstance(value, bytes):
        value = value.decode("utf-8", "replace")
    if not isinstance(value, str):
        raise InputError(f"{where}: attribute {key!r} must be text")
    return value


def _json(text: str, where: str) -> Any:
    if len(text) > 50_000_000:
        raise InputError(f"{where}: JSON text of {len(text)} characters is too large")
    try:
        return json.loads(text)
    except RecursionError:
        raise InputError(f"{where}: JSON nested too deeply") from None
    except json.JSONDecodeError as exc:
        raise InputError(f"{where}: not valid JSON ({exc.msg} at line {exc.lineno})") from None


_STATE_KEYS = "version, state, reason, author, at"


def _record_wording(field: str, err: dict[str, Any]) -> str | None:
    """The bundle reader's words for a version record the schema refuses."""
    kind, value = err.get("type"), str(err.get("input"))[:40]
    if field in ("version", "parent_version", "n_freq"):
        return f"{field} must be a whole number >= 1, got {value!r}"
    if field == "uuid":
        return f"uuid {value!r} is not a UUID"
    if field == "blob_sha256":
        return "blob_sha256 is not a SHA-256 hex digest"
    if field.startswith("raw_blobs"):
        return "raw_blobs must map simple names to SHA-256 hex digests"
    if field == "provenance" or (field.startswith("provenance.") and kind in ("missing", "extra_forbidden")):
        return "provenance must have input_files, method, parameters, software_version"
    if field == "record" or field == "top level":
        return "record must be a JSON object"
    return None


def _states_wording(field: str, err: dict[str, Any]) -> str | None:
    """The bundle reader's words for labels and states the schema refuses."""
    kind, value = err.get("type"), str(err.get("input"))[:40]
    if field == "labels":
        return "labels must be a JSON object {label: version}"
    if field.startswith("labels."):
        return f"label {field[len('labels.'):]!r} version must be a whole number >= 1, got {value!r}"
    if field == "states":
        return f"states must be a JSON list (at most {MAX_STATES})"
    state = re.fullmatch(r"states\[(\d+)\](?:\.(\w+))?", field)
    if state:
        w = f"state {int(state.group(1)) + 1}"
        key = state.group(2)
        if key is None or kind in ("missing", "extra_forbidden"):
            return f"{w} must have exactly {_STATE_KEYS}"
        if key == "state":
            return f"{w}: state must be 'active' or 'deprecated', got {value!r}"
        if key == "version":
            return f"{w}: version must be a whole number >= 1, got {value!r}"
    return None


def _check_record(record: Any, name: str, jt: str, frf: FRF, label: str) -> None:
    """The record is a well-formed catalogue entry describing ``frf``.

    Its structure and JSON types are the schema's (:class:`jointdb.schemas.bundle.VersionRecord`,
    ``docs/schemas/bundle-record.schema.json``); what follows checks what a schema cannot say:
    canonical forms, the FRF it describes, version numbers in order.
    """
    from jointdb.schemas import parse

    parse("bundle-record", record, label, wording=_record_wording)
    version = _int(record["version"], f"{label}: version", 1, 10**9)
    try:
        uuidlib.UUID(record["uuid"])
    except ValueError:
        raise InputError(f"{label}: uuid {record['uuid'][:40]!r} is not a UUID") from None
    parse_time(record["created_at"], f"{label}: created_at")
    _text(record["author"], f"{label}: author")
    cond = record["conditions"]
    if Conditions.from_dict(cond).to_dict() != cond:
        raise InputError(f"{label}: conditions are not in the catalogue's form (materials, preload_n, torque_nm, "
                         "geometry, extra)")
    if check_model_kind(record["model_kind"], frf) != record["model_kind"]:
        raise InputError(f"{label}: model kind {record['model_kind']!r} is not in canonical form")
    described = {"dofs": list(dof_strings(frf.outputs)), "quantity": frf.quantity.value, "n_freq": frf.n_freq,
                 "freq_min_hz": float(frf.freq[0]), "freq_max_hz": float(frf.freq[-1])}
    for key, value in described.items():
        if record[key] != value:
            raise InputError(f"{label}: {key} {str(record[key])[:60]!r} does not describe the FRF ({value!r})")
    prov = record["provenance"]
    checked = Provenance(method=prov["method"], parameters=prov["parameters"], input_files=prov["input_files"])
    if checked.method != prov["method"] or dict(checked.input_files) != prov["input_files"]:
        raise InputError(f"{label}: provenance is not in canonical form")
    _text(prov["software_version"], f"{label}: software_version", 50)
    if record["parent_version"] is not None:
        _int(record["parent_version"], f"{label}: parent_version", 1, version - 1)
    if as_quality(record["quality"]) != record["quality"]:
        raise InputError(f"{label}: quality must map names to finite numbers")
    if not all(_RAW_KEY.fullmatch(k) for k in record["raw_blobs"]):
        raise InputError(f"{label}: raw_blobs must map simple names to SHA-256 hex digests")
    if record["name"] != name or record["joint_type"] != jt:
        raise IntegrityError(f"{label}: record names another joint")


def _check_labels(labels: Any, n: int, where: str) -> dict[str, int]:
    """A joint's labels: the schema's structure (:class:`jointdb.schemas.bundle.JointStates`), then
    canonical label text and versions that exist (1..n)."""
    from jointdb.schemas import parse

    parse("bundle-states", {"labels": labels, "states": []}, where, wording=_states_wording)
    for label, version in labels.items():
        if check_label(label) != label:
            raise InputError(f"{where}: label {label!r} has surrounding spaces")
        _int(version, f"{where}: label {label!r} version", 1, n)
    return labels


def _check_states(states: Any, n: int, where: str) -> list[dict[str, Any]]:
    """A joint's state changes: the schema's structure, then versions that exist, text and times."""
    from jointdb.schemas import parse

    parse("bundle-states", {"labels": {}, "states": states}, where, wording=_states_wording)
    for i, st in enumerate(states):
        w = f"{where}: state {i + 1}"
        if st["version"] is not None:
            _int(st["version"], f"{w}: version", 1, n)
        check_text(st["reason"], f"{w}: reason")  # text, at most 10000 characters, no control characters
        _text(st["author"], f"{w}: author")
        parse_time(st["at"], f"{w}: at")
    return states


def _read_joint(g, where: str) -> dict[str, Any]:
    name = check_name(_attr(g, "name", where))
    jt = check_joint_type(_attr(g, "joint_type", where))
    if jt != _attr(g, "joint_type", where):
        raise InputError(f"{where}: joint type {_attr(g, 'joint_type', where)!r} is not in canonical form")
    where = f"{where} ({name})"
    created_at = _attr(g, "created_at", where)
    parse_time(created_at, f"{where}: created_at")
    created_by = _text(_attr(g, "created_by", where), f"{where}: created_by")
    versions = []
    for vname in sorted(k for k in g if k.startswith("v")):
        vg = g[vname]
        label = f"{where} {vname}"
        record = _json(_attr(vg, "record", label), f"{label} record")
        digest = _attr(vg, "record_sha256", label)
        if not isinstance(record, dict) or record_sha256(record) != digest:
            raise IntegrityError(f"{label}: record hash mismatch (bundle altered or damaged)")
        if "frf" not in vg:
            raise InputError(f"{label}: the FRF group is missing")
        frf, _ = read_frf_group(vg["frf"], label)
        _check_record(record, name, jt, frf, label)
        if frf_sha256(frf) != record["blob_sha256"]:
            raise IntegrityError(f"{label}: FRF content does not match its hash")
        raw: dict[str, FRF] = {}
        for key, raw_digest in record["raw_blobs"].items():
            if "raw" not in vg or key not in vg["raw"]:
                raise InputError(f"{label}: raw measurement {key!r} is missing")
            raw_frf, _ = read_frf_group(vg["raw"][key], f"{label} raw {key}")
            if frf_sha256(raw_frf) != raw_digest:
                raise IntegrityError(f"{label}: raw measurement {key!r} does not match its hash")
            raw[key] = raw_frf
        versions.append({"record": record, "digest": digest, "frf": frf, "raw": raw})
    numbers = [v["record"]["version"] for v in versions]
    if not numbers or numbers != list(range(1, len(numbers) + 1)):
        raise InputError(f"{where}: versions {numbers[:10]} are not numbered 1..n")
    labels = _check_labels(_json(_attr(g, "labels", where), f"{where} labels"), len(numbers), where)
    states = _check_states(_json(_attr(g, "states", where), f"{where} states"), len(numbers), where)
    return {"name": name, "joint_type": jt, "created_at": created_at, "created_by": created_by,
            "labels": labels, "states": states, "versions": versions}


def read_bundle(path: str | os.PathLike, trusted_keys=(), require_signature: bool = False) -> Bundle:
    """Read and verify a bundle completely (module docstring); no database is touched.

    Parameters
    ----------
    trusted_keys
        Ed25519 public keys (:func:`jointdb.store._signing.load_public_key`) whose
        signature is accepted.
    require_signature
        Refuse a bundle that is not signed by one of ``trusted_keys``.

    Raises
    ------
    NotFoundError, InputError, IntegrityError
    """
    import h5py

    where = os.fspath(path)
    if os.path.isdir(where):
        raise InputError(f"bundle {where} is a directory")
    if not os.path.isfile(where):
        raise NotFoundError(f"bundle {where} does not exist")
    if require_signature and not trusted_keys:
        raise InputError("--require-signature needs at least one trusted public key (--trust KEY.pub)")
    try:
        f = h5py.File(where, "r", locking=False)
    except OSError as exc:
        raise InputError(f"{where}: not a jointdb bundle (cannot open as HDF5: {str(exc).splitlines()[0]})") from None
    try:
        with f:
            if f.attrs.get("format") != FORMAT and str(f.attrs.get("format", "")) != FORMAT:
                raise InputError(f"{where}: not a jointdb bundle (format attribute {str(f.attrs.get('format'))[:40]!r})")
            fmt_version = f.attrs.get("format_version", 0)
            if isinstance(fmt_version, bool) or not isinstance(fmt_version, (int, np.integer)) \
                    or int(fmt_version) not in (1, 2):
                raise InputError(f"{where}: bundle format version {str(fmt_version)[:20]} is not one this jointdb "
                                 f"reads (1..{FORMAT_VERSION})")
            if "joints" not in f or not isinstance(f["joints"], h5py.Group):
                raise InputError(f"{where}: the joints group is missing")
            joints = [_read_joint(f["joints"][g], f"{where}: joint {g}") for g in sorted(f["joints"])]
            names = [j["name"] for j in joints]
            if len(set(names)) != len(names):
                raise InputError(f"{where}: a joint appears twice")
            digest = None
            if int(fmt_version) >= 2:
                digest = manifest_sha256(joints)
                if _attr(f, "bundle_sha256", where) != digest:
                    raise IntegrityError(f"{where}: bundle hash mismatch (joints, labels or states were altered "
                                         "after export)")
            signature = f.attrs.get("signature")
            signer = f.attrs.get("signer_public_key")
    except JointdbError:
        raise
    except (OSError, KeyError, TypeError, ValueError, AttributeError, RecursionError, UnicodeError) as exc:
        raise InputError(f"{where}: malformed bundle ({type(exc).__name__}: {str(exc).splitlines()[0][:200]})") from None
    bundle = Bundle(where, joints, digest)
    _verify_signature(bundle, signature, signer, trusted_keys, require_signature)
    return bundle


def _verify_signature(bundle: Bundle, signature, signer, trusted_keys, require_signature: bool) -> None:
    """Check the signature: any trusted key (or ``require_signature``) means it must verify.

    ``bundle.signer`` is set only from a verified signature (the key that verified it); the
    unchecked ``signer_public_key`` attribute is never reported as the signer.

    Raises
    ------
    IntegrityError
        Trusted keys were given (or a signature is required) and the bundle is unsigned,
        or its signature does not verify with any trusted key.
    """
    from jointdb.store import _signing

    where = bundle.path
    if signature is not None and bundle.digest is None:
        raise InputError(f"{where}: a signed bundle must be format version 2")
    if signature is not None and signer is not None:
        try:
            bytes.fromhex(str(signer))
        except ValueError:
            raise InputError(f"{where}: signer_public_key is not hex") from None
    if not trusted_keys:
        if require_signature:
            raise IntegrityError(f"{where}: the bundle is not signed; --require-signature refuses it")
        bundle.notes.append("unsigned / signature not checked (give --trust KEY.pub to verify who exported it)")
        return
    if signature is None:
        raise IntegrityError(f"{where}: the bundle is not signed, but trusted keys were given (--trust); refusing it")
    key = _signing.verify_digest(trusted_keys, bundle.digest, str(signature))
    if key is None:
        raise IntegrityError(f"{where}: the signature does not verify with any trusted key (bundle altered, or "
                             "signed by a key that is not trusted)")
    bundle.signature_verified = True
    bundle.signer = _signing.fingerprint(_signing.public_raw(key))
    bundle.notes.append(f"signature verified: signed by trusted key {bundle.signer}")
