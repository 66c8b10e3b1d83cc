"""The one output module all CLI commands use.

Results go to stdout: a table for people, JSON for scripts (``--json``).
Messages and progress bars go to stderr; progress is shown only on a terminal.
"""

from __future__ import annotations

import dataclasses
import enum
import json
import math
import sys
from collections.abc import Iterable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

T = TypeVar("T")


def to_jsonable(obj: Any) -> Any:
    """Convert numpy scalars/arrays, dataclasses, enums, paths and complex numbers to JSON types."""
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return {f.name: to_jsonable(getattr(obj, f.name)) for f in dataclasses.fields(obj)}
    if isinstance(obj, Mapping):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, enum.Enum):
        return obj.value
    if isinstance(obj, Path):
        return str(obj)
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, (np.floating, float)):
        value = float(obj)
        return value if math.isfinite(value) else None
    if isinstance(obj, (complex, np.complexfloating)):
        return {"re": to_jsonable(obj.real), "im": to_jsonable(obj.imag)}
    if isinstance(obj, (np.bool_,)):
        return bool(obj)
    if isinstance(obj, (list, tuple, set, frozenset)):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, (str, int, bool)) or obj is None:
        return obj
    return str(obj)


def _fmt(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.6g}"
    if value is None:
        return "-"
    return str(value)


def emit(
    data: Any,
    *,
    as_json: bool = False,
    columns: Sequence[str] | None = None,
    title: str | None = None,
) -> None:
    """Write a command's result to stdout.

    Parameters
    ----------
    data
        A list of row mappings (rendered as a table), a mapping (rendered as a
        two-column key/value table) or a string.
    as_json
        Write ``json.dumps(data)`` instead of a table.
    columns
        Column order for a list of rows (default: keys of the first row).
    title
        Optional table title (ignored for JSON).
    """
    if as_json:
        sys.stdout.write(json.dumps(to_jsonable(data), indent=2) + "\n")
        return
    from rich.console import Console
    from rich.table import Table

    # piped or logged output is not cut to 80 columns: tables keep their full cells
    width = None if sys.stdout.isatty() else 10_000
    console = Console(file=sys.stdout, soft_wrap=True, width=width)
    if isinstance(data, str):
        console.print(data, highlight=False, markup=False)
        return
    if isinstance(data, Mapping):
        table = Table(title=title, show_header=False)
        table.add_column("field", style="bold")
        table.add_column("value")
        for key, value in data.items():
            table.add_row(str(key), _fmt(value))
        console.print(table)
        return
    rows = list(data)
    if not rows:
        console.print("(no rows)", highlight=False)
        return
    cols = list(columns) if columns else list(rows[0].keys())
    table = Table(title=title)
    for col in cols:
        table.add_column(col)
    for row in rows:
        table.add_row(*(_fmt(row.get(col)) for col in cols))
    console.print(table)


def message(text: str) -> None:
    """Write a message for people to stderr."""
    sys.stderr.write(text.rstrip("\n") + "\n")


def progress(items: Iterable[T], *, total: int | None = None, description: str = "") -> Iterator[T]:
    """Iterate with a progress bar on stderr when stderr is a terminal; silently otherwise."""
    if not sys.stderr.isatty():
        yield from items
        return
    from rich.progress import track

    yield from track(items, total=total, description=description, console=_stderr_console(), transient=True)


def _stderr_console():
    from rich.console import Console

    return Console(file=sys.stderr)
