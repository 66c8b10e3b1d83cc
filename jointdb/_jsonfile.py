"""Reading the project's JSON description files (models, stacks, campaigns) with one set of errors.

Plain standard library: the numerical core's file loaders may use it without
pulling in any I/O library.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

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
        If it cannot be read, is not UTF-8 text, or is not valid JSON (with line and column).
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise NotFoundError(f"{what} {str(p)!r} does not exist") from None
    except UnicodeDecodeError:
        raise InputError(f"{what} {p}: not a UTF-8 text file") from None
    except OSError as exc:
        raise InputError(f"cannot read {what} {p}: {exc.strerror or exc}") from None
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(f"{what} {p}: not valid JSON (line {exc.lineno}, column {exc.colno}: {exc.msg})") from None
