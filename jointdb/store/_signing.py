"""Ed25519 keys and signatures for bundles (``cryptography`` package).

A key pair is two PEM files: ``NAME`` (private key, PKCS#8, mode 0600) and
``NAME.pub`` (public key, SubjectPublicKeyInfo). A lab signs the bundles it
exports with its private key; whoever imports them trusts the lab's ``.pub``
file. What is signed is the bundle hash (see :mod:`jointdb.store._bundle`)
behind a fixed prefix, so a signature says: this lab exported exactly these
joints, versions, labels and states.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import tempfile
from pathlib import Path

from jointdb.errors import ConflictError, InputError, NotFoundError

SIGNED_PREFIX = b"jointdb-bundle-signature-v1\n"


def _crypto():
    try:
        from cryptography.hazmat.primitives import serialization
        from cryptography.hazmat.primitives.asymmetric import ed25519
    except ImportError:  # pragma: no cover - a declared dependency
        raise InputError('signing needs the cryptography package: pip install "cryptography>=42"') from None
    return serialization, ed25519


def _write_new(path: Path, data: bytes, mode: int) -> None:
    """Write a new file (never replacing one) completely or not at all."""
    directory = path.parent if str(path.parent) else Path(".")
    if not directory.is_dir():
        raise InputError(f"cannot write {path}: directory {directory} does not exist")
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=directory)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.chmod(tmp, mode)
        os.link(tmp, path)  # FileExistsError instead of replacing a key
    except FileExistsError:
        raise ConflictError(f"{path} already exists; keys are never overwritten (choose another name)") from None
    except OSError as exc:
        raise InputError(f"cannot write {path}: {exc.strerror or exc}") from None
    finally:
        with contextlib.suppress(OSError):
            os.unlink(tmp)


def create_key_pair(path: str | os.PathLike) -> tuple[Path, Path]:
    """Write a new Ed25519 key pair to ``path`` (private) and ``path.pub``.

    Parameters
    ----------
    path
        The private key file (PEM, mode 0600); the public key goes to ``path.pub``.

    Returns
    -------
    private, public : Path

    Raises
    ------
    ConflictError
        Either file exists already (nothing is written).
    InputError
        The directory does not exist or cannot be written.
    """
    serialization, ed25519 = _crypto()
    private_path = Path(path)
    public_path = Path(str(private_path) + ".pub")
    for p in (private_path, public_path):
        if p.exists():
            raise ConflictError(f"{p} already exists; keys are never overwritten (choose another name)")
    key = ed25519.Ed25519PrivateKey.generate()
    private_pem = key.private_bytes(serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8,
                                    serialization.NoEncryption())
    public_pem = key.public_key().public_bytes(serialization.Encoding.PEM,
                                               serialization.PublicFormat.SubjectPublicKeyInfo)
    _write_new(private_path, private_pem, 0o600)
    try:
        _write_new(public_path, public_pem, 0o644)
    except BaseException:
        private_path.unlink(missing_ok=True)
        raise
    return private_path, public_path


def read_small_file(path: str | os.PathLike, shown: str, too_large: str, limit: int = 64 * 1024) -> bytes:
    """The bytes of a small file (a key, a checkpoint), with one-line errors.

    Parameters
    ----------
    path
        The file.
    shown
        How the messages name it, e.g. ``"checkpoint cp.json"``.
    too_large
        What a file over ``limit`` is told, with ``{n}`` for its size in bytes.
    limit
        Largest size accepted [bytes].

    Returns
    -------
    bytes

    Raises
    ------
    InputError
        The file cannot be read or is larger than ``limit``.
    """
    try:
        data = Path(path).read_bytes()
    except OSError as exc:
        raise InputError(f"cannot read {shown}: {exc.strerror or exc}") from None
    if len(data) > limit:
        raise InputError(f"{shown} {too_large.format(n=len(data))}")
    return data


def _read(path: str | os.PathLike, what: str) -> bytes:
    p = Path(path)
    if not p.is_file():
        raise NotFoundError(f"{what} {p} does not exist")
    return read_small_file(p, f"{what} {p}", "is not a key file ({n} bytes)")


def load_private_key(path: str | os.PathLike):
    """The Ed25519 private key in a PEM file (``jointdb keys create``), to sign a bundle with.

    Parameters
    ----------
    path
        The unencrypted PEM file.

    Returns
    -------
    cryptography.hazmat.primitives.asymmetric.ed25519.Ed25519PrivateKey

    Raises
    ------
    NotFoundError
        No such file.
    InputError
        Not an unencrypted Ed25519 PEM private key.
    """
    serialization, ed25519 = _crypto()
    data = _read(path, "private key")
    try:
        key = serialization.load_pem_private_key(data, password=None)
    except (ValueError, TypeError) as exc:
        raise InputError(f"{path} is not an unencrypted PEM private key ({str(exc).splitlines()[0]})") from None
    if not isinstance(key, ed25519.Ed25519PrivateKey):
        raise InputError(f"{path} is not an Ed25519 private key (make one with `jointdb keys create`)")
    return key


def load_public_key(path: str | os.PathLike):
    """The Ed25519 public key in a PEM file (``NAME.pub`` of ``jointdb keys create``), to trust.

    Parameters
    ----------
    path
        The PEM file.

    Returns
    -------
    cryptography.hazmat.primitives.asymmetric.ed25519.Ed25519PublicKey

    Raises
    ------
    NotFoundError
        No such file.
    InputError
        Not an Ed25519 PEM public key.
    """
    serialization, ed25519 = _crypto()
    data = _read(path, "public key")
    try:
        key = serialization.load_pem_public_key(data)
    except (ValueError, TypeError) as exc:
        raise InputError(f"{path} is not a PEM public key ({str(exc).splitlines()[0]})") from None
    if not isinstance(key, ed25519.Ed25519PublicKey):
        raise InputError(f"{path} is not an Ed25519 public key (use the .pub file of `jointdb keys create`)")
    return key


def public_raw(key) -> bytes:
    serialization, _ = _crypto()
    return key.public_bytes(serialization.Encoding.Raw, serialization.PublicFormat.Raw)


def fingerprint(public_key_raw: bytes) -> str:
    """Short, stable name of a public key: the first 16 hex digits of SHA-256 of its 32 raw bytes."""
    return hashlib.sha256(public_key_raw).hexdigest()[:16]


def sign_digest(private_key, digest_hex: str) -> tuple[str, str]:
    """``(signature_hex, public_key_hex)`` over :data:`SIGNED_PREFIX` + the bundle hash."""
    signature = private_key.sign(SIGNED_PREFIX + digest_hex.encode("ascii"))
    return signature.hex(), public_raw(private_key.public_key()).hex()


def verify_digest(public_keys, digest_hex: str, signature_hex: str):
    """The trusted key (of ``public_keys``) whose signature over the bundle hash verifies, else None."""
    from cryptography.exceptions import InvalidSignature

    try:
        signature = bytes.fromhex(signature_hex)
    except ValueError:
        return None
    for key in public_keys:
        try:
            key.verify(signature, SIGNED_PREFIX + digest_hex.encode("ascii"))
            return key
        except InvalidSignature:
            continue
    return None
