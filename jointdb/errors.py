"""The one small exception hierarchy of jointdb.

Every error a user can cause derives from :class:`JointdbError`. The CLI maps
each class to an exit code and one line on stderr; another front end maps them
its own way (e.g. to status codes). Input errors are also ``ValueError`` so that library users can
catch them the ordinary way.
"""

from __future__ import annotations


class JointdbError(Exception):
    """Base class of all errors jointdb raises on purpose.

    Each kind states its CLI exit code and HTTP status in its class line:
    ``class InputError(JointdbError, ValueError, exit_code=2, http_status=422)``.
    """

    exit_code = 1
    http_status = 500

    def __init_subclass__(cls, *, exit_code: int | None = None, http_status: int | None = None, **kwargs) -> None:
        super().__init_subclass__(**kwargs)
        if exit_code is not None:  # a subclass that names none keeps its parent's
            cls.exit_code = exit_code
        if http_status is not None:
            cls.http_status = http_status


class InputError(JointdbError, ValueError, exit_code=2, http_status=422):
    """Bad input: a file, an array, an option or a field that is wrong."""


class NotFoundError(JointdbError, LookupError, exit_code=3, http_status=404):
    """A joint, version, label, blob or file that does not exist."""


class ConflictError(JointdbError, exit_code=4, http_status=409):
    """A write that would overwrite or contradict what is already stored."""


class IntegrityError(JointdbError, exit_code=5, http_status=500):
    """Stored data failed verification (missing or corrupt blob, bad hash)."""


class NumericalError(JointdbError, ArithmeticError, exit_code=6, http_status=422):
    """A computation that cannot give a trustworthy answer (singular system, ...)."""


class NotPermittedError(JointdbError, PermissionError, exit_code=2, http_status=403):
    """A valid token whose owner may not do this (e.g. label a joint another team catalogued)."""


def field_error(where: str, reason: str) -> InputError:
    """The :class:`InputError` for one field of a file or document: ``"{where}: {reason}"``.

    Parameters
    ----------
    where
        The field's path, e.g. ``"tool.segments[1].length"``.
    reason
        What is wrong, e.g. ``"must be > 0, got -0.01"``.

    Returns
    -------
    InputError
        To be raised by the caller.
    """
    return InputError(f"{where}: {reason}")
