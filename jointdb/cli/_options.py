"""Options spelled the same way by every command: ``--plots DIR``, ``--table``, ``--out FILE``.

One plot option: ``--plots DIR`` — a directory (created if needed) into which a
command writes its figures under fixed names (``lobes.png``, ``tip-vs-rigid.png``,
``modal-fit-overlay.png``, ...), whether it draws one figure or several. The
older spellings ``--plot FILE.png`` / ``--plot DIR/`` still work as a hidden,
deprecated alias (a note on stderr says so).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Optional

import typer

from jointdb.errors import InputError

PlotsOpt = Annotated[
    Optional[Path],
    typer.Option("--plots", metavar="DIR", help="Write the figures (PNG) into this directory (created if needed)."),
]
#: Deprecated alias of ``--plots``: a ``.png`` file (one-figure commands) or a directory.
LegacyPlotOpt = Annotated[Optional[Path], typer.Option("--plot", hidden=True)]
TableOpt = Annotated[bool, typer.Option("--table", help="Print the full table (default: a summary).")]


def plots_dir(plots: Path | None, legacy: Path | None, *, one_file: bool = False) -> Path | None:
    """The checked figure directory of ``--plots`` (or of the deprecated ``--plot``), or None.

    With ``one_file`` the deprecated ``--plot FILE.png`` names the file itself;
    use :func:`plot_file` then.

    Raises
    ------
    InputError
        Both spellings given; the path exists and is not a directory; its parent
        does not exist.
    """
    global _legacy_used
    _legacy_used = legacy is not None
    if plots is not None and legacy is not None:
        raise InputError("give --plots DIR only (--plot is its deprecated spelling)")
    if legacy is not None:
        if legacy.suffix and not legacy.is_dir():  # a file name, as --plot FILE.png took
            if legacy.suffix.lower() != ".png":
                raise InputError(f"--plot {str(legacy)!r} must end in .png (or use --plots DIR)")
            if not one_file:
                raise InputError(f"--plot {str(legacy)!r}: this command writes several figures; use --plots DIR")
            if not legacy.parent.is_dir():
                raise InputError(f"--plot {str(legacy)!r}: directory {str(legacy.parent)!r} does not exist")
            return legacy
        plots = legacy
    if plots is None:
        return None
    if plots.exists() and not plots.is_dir():
        raise InputError(f"--plots {str(plots)!r}: exists and is not a directory")
    if not plots.exists() and not plots.parent.is_dir():
        raise InputError(f"--plots {str(plots)!r}: directory {str(plots.parent)!r} does not exist")
    return plots


#: Set when the deprecated ``--plot`` was given; :func:`deprecation_note` says so once the figures are written
#: (not before: a refused command keeps its one error line).
_legacy_used = False


def deprecation_note() -> None:
    """Tell the user (stderr) that ``--plot`` is deprecated, if it was used; once."""
    global _legacy_used
    if _legacy_used:
        from jointdb.cli._output import message

        message("note: --plot is deprecated; use --plots DIR (the figures get fixed names in DIR)")
        _legacy_used = False


def plot_file(target: Path | None, name: str) -> Path | None:
    """Where a one-figure command writes its figure: ``DIR/name`` (DIR created), or the deprecated
    ``--plot FILE.png`` itself; None without a plot option. Called when the figure is drawn."""
    if target is None:
        return None
    deprecation_note()
    if target.suffix.lower() == ".png" and not target.is_dir():
        return target
    target.mkdir(parents=True, exist_ok=True)
    return target / name


def check_out(path: Path | None, suffixes: tuple[str, ...], option: str = "--out") -> None:
    """Refuse an ``--out`` file with an unknown suffix or a missing directory, before any work."""
    if path is None:
        return
    if path.suffix.lower() not in suffixes:
        raise InputError(f"{option} {str(path)!r}: unknown format {path.suffix or '(no suffix)'}; "
                         f"use {', '.join(suffixes)}")
    if not path.parent.is_dir():
        raise InputError(f"{option} {str(path)!r}: directory {str(path.parent)!r} does not exist")
    if path.is_dir():
        raise InputError(f"{option} {str(path)!r}: is a directory")
