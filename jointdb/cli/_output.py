"""The one output module all CLI commands use.

Results go to stdout: a short summary or a table for people (every column
header names its unit), JSON in SI units for scripts (``--json``), and data
files by suffix (``--out``: :func:`write_rows`). Messages and progress go to
stderr: a progress bar on a terminal, one plain line per step (count, elapsed
time, ETA) when stderr is a pipe or a log. ``-v``/``-q`` set the level of the
standard :mod:`logging` tree ``jointdb`` (:func:`configure_logging`); library
modules log through ``logging.getLogger(__name__)`` and never print.
"""

from __future__ import annotations

import json
import logging
import math
import sys
import time
from collections.abc import Iterable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any, TypeVar

T = TypeVar("T")


#: Column-name suffixes of SI quantities and the unit shown in table headers (longest first).
_SUFFIX_UNITS = (
    ("_nms_per_rad", "N·m·s/rad"), ("_nm_per_rad", "N·m/rad"), ("_ns_per_m", "N·s/m"), ("_n_per_m", "N/m"),
    ("_m_per_n", "m/N"), ("_hz", "Hz"), ("_rpm", "rpm"), ("_mm", "mm"), ("_nm", "N·m"), ("_n", "N"),
    ("_m", "m"), ("_s", "s"), ("_deg", "°"), ("_pct", "%"),
)


def header(column: str) -> str:
    """Table header of a column: the unit suffix of an SI name written out, ``"depth_mm"`` →
    ``"depth [mm]"``, ``"spindle_speed_rpm"`` → ``"spindle_speed [rpm]"`` (the name stays as in ``--json``).

    Names without a unit suffix, per-condition distances ``d_*`` (dimensionless) and
    names already holding a unit (``"peak (Hz)"``, ``"k [N/m]"``) are kept as they are.
    """
    if column.startswith("d_") or "[" in column or "(" in column:
        return column
    for suffix, unit in _SUFFIX_UNITS:
        if column.endswith(suffix) and len(column) > len(suffix):
            return f"{column[: -len(suffix)]} [{unit}]"
    return column


def _fmt(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.6g}"
    if value is None:
        return "-"
    if isinstance(value, (list, tuple)) and all(isinstance(v, (int, float)) for v in value):
        return " – ".join(_fmt(v) for v in value) if len(value) == 2 else ", ".join(_fmt(v) for v in value)
    return str(value)


def _cell(text: str, markdown: bool = False):
    """A table cell taken literally (``[mm]`` is a unit, not rich markup); ``|`` escaped in a Markdown table."""
    from rich.text import Text

    return Text(text.replace("|", "\\|") if markdown else text)


def _title(title: str | None):
    """A table title taken literally, like a cell (``[/]`` in a name is text, not rich markup), in Rich's title style."""
    from rich.text import Text

    return None if title is None else Text(title, style="table.title")


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
        from jointdb.io._jsonable import to_jsonable  # here: the table path stays numpy- and io-free

        sys.stdout.write(json.dumps(to_jsonable(data), indent=2) + "\n")
        return
    if not isinstance(data, str) and not sys.stdout.isatty():  # the same Markdown table, without Rich if simple
        data = data if isinstance(data, Mapping) else list(data)
        text = _markdown_table(data, columns, title)
        if text is not None:
            sys.stdout.write(text)
            return
    from rich.console import Console
    from rich.table import Table

    # piped or logged output is not cut to 80 columns: tables keep their full cells
    # and is plain text: a Markdown table (ASCII, reads in a log and renders in a notebook)
    tty = sys.stdout.isatty()
    width = None if tty else 10_000
    console = Console(file=sys.stdout, soft_wrap=True, width=width)
    from rich import box

    style = {} if tty else {"box": box.MARKDOWN}
    if isinstance(data, str):
        console.print(data, highlight=False, markup=False)
        return
    if isinstance(data, Mapping):
        table = Table(title=_title(title), show_header=not tty, **style)
        table.add_column("field", style="bold")
        table.add_column("value")
        for key, value in data.items():
            table.add_row(_cell(header(str(key)), not tty), _cell(_fmt(value), not tty))
        console.print(table)
        return
    rows = list(data)
    if not rows:
        console.print("(no rows)", highlight=False)
        return
    cols = list(columns) if columns else list(rows[0].keys())
    table = Table(title=_title(title), **style)
    for col in cols:
        table.add_column(_cell(header(col), not tty), overflow="fold")
    for row in rows:
        table.add_row(*(_cell(_fmt(row.get(col)), not tty) for col in cols))
    console.print(table)


def _markdown_table(data: Any, columns: Sequence[str] | None, title: str | None) -> str | None:
    """What :func:`emit` prints for piped output via Rich, from :mod:`jointdb.cli._mdtable` (None: ask Rich)."""
    from jointdb.cli._mdtable import render

    def esc(text: str) -> str:
        return text.replace("|", "\\|")

    if isinstance(data, Mapping):
        return render(title, ["field", "value"], [(esc(header(str(k))), esc(_fmt(v))) for k, v in data.items()])
    if not data:
        return "(no rows)\n"
    cols = list(columns) if columns else list(data[0].keys())
    return render(title, [esc(header(c)) for c in cols], [[esc(_fmt(r.get(c))) for c in cols] for r in data])


def message(text: str) -> None:
    """Write a message for people to stderr (under ``-q`` only warnings and errors)."""
    if _QUIET and not text.lstrip().lower().startswith(("warning", "error")):
        return
    sys.stderr.write(text.rstrip("\n") + "\n")


def _seconds(t: float) -> str:
    t = max(0.0, t)
    if t < 90:
        return f"{t:.0f} s"
    if t < 5400:
        return f"{t / 60:.1f} min"
    return f"{t / 3600:.1f} h"


def progress_line(description: str, done: int, total: int | None, elapsed: float) -> str:
    """One plain progress line: ``"lobes (SD): 5/25 (20%), 3 s elapsed, ETA 12 s"``."""
    if not total:
        return f"{description}: {done} done, {_seconds(elapsed)} elapsed"
    eta = elapsed / done * (total - done) if done else float("nan")
    eta_txt = _seconds(eta) if math.isfinite(eta) else "?"
    return f"{description}: {done}/{total} ({100 * done / total:.0f}%), {_seconds(elapsed)} elapsed, ETA {eta_txt}"


def progress(
    items: Iterable[T], *, total: int | None = None, description: str = "", min_interval_s: float = 5.0,
) -> Iterator[T]:
    """Iterate with progress on stderr.

    On a terminal: a transient rich progress bar. Otherwise (pipe, log file, CI):
    one plain line per finished item with the count, elapsed time and ETA — at
    most one line per ``min_interval_s`` seconds and per 5 % of ``total``, plus
    the first and the last. Nothing under ``-q``.
    """
    if total is None and hasattr(items, "__len__"):
        total = len(items)  # type: ignore[arg-type]
    if _QUIET:
        yield from items
        return
    if sys.stderr.isatty():
        from rich.progress import track

        yield from track(items, total=total, description=description, console=_stderr_console(), transient=True)
        return
    start = last = time.monotonic()
    step = max(1, (total or 0) // 20)
    done = 0
    for item in items:
        yield item
        done += 1
        now = time.monotonic()
        if done == 1 or done == total or (done % step == 0 and now - last >= min_interval_s) \
                or now - last >= 6 * min_interval_s:
            last = now
            sys.stderr.write(progress_line(description or "progress", done, total, now - start) + "\n")
            sys.stderr.flush()


#: Set by ``-q``: messages other than warnings and errors, and progress, are not written.
_QUIET = False


def configure_logging(verbose: int = 0, quiet: bool = False) -> None:
    """Set up the ``jointdb`` logger tree for the CLI (``-v``: INFO, ``-vv``: DEBUG, ``-q``: ERROR).

    Records go to stderr as ``LEVEL name: message``; the default level is WARNING.
    """
    global _QUIET
    _QUIET = bool(quiet)
    level = logging.ERROR if quiet else logging.DEBUG if verbose >= 2 else logging.INFO if verbose == 1 \
        else logging.WARNING
    logger = logging.getLogger("jointdb")
    logger.setLevel(level)
    if not any(isinstance(h, _StderrHandler) for h in logger.handlers):
        handler = _StderrHandler()
        handler.setFormatter(logging.Formatter("%(levelname)s %(name)s: %(message)s"))
        logger.addHandler(handler)


class _StderrHandler(logging.StreamHandler):
    """A stream handler writing to whatever ``sys.stderr`` is at each record (redirections, test runners)."""

    @property
    def stream(self):  # type: ignore[override]
        return sys.stderr

    @stream.setter
    def stream(self, value) -> None:
        pass


def write_rows(path: Path, rows: Sequence[Mapping[str, Any]], *, columns: Sequence[str] | None = None,
               meta: Mapping[str, Any] | None = None, kind: str = "table") -> Path:
    """Write table rows (SI values, unit-suffixed column names) to ``path``, format by suffix.

    ``.csv``: a header line of the column names, one line per row. ``.json``:
    ``{"kind", "meta", "columns", "rows"}``. ``.h5``/``.hdf5``: one dataset per
    column under ``/<kind>`` and ``meta`` as JSON in the group's ``meta``
    attribute. Written atomically (whole or not at all).

    Raises
    ------
    InputError
        Unknown suffix, or the directory does not exist.
    """
    import numpy as np

    from jointdb.errors import InputError
    from jointdb.io._atomic import atomic_path
    from jointdb.io._jsonable import to_jsonable

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".csv", ".json", ".h5", ".hdf5"):
        raise InputError(f"--out {str(path)!r}: unknown format {suffix or '(no suffix)'}; use .csv, .json or .h5")
    if not path.parent.is_dir():
        raise InputError(f"--out {str(path)!r}: directory {str(path.parent)!r} does not exist")
    rows = list(rows)
    cols = list(columns) if columns else (list(rows[0].keys()) if rows else [])
    with atomic_path(path) as tmp:
        if suffix == ".csv":
            import csv

            with tmp.open("w", newline="", encoding="utf-8") as fh:
                writer = csv.writer(fh)
                writer.writerow(cols)
                for row in rows:
                    writer.writerow(["" if row.get(c) is None else row.get(c) for c in cols])
        elif suffix == ".json":
            doc = {"kind": kind, "meta": dict(meta or {}), "columns": cols,
                   "rows": [{c: row.get(c) for c in cols} for row in rows]}
            tmp.write_text(json.dumps(to_jsonable(doc), indent=1) + "\n", encoding="utf-8")
        else:
            import h5py

            with h5py.File(tmp, "w") as fh:
                grp = fh.create_group(kind)
                grp.attrs["meta"] = json.dumps(to_jsonable(dict(meta or {})))
                grp.attrs["columns"] = json.dumps(cols)
                for c in cols:
                    values = [row.get(c) for row in rows]
                    if all(isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool)
                           for v in values):
                        grp.create_dataset(c, data=np.asarray(values, dtype=float))
                    else:
                        grp.create_dataset(c, data=np.asarray(["" if v is None else str(v) for v in values],
                                                              dtype=h5py.string_dtype()))
    return path


def _stderr_console():
    from rich.console import Console

    return Console(file=sys.stderr)
