"""API tokens of the HTTP service: create, list, revoke, authenticate.

A token is ``jdb_<id>_<secret>``: ``<id>`` (12 hex digits) is public and names the
token in listings; ``<secret>`` is 32 random bytes (base64url). The database keeps
only the SHA-256 of the whole token (a high-entropy secret needs no slow hash),
compared in constant time; the token is shown once, when it is created.

Roles are ordered: ``reader`` < ``writer`` < ``admin``; a role includes the ones
below it. Creating and revoking tokens is written to the audit log (action
``token-create`` / ``token-revoke``, never the token).
"""

from __future__ import annotations

import hashlib
import hmac
import re
import secrets
from dataclasses import dataclass
from datetime import datetime, timedelta, timezone
from typing import TYPE_CHECKING

from sqlalchemy import select
from sqlalchemy.orm import Session

from jointdb.errors import InputError, NotFoundError
from jointdb.store._models import AuditRow, TokenRow, utcnow
from jointdb.store._records import as_utc, current_actor

if TYPE_CHECKING:  # pragma: no cover
    from jointdb.store import Repository

ROLES = ("reader", "writer", "admin")
_TOKEN = re.compile(r"jdb_([0-9a-f]{12})_[A-Za-z0-9_-]{43}")
_OWNER = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.@-]{0,99}")


@dataclass(frozen=True)
class TokenInfo:
    """A token as listed (never the secret): owner ``name``, ``role``, times in UTC."""

    token_id: str
    name: str
    role: str
    created_at: datetime
    created_by: str
    expires_at: datetime | None
    revoked_at: datetime | None

    def status(self, now: datetime | None = None) -> str:
        now = now or utcnow()
        if self.revoked_at is not None:
            return "revoked"
        if self.expires_at is not None and self.expires_at <= now:
            return "expired"
        return "active"

    def allows(self, role: str) -> bool:
        """True when this token's role includes ``role``."""
        return ROLES.index(self.role) >= ROLES.index(role)

    def to_dict(self) -> dict:
        return {
            "token_id": self.token_id, "name": self.name, "role": self.role, "status": self.status(),
            "created_at": self.created_at.isoformat(timespec="seconds"), "created_by": self.created_by,
            "expires_at": self.expires_at.isoformat(timespec="seconds") if self.expires_at else None,
            "revoked_at": self.revoked_at.isoformat(timespec="seconds") if self.revoked_at else None,
        }


def token_sha256(token: str) -> str:
    return hashlib.sha256(token.encode("utf-8")).hexdigest()


def _info(row: TokenRow) -> TokenInfo:
    return TokenInfo(row.token_id, row.name, row.role, row.created_at, row.created_by, row.expires_at,
                     row.revoked_at)


def check_role(role: str) -> str:
    r = str(role or "").strip().lower()
    if r not in ROLES:
        raise InputError(f"role {role!r} must be one of {', '.join(ROLES)}")
    return r


def check_owner(name: str) -> str:
    text = str(name or "").strip()
    if not _OWNER.fullmatch(text):
        raise InputError(f"token owner {str(name)[:60]!r} must be 1-100 letters, digits, '.', '_', '@' or '-'")
    return text


def parse_expiry(expires: str | datetime | None, now: datetime | None = None) -> datetime | None:
    """``None``, an ISO 8601 time, or a lifetime such as ``30d``, ``12h``, ``90m``."""
    if expires is None or expires == "":
        return None
    now = now or utcnow()
    if isinstance(expires, str):
        m = re.fullmatch(r"\s*(\d+)\s*([dhm])\s*", expires)
        if m:
            n, unit = int(m.group(1)), m.group(2)
            if n < 1:
                raise InputError(f"--expires {expires!r}: a lifetime must be at least 1{unit}")
            return now + timedelta(**{{"d": "days", "h": "hours", "m": "minutes"}[unit]: n})
    at = as_utc(expires)
    if at <= now:
        raise InputError(f"--expires {at.isoformat(timespec='seconds')} is in the past")
    return at


def create_token(repo: "Repository", name: str, role: str, expires: str | datetime | None = None,
                 created_by: str | None = None) -> tuple[str, TokenInfo]:
    """A new token for owner ``name``: returns ``(token, info)``; the token is not stored."""
    name, role = check_owner(name), check_role(role)
    expires_at = parse_expiry(expires)
    actor = current_actor(created_by)
    token_id = secrets.token_hex(6)
    token = f"jdb_{token_id}_{secrets.token_urlsafe(32)}"

    def write(s: Session) -> TokenInfo:
        now = utcnow()
        row = TokenRow(token_id=token_id, sha256=token_sha256(token), name=name, role=role, created_at=now,
                       created_by=actor, expires_at=expires_at, revoked_at=None)
        s.add(row)
        s.add(AuditRow(at=now, actor=actor, action="token-create", joint_name=None, version=None,
                       details={"token_id": token_id, "owner": name, "role": role}))
        s.flush()
        return _info(row)

    return token, repo._retrying(write)


def list_tokens(repo: "Repository") -> list[TokenInfo]:
    with repo._read() as s:
        return [_info(r) for r in s.scalars(select(TokenRow).order_by(TokenRow.id))]


def revoke_token(repo: "Repository", token_id: str, revoked_by: str | None = None) -> TokenInfo:
    """Revoke a token by its public id (or by the whole token); revoking twice is a no-op."""
    tid = str(token_id or "").strip()
    m = _TOKEN.fullmatch(tid)
    if m:
        tid = m.group(1)
    if not re.fullmatch(r"[0-9a-f]{12}", tid):
        raise InputError(f"token id {tid[:20]!r} must be the 12 hex digits `jointdb tokens list` shows")
    actor = current_actor(revoked_by)

    def write(s: Session) -> TokenInfo:
        row = s.scalar(select(TokenRow).where(TokenRow.token_id == tid).with_for_update())
        if row is None:
            raise NotFoundError(f"no token with id {tid} (see `jointdb tokens list`)")
        if row.revoked_at is None:
            now = utcnow()
            row.revoked_at = now
            s.add(AuditRow(at=now, actor=actor, action="token-revoke", joint_name=None, version=None,
                           details={"token_id": tid, "owner": row.name}))
        s.flush()
        return _info(row)

    return repo._retrying(write)


def authenticate(repo: "Repository", token: str) -> TokenInfo | None:
    """The active token's info, or None (unknown, malformed, revoked or expired token).

    Nothing about the presented token is ever put into an exception or a log.
    """
    if not isinstance(token, str) or not _TOKEN.fullmatch(token):
        return None
    digest = token_sha256(token)
    with repo._read() as s:
        row = s.scalar(select(TokenRow).where(TokenRow.token_id == token[4:16]))
    if row is None or not hmac.compare_digest(row.sha256, digest):
        return None
    info = _info(row)
    return info if info.status(datetime.now(timezone.utc)) == "active" else None
