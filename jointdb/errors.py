"""The one small exception hierarchy of jointdb.

Every error a user can cause derives from :class:`JointdbError`. The CLI maps
each class to an exit code and one line on stderr; another front end maps them
its own way (e.g. to status codes). Input errors are also ``ValueError`` so that library users can
catch them the ordinary way.
"""

from __future__ import annotations


class JointdbError(Exception):
    """Base class of all errors jointdb raises on purpose."""

    exit_code = 1
    http_status = 500


class InputError(JointdbError, ValueError):
    """Bad input: a file, an array, an option or a field that is wrong."""

    exit_code = 2
    http_status = 422


class NotFoundError(JointdbError, LookupError):
    """A joint, version, label, blob or file that does not exist."""

    exit_code = 3
    http_status = 404


class ConflictError(JointdbError):
    """A write that would overwrite or contradict what is already stored."""

    exit_code = 4
    http_status = 409


class IntegrityError(JointdbError):
    """Stored data failed verification (missing or corrupt blob, bad hash)."""

    exit_code = 5
    http_status = 500


class NumericalError(JointdbError, ArithmeticError):
    """A computation that cannot give a trustworthy answer (singular system, ...)."""

    exit_code = 6
    http_status = 422


class NotPermittedError(JointdbError, PermissionError):
    """A valid token whose owner may not do this (e.g. label a joint another team catalogued)."""

    exit_code = 2
    http_status = 403
