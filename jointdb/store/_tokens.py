"""API tokens of the HTTP service: create, list, revoke, authenticate.

A token is ``jdb_<id>_<secret>``: ``<id>`` (12 hex digits) is public and names the
token in listings; ``<secret>`` is 32 random bytes (base64url). The database keeps
only the SHA-256 of the whole token (a high-entropy secret needs no slow hash),
compared in constant time; the token is shown once, when it is created.

Roles are ordered: ``reader`` < ``writer`` < ``admin``; a role includes the ones
below it. Creating and revoking tokens is written to the audit log (action
``token-create`` / ``token-revoke``, never the token). A token may name a ``team``:
a writer may label or deprecate the joints they or their team catalogued
(:func:`check_may_change`), an admin any.

Sessions of the web catalogue live here too (:func:`open_session`,
:func:`session_user`, :func:`close_session`): the browser holds a random session id
(256 bits), the database only its SHA-256, the token it was opened with and its
times; a session ends when it is closed (sign-out), idle too long, past its absolute
lifetime, or when its token is revoked or expires.
"""

from __future__ import annotations

import hashlib
import hmac
import re
import secrets
from dataclasses import dataclass
from datetime import datetime, timedelta, timezone
from typing import TYPE_CHECKING

from sqlalchemy import bindparam, delete, select, update
from sqlalchemy.orm import Session

from jointdb.errors import InputError, NotFoundError, NotPermittedError
from jointdb.store._access import read_session
from jointdb.store._models import AuditRow, JointRow, TokenRow, VersionRow, WebSessionRow, utcnow
from jointdb.store._records import as_utc, current_actor

if TYPE_CHECKING:  # pragma: no cover
    from jointdb.store import Repository

ROLES = ("reader", "writer", "admin")
_TOKEN = re.compile(r"jdb_([0-9a-f]{12})_[A-Za-z0-9_-]{43}")
_OWNER = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.@-]{0,99}")
_SESSION = re.compile(r"[A-Za-z0-9_-]{43}")
#: How often at most a session's ``last_seen_at`` is written (a page view is not a write each time).
SESSION_TOUCH_S = 60.0
#: Sessions ended longer ago than this are deleted when a new one is opened.
SESSION_KEEP_S = 7 * 24 * 3600.0


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
    team: str | None = None

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
            "team": self.team,
        }


def token_sha256(token: str) -> str:
    return hashlib.sha256(token.encode("utf-8")).hexdigest()


def _info(row: TokenRow) -> TokenInfo:
    return TokenInfo(row.token_id, row.name, row.role, row.created_at, row.created_by, row.expires_at,
                     row.revoked_at, row.team)


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


def check_team(team: str | None) -> str | None:
    """``None`` (no team) or a team name: 1-100 letters, digits, '.', '_', '@' or '-'."""
    if team is None or str(team).strip() == "":
        return None
    text = str(team).strip()
    if not _OWNER.fullmatch(text) or len(text) > 100:
        raise InputError(f"team {str(team)[:60]!r} must be 1-100 letters, digits, '.', '_', '@' or '-'")
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
                 created_by: str | None = None, team: str | None = None) -> tuple[str, TokenInfo]:
    """A new token for owner ``name`` (optionally of ``team``): returns ``(token, info)``;
    the token is not stored."""
    name, role, team = check_owner(name), check_role(role), check_team(team)
    expires_at = parse_expiry(expires)
    actor = current_actor(created_by)
    token_id = secrets.token_hex(6)
    token = f"jdb_{token_id}_{secrets.token_urlsafe(32)}"

    def write(s: Session) -> TokenInfo:
        now = utcnow()
        row = TokenRow(token_id=token_id, sha256=token_sha256(token), name=name, role=role, created_at=now,
                       created_by=actor, expires_at=expires_at, revoked_at=None, team=team)
        s.add(row)
        details = {"token_id": token_id, "owner": name, "role": role, **({"team": team} if team else {})}
        s.add(AuditRow(at=now, actor=actor, action="token-create", joint_name=None, version=None,
                       details=details))
        s.flush()
        return _info(row)

    return token, repo.storage.retrying(write)


def list_tokens(repo: "Repository") -> list[TokenInfo]:
    with read_session(repo) as s:
        return [_info(r) for r in s.scalars(select(TokenRow).order_by(TokenRow.id))]


def revoke_token(repo: "Repository", token_id: str, revoked_by: str | None = None) -> TokenInfo:
    """Revoke a token by its public id (or by the whole token); revoking twice is a no-op.
    The web sessions opened with it end too."""
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
        s.execute(update(WebSessionRow).where(WebSessionRow.token_id == tid, WebSessionRow.revoked_at.is_(None))
                  .values(revoked_at=utcnow()))
        s.flush()
        return _info(row)

    return repo.storage.retrying(write)


#: The token row by its public id (one statement, compiled once; columns by their attribute names).
_BY_TOKEN_ID = select(*TokenRow.__table__.columns).where(TokenRow.__table__.c.token_id == bindparam("token_id"))


def authenticate(repo: "Repository", token: str) -> TokenInfo | None:
    """The active token's info, or None (unknown, malformed, revoked or expired token).

    Nothing about the presented token is ever put into an exception or a log.
    """
    if not isinstance(token, str) or not _TOKEN.fullmatch(token):
        return None
    digest = token_sha256(token)
    with repo.read_engine.connect() as conn:  # Core, not an ORM session: this runs on every request
        row = conn.execute(_BY_TOKEN_ID, {"token_id": token[4:16]}).first()
    if row is None or not hmac.compare_digest(row.sha256, digest):
        return None
    info = _info(row)
    return info if info.status(datetime.now(timezone.utc)) == "active" else None


def check_may_change(repo: "Repository", who: TokenInfo, name: str, action: str) -> None:
    """Whether ``who`` may ``action`` (label, deprecate) the joint ``name``.

    An admin may change any joint; a writer the joints they catalogued (the author
    of the joint's first version is the token's owner) or that a member of their
    team catalogued (a token of the author's names the same team). Adding a
    version to someone else's joint does not make it yours. An unknown joint
    passes (the write itself answers "not found").

    Raises
    ------
    NotPermittedError
        Naming the joint's author and what would allow the change.
    """
    if who.allows("admin"):
        return
    if not who.allows("writer"):
        raise NotPermittedError(f"the token of {who.name} has role {who.role}; {action} needs writer")
    with read_session(repo) as s:
        author = s.scalar(select(VersionRow.author).join(JointRow, JointRow.id == VersionRow.joint_id)
                          .where(JointRow.name == name).order_by(VersionRow.version).limit(1))
        if author is None or author == who.name:
            return
        if who.team is not None and s.scalar(select(TokenRow.id).where(
                TokenRow.name == author, TokenRow.team == who.team).limit(1)) is not None:
            return
    team = f" or team {who.team}" if who.team else ""
    raise NotPermittedError(f"{who.name}{team} may not {action} {name}: it was catalogued by {author}; "
                            f"its author, their team or an admin may")


@dataclass(frozen=True)
class WebSession:
    """An open session of the web catalogue: its token (owner, role, team) and times in UTC."""

    token: TokenInfo
    created_at: datetime
    last_seen_at: datetime
    expires_at: datetime


def session_sha256(session_id: str) -> str:
    return hashlib.sha256(b"jointdb-web-session\x00" + session_id.encode("utf-8")).hexdigest()


def open_session(repo: "Repository", token: str, lifetime_s: float,
                 now: datetime | None = None) -> tuple[str, WebSession] | None:
    """Sign in with an API token: ``(session_id, session)``, or None when the token is not
    accepted. The session ends after ``lifetime_s`` at the latest (or when the token
    expires, if sooner); sessions ended more than a week ago are deleted."""
    info = authenticate(repo, token)
    if info is None:
        return None
    now = now or utcnow()
    expires = now + timedelta(seconds=float(lifetime_s))
    if info.expires_at is not None:
        expires = min(expires, info.expires_at)
    session_id = secrets.token_urlsafe(32)  # 256 bits

    def write(s: Session) -> WebSession:
        old = now - timedelta(seconds=SESSION_KEEP_S)
        s.execute(delete(WebSessionRow).where(WebSessionRow.expires_at < old))
        s.execute(delete(WebSessionRow).where(WebSessionRow.revoked_at < old))
        s.add(WebSessionRow(sha256=session_sha256(session_id), token_id=info.token_id, owner=info.name,
                            created_at=now, last_seen_at=now, expires_at=expires, revoked_at=None))
        s.flush()
        return WebSession(info, now, now, expires)

    return session_id, repo.storage.retrying(write)


def session_user(repo: "Repository", session_id: str | None, idle_s: float,
                 now: datetime | None = None) -> TokenInfo | None:
    """The token behind an open session, or None: unknown, malformed, closed, idle for
    ``idle_s`` or more, past its lifetime, or its token revoked or expired. Records
    the visit (``last_seen_at``, at most once a minute)."""
    if not isinstance(session_id, str) or not _SESSION.fullmatch(session_id):
        return None
    now = now or utcnow()
    digest = session_sha256(session_id)
    with read_session(repo) as s:
        found = s.execute(select(WebSessionRow, TokenRow).join(TokenRow, TokenRow.token_id == WebSessionRow.token_id)
                          .where(WebSessionRow.sha256 == digest)).first()
    if found is None:
        return None
    row, token = found
    idle_end = row.last_seen_at + timedelta(seconds=float(idle_s))
    if row.revoked_at is not None or row.expires_at <= now or idle_end <= now:
        return None
    info = _info(token)
    if info.status(now) != "active":
        return None
    if (now - row.last_seen_at).total_seconds() >= min(SESSION_TOUCH_S, float(idle_s) / 4):
        def touch(s: Session) -> None:
            s.execute(update(WebSessionRow).where(WebSessionRow.id == row.id, WebSessionRow.revoked_at.is_(None))
                      .values(last_seen_at=now))

        repo.storage.retrying(touch)
    return info


def close_session(repo: "Repository", session_id: str | None) -> bool:
    """Sign out: the session is revoked in the database (True when an open one was closed)."""
    if not isinstance(session_id, str) or not _SESSION.fullmatch(session_id):
        return False
    digest = session_sha256(session_id)

    def write(s: Session) -> bool:
        done = s.execute(update(WebSessionRow).where(WebSessionRow.sha256 == digest,
                                                     WebSessionRow.revoked_at.is_(None))
                         .values(revoked_at=utcnow()))
        return bool(done.rowcount)

    return repo.storage.retrying(write)
