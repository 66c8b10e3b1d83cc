"""Reading the project's JSON description files (models, stacks, campaigns) with one set of errors.

Plain standard library: the numerical core's file loaders may use it without
pulling in any I/O library.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

from jointdb.schemas._limits import MAX_JSON_BYTES, check_json_numbers, check_json_text
from jointdb.errors import InputError, NotFoundError


def read_json_file(path: str | os.PathLike, what: str) -> Any:
    """Parsed content of a JSON file.

    Parameters
    ----------
    path
        The file.
    what
        What the file is, for messages (e.g. ``"model file"``).

    Raises
    ------
    NotFoundError
        If the file does not exist.
    InputError
        If it cannot be read, is not UTF-8 text, is not valid JSON (with line and column), or
        exceeds a limit of :mod:`jointdb.schemas._limits` (size, nesting depth, a number that is NaN,
        infinite or beyond ±1e300).
    """
    p = Path(path)
    try:
        size = p.stat().st_size
        if size > MAX_JSON_BYTES:
            raise InputError(f"{what} {p}: {size} bytes; the limit is {MAX_JSON_BYTES} "
                             "(a description file is a few kilobytes)")
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise NotFoundError(f"{what} {str(p)!r} does not exist") from None
    except UnicodeDecodeError:
        raise InputError(f"{what} {p}: not a UTF-8 text file") from None
    except OSError as exc:
        raise InputError(f"cannot read {what} {p}: {exc.strerror or exc}") from None
    check_json_text(text, f"{what} {p}")
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(f"{what} {p}: not valid JSON (line {exc.lineno}, column {exc.colno}: {exc.msg})") from None
    except (ValueError, RecursionError) as exc:
        if "digits" in str(exc):  # Python refuses integers of more than 4300 digits
            raise InputError(f"{what} {p}: holds an integer of more than 4300 digits; not a description file") from None
        raise InputError(f"{what} {p}: not readable JSON ({exc})") from None
    try:
        check_json_numbers(data)
    except InputError as exc:
        raise InputError(f"{what} {p}: {exc}") from None
    return data
