"""Database errors a user can cause or meet, as one-line jointdb errors.

:func:`translate_error` maps a driver exception (no server, no driver, a damaged
SQLite file, a refusal by the immutability guards) to the project's error
classes; :func:`db_errors` and :func:`with_db_errors` apply it around a block or
a method. URLs in messages never show a password (:func:`safe_url`).
"""

from __future__ import annotations

import contextlib
import functools
import re

from sqlalchemy.engine import make_url
from sqlalchemy.exc import ArgumentError, DBAPIError, NoSuchModuleError

from jointdb.errors import ConflictError, InputError, IntegrityError, JointdbError


def safe_url(url: str) -> str:
    """The URL with any password hidden (for messages)."""
    try:
        return make_url(url).render_as_string(hide_password=True)
    except (ArgumentError, ValueError):
        return re.sub(r"(://[^:/@]*:)[^@]*@", r"\1***@", url)


def translate_error(exc: BaseException, url: str | None = None) -> JointdbError:
    """A one-line jointdb error for a database-level exception.

    - a refusal by the immutability guards (message starting ``jointdb:``) -> ConflictError;
    - a damaged SQLite file (``malformed``, ``not a database``) -> IntegrityError;
    - no server, no such database, cannot open the file, no driver -> InputError;
    - anything else -> JointdbError (exit 1) with the driver's first line.
    """
    where = f"database {safe_url(url)}" if url else "database"
    if isinstance(exc, JointdbError):
        return exc
    if isinstance(exc, ImportError):
        name = getattr(exc, "name", "") or ""
        if "psycopg" in name or "psycopg" in str(exc):
            return InputError('PostgreSQL support is not installed: pip install "jointdb[postgres]" '
                              "(and use a postgresql+psycopg:// URL)")
        return InputError(f"{where}: the database driver cannot be imported ({exc})")
    if isinstance(exc, NoSuchModuleError):
        return InputError(f"{where}: unknown database driver ({exc}); use sqlite:/// or postgresql+psycopg://")
    orig = getattr(exc, "orig", None) or exc
    text = str(orig).strip().splitlines()[0] if str(orig).strip() else type(orig).__name__
    low = text.lower()
    if "jointdb:" in low:
        return ConflictError(text[low.index("jointdb:"):])
    if "malformed" in low or "not a database" in low or "disk i/o error" in low:
        return IntegrityError(f"{where} is damaged ({text}); restore it from a backup")
    if isinstance(exc, DBAPIError) and exc.connection_invalidated or any(
        s in low for s in ("connection", "could not connect", "unable to open database", "does not exist",
                           "timeout expired", "password authentication", "could not translate host")
    ):
        return InputError(f"cannot open {where}: {text}")
    return JointdbError(f"{where}: {text}")


@contextlib.contextmanager
def db_errors(url: str | None = None):
    """Turn database-level exceptions raised inside into jointdb errors (:func:`translate_error`)."""
    try:
        yield
    except (DBAPIError, NoSuchModuleError, ImportError) as exc:
        raise translate_error(exc, url) from None


def with_db_errors(method):
    """Method decorator: :func:`db_errors` with ``self.url``."""

    @functools.wraps(method)
    def wrapper(self, *args, **kwargs):
        with db_errors(getattr(self, "url", None)):
            return method(self, *args, **kwargs)

    return wrapper


