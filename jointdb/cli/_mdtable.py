"""The Markdown table of piped output, written without Rich when that is safe (start-up time).

:func:`jointdb.cli._output.emit` prints tables with Rich; when stdout is not a terminal the
table is a Markdown table (``box.MARKDOWN``, no width limit) and Rich adds no colour.
Importing Rich costs a one-shot command like ``jointdb query`` a sixth of its start-up,
so this module writes the same text for the cases where it is simple: every character
one terminal cell wide (the ASCII and Latin-1 ranges and a few typographic marks; Rich
measures others with its own tables), no line breaks or tabs in a cell, a title without
Rich markup or emoji codes, and no environment variable that makes Rich emit colour.
Otherwise :func:`render` returns None and Rich renders the table. A test compares the
two on generated tables.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Sequence

#: characters beyond U+02FF that Rich also counts as one cell (a test checks each)
_NARROW = frozenset("–—‘’“”…•€™")
#: environment variables with which Rich may write colour or terminal codes to a pipe
_RICH_ENV = ("FORCE_COLOR", "TTY_COMPATIBLE", "TTY_INTERACTIVE", "JUPYTER_COLUMNS", "JUPYTER_LINES")
#: the console width :func:`jointdb.cli._output.emit` gives Rich for piped output
WIDTH = 10_000


def _simple(text: str) -> bool:
    return all((ch < "\u0300" or ch in _NARROW) and ch.isprintable() for ch in text)


def _simple_title(title: str) -> bool:
    return _simple(title) and "[" not in title and ":" not in title


def render(title: str | None, headers: Sequence[str], rows: Sequence[Sequence[str]]) -> str | None:
    """The Markdown table Rich prints for ``title``, ``headers`` and ``rows`` (cell texts as
    Rich gets them, ``|`` already escaped), or None when this module does not write it."""
    if any(k in os.environ for k in _RICH_ENV) or "IPython" in sys.modules:
        return None
    if title is not None and not _simple_title(title):
        return None
    cells = [list(headers), *(list(r) for r in rows)]
    if not headers or any(len(r) != len(headers) or not all(_simple(t) for t in r) for r in cells):
        return None
    widths = [max(len(r[i]) for r in cells) for i in range(len(headers))]
    total = sum(widths) + 3 * len(widths) + 1
    if total > WIDTH:
        return None
    edge = " " * total
    lines = [title] if title else []
    lines.append(edge)
    lines.append("| " + " | ".join(h.ljust(w) for h, w in zip(headers, widths)) + " |")
    lines.append("|" + "|".join("-" * (w + 2) for w in widths) + "|")
    lines.extend("| " + " | ".join(t.ljust(w) for t, w in zip(r, widths)) + " |" for r in cells[1:])
    lines.append(edge)
    return "\n".join(lines) + "\n"
