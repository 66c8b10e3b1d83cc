"""CLI: structural models — ``jointdb modes`` and ``jointdb frf``.

Thin: parse options, call :mod:`jointdb.fe`, render with :mod:`jointdb.cli._output`;
file writers (:mod:`jointdb.io`) and plots (:mod:`jointdb.plots._frf`) are
imported only inside the commands that need them.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Optional

import numpy as np
import typer

from jointdb.cli._options import LegacyPlotOpt, PlotsOpt, plot_file, plots_dir

from jointdb.schemas._limits import check_lines
from jointdb.errors import InputError


def _split(text: str | None) -> list[str] | None:
    if text is None:
        return None
    items = [t.strip() for t in text.split(",") if t.strip()]
    if not items:
        raise InputError(f"empty list {text!r}")
    return items


def frequency_grid(fmin: float | None, fmax: float, df: float | None, n_lines: int | None, *, avoid_zero: bool) -> np.ndarray:
    """The frequency lines [Hz] from ``--fmin/--fmax`` and ``--df`` or ``--n-lines``.

    With no ``--fmin`` the grid starts at 0 Hz, or one step above it when the
    model has rigid-body modes (``avoid_zero``).
    """
    if df is not None and n_lines is not None:
        raise InputError("give either --df or --n-lines, not both")
    if not np.isfinite(fmax) or fmax <= 0:
        raise InputError(f"--fmax must be > 0 Hz, got {fmax:g}")
    start = 0.0 if fmin is None else float(fmin)
    if not np.isfinite(start) or start < 0 or start >= fmax:
        raise InputError(f"--fmin must be in [0, fmax) = [0, {fmax:g}) Hz, got {start:g}")
    if df is not None:
        if not np.isfinite(df) or df <= 0:
            raise InputError(f"--df must be > 0 Hz, got {df:g}")
        check_lines((fmax - start) / df + 1, "--df")
        n = int(np.floor((fmax - start) / df + 1e-9)) + 1
        grid = start + df * np.arange(n)
    else:
        n = 1001 if n_lines is None else int(n_lines)
        if n < 2:
            raise InputError(f"--n-lines must be >= 2, got {n}")
        check_lines(n, "--n-lines")
        grid = np.linspace(start, fmax, n)
    if fmin is None and avoid_zero and grid[0] == 0.0:
        grid = grid[1:] if grid.size > 1 else grid + (df or fmax / 1000)
    return grid


def write_frf_file(path: Path, frf, *, binary: bool = False) -> str:
    """Write an FRF by the file's suffix (.uff/.unv, .h5/.hdf5, .csv); returns the format name.

    ``binary`` selects binary UFF58 (58b, exact) instead of ASCII.
    """
    from jointdb.usecases import frf_format
    from jointdb.usecases import write_frf_file as write

    write(path, frf, binary=binary, round_freq=False)
    return frf_format(path)


def modes_cmd(
    model_file: Annotated[Path, typer.Argument(metavar="MODEL.json", help="Beam model description (JSON).")],
    n: Annotated[int, typer.Option("--n", help="Number of lowest modes.")] = 10,
    out: Annotated[Optional[Path], typer.Option("--out", help="Write the modes to .csv, .json or .h5.")] = None,
    as_json: Annotated[bool, typer.Option("--json", help="Machine-readable output.")] = False,
) -> None:
    """Natural frequencies of a beam model (undamped), lowest first.

    Example: jointdb modes fixtures/models/end-mill-in-holder.json --n 5
    """
    from jointdb.fe import load_model

    from jointdb.cli._options import check_out

    if n < 1:
        raise InputError(f"--n must be >= 1, got {n}")
    check_out(out, (".csv", ".json", ".h5", ".hdf5"))
    model = load_model(model_file)
    modes = model.modes(n)
    from jointdb.usecases import mode_rows

    rows = mode_rows(modes)
    if out is not None:
        from jointdb.cli._output import message, write_rows

        write_rows(out, rows, kind="modes", meta={"model": model.name or model_file.name, "theory": model.theory})
        message(f"wrote {out}")
    if as_json:
        from jointdb.cli._output import emit

        emit(
            {
                "model": model.name or model_file.name,
                "kind": model.kind,
                "theory": model.theory,
                "n_dof": len(modes.dof_labels),
                "n_rigid": modes.n_rigid,
                "modes": rows,
            },
            as_json=True,
        )
        return
    from jointdb.cli._output import emit

    title = f"{model.name or model_file.name} — {model.theory}, {model.kind}, {len(modes.dof_labels)} DOF"
    emit(rows, columns=["mode", "freq_hz", "type"], title=title)


def frf_cmd(
    model_file: Annotated[Path, typer.Argument(metavar="MODEL.json", help="Beam model description (JSON).")],
    points: Annotated[Optional[str], typer.Option("--points", help="Comma-separated point names (default: all).")] = None,
    directions: Annotated[
        Optional[str], typer.Option("--directions", help="Comma-separated directions, e.g. x,ry (default: all of the model's).")
    ] = None,
    fmin: Annotated[Optional[float], typer.Option("--fmin", help="First line [Hz] (default 0, or one step above for free-free models).")] = None,
    fmax: Annotated[float, typer.Option("--fmax", help="Last line [Hz].")] = 5000.0,
    df: Annotated[Optional[float], typer.Option("--df", help="Line spacing [Hz].")] = None,
    n_lines: Annotated[Optional[int], typer.Option("--n-lines", help="Number of lines (default 1001).")] = None,
    method: Annotated[str, typer.Option("--method", help="direct | modal.")] = "direct",
    n_modes: Annotated[Optional[int], typer.Option("--n-modes", help="Modes kept by --method modal.")] = None,
    quantity: Annotated[str, typer.Option("--quantity", help="receptance | mobility | accelerance.")] = "receptance",
    out: Annotated[Optional[Path], typer.Option("--out", help="Write the FRFs: .uff (UFF58), .h5 (HDF5) or .csv.")] = None,
    binary: Annotated[
        bool, typer.Option("--binary", help="UFF58 output as binary 58b (exact; ASCII keeps 6 digits of frequency).")
    ] = False,
    plots: PlotsOpt = None,
    as_json: Annotated[bool, typer.Option("--json", help="Machine-readable summary.")] = False,
    plot: LegacyPlotOpt = None,
) -> None:
    """FRFs between named points of a beam model, to UFF58 / HDF5 / CSV and a Bode plot.

    With --plots DIR the Bode plot of the driving points is DIR/frf-bode.png.

    Example: jointdb frf fixtures/models/end-mill-in-holder.json --points tip --fmax 8000 --df 2 --out tip.uff --plots figs
    """
    from jointdb.cli._output import emit, message
    from jointdb.fe import load_model, rigid_body_count
    from jointdb.frf import Quantity

    model = load_model(model_file)
    q = Quantity.parse(quantity)
    if out is not None:
        from jointdb.usecases import frf_format

        frf_format(out, "--out")
        if not out.parent.is_dir():  # fail before the computation, not after
            raise InputError(f"--out {str(out)!r}: directory {str(out.parent)!r} does not exist")
    plot = plots_dir(plots, plot, one_file=True)
    rigid = rigid_body_count(model.assemble()) > 0
    grid = frequency_grid(fmin, fmax, df, n_lines, avoid_zero=rigid)
    if rigid and fmin is None:
        message(f"model has rigid-body modes: frequency lines start at {grid[0]:g} Hz")
    frf = model.frf(grid, points=_split(points), directions=_split(directions), method=method, n_modes=n_modes)
    frf = frf.to(q)
    summary = {
        "model": model.name or model_file.name,
        "method": method,
        "quantity": q.value,
        "lines": int(frf.n_freq),
        "fmin_hz": float(frf.freq[0]),
        "fmax_hz": float(frf.freq[-1]),
        "dofs": " ".join(str(d) for d in frf.outputs),
    }
    for d in frf.outputs:
        h = np.abs(frf.entry(d, d))
        k = int(np.argmax(h))
        summary[f"max |H[{d},{d}]|"] = f"{h[k]:.4g} at {frf.freq[k]:.6g} Hz"
    if out is not None:
        fmt = write_frf_file(out, frf, binary=binary)
        message(f"wrote {frf.n_freq} lines x {len(frf.outputs)}x{len(frf.inputs)} FRFs to {out} ({fmt})")
        summary["out"] = str(out)
    if plot is not None:
        from jointdb.plots._frf import save_bode

        plot = save_bode(plot_file(plot, "frf-bode.png"), frf, title=model.name or model_file.name)
        message(f"wrote Bode plot {plot}")
        summary["plot"] = str(plot)
    emit(summary, as_json=as_json, title="FRF synthesis")


def register(app: typer.Typer) -> None:
    """Add ``modes`` and ``frf`` to the app."""

    app.command("modes")(modes_cmd)
    app.command("frf")(frf_cmd)
