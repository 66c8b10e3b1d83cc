"""FRF figures: Bode (magnitude + phase) and Nyquist, saved as PNG (matplotlib Agg).

Imported lazily by the CLI only; the numerical core never imports matplotlib.
"""

from __future__ import annotations

import textwrap
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from jointdb.errors import InputError
from jointdb.frf import FRF, Dof
from jointdb.plots._axes import phase_deg

__all__ = ["bode_figure", "nyquist_figure", "save_bode", "save_nyquist"]

def _pyplot():
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


def _pairs(frf: FRF, pairs: Sequence[tuple] | None) -> list[tuple[Dof, Dof]]:
    if pairs is None:
        # driving points first (output == input), else the first column
        drive = [(o, o) for o in frf.outputs if o in frf.inputs]
        translational = [pair for pair in drive if not pair[0].is_rotation]
        if translational:
            return translational
        if drive:
            return drive
        return [(o, frf.inputs[0]) for o in frf.outputs]
    return [(Dof.parse(o), Dof.parse(i)) for o, i in pairs]


def _unit(frf: FRF, out: Dof, inp: Dof) -> str:
    num = "rad" if out.is_rotation else "m"
    den = "N·m" if inp.is_rotation else "N"
    return {"receptance": f"{num}/{den}", "mobility": f"{num}/({den}·s)",
            "accelerance": f"{num}/({den}·s²)"}[frf.quantity.value]


def bode_figure(
    frf: FRF,
    pairs: Sequence[tuple] | None = None,
    title: str | None = None,
    labels: Sequence[str] | None = None,
    others: Sequence[FRF] = (),
):
    """Bode plot: magnitude (log) over phase (degrees) for some FRF entries.

    Parameters
    ----------
    frf
        The FRF set.
    pairs
        ``[(output, input), ...]`` DOFs (labels like ``"1x"``); default: the
        translational driving points (all driving points if there are none).
    title
        Figure title.
    labels
        Legend labels of ``frf`` and of each of ``others`` (overlays on the same
        pairs, e.g. measured vs model).
    others
        Further FRF sets with the same DOFs to overlay.

    Returns
    -------
    matplotlib.figure.Figure
    """
    plt = _pyplot()
    sel = _pairs(frf, pairs)
    fig, (ax_m, ax_p) = plt.subplots(2, 1, sharex=True, figsize=(8, 6), height_ratios=(2, 1))
    sets = [frf, *others]
    names = list(labels) if labels is not None else [""] * len(sets)
    if len(names) != len(sets):
        raise InputError(f"{len(names)} labels for {len(sets)} FRF sets")
    for k, (data, name) in enumerate(zip(sets, names)):
        style = "-" if k == 0 else "--"
        for out, inp in sel:
            h = data.entry(out, inp)
            tag = f"H[{out},{inp}] [{_unit(data, out, inp)}]" + (f" {name}" if name else "")
            mag = np.abs(h)
            ax_m.semilogy(data.freq, np.where(mag > 0, mag, np.nan), style, label=tag, linewidth=1.2)
            ax_p.plot(*phase_deg(data.freq, h), style, linewidth=1.0)
    units = {_unit(frf, o, i) for o, i in sel}
    ax_m.set_ylabel(f"|{frf.quantity.value}|" + (f" [{units.pop()}]" if len(units) == 1 else ""))
    ax_p.set_ylabel("phase [°]")
    ax_p.set_yticks([-180, -90, 0, 90, 180])
    ax_p.set_xlabel("frequency [Hz]")
    ax_m.grid(True, which="both", alpha=0.3)
    ax_p.grid(True, alpha=0.3)
    ax_m.legend(fontsize=8, loc="best")
    if title:
        ax_m.set_title(textwrap.fill(title, 70), fontsize=10)
    fig.tight_layout()
    return fig


def nyquist_figure(frf: FRF, pairs: Sequence[tuple] | None = None, title: str | None = None):
    """Nyquist plot (real vs imaginary part) of some FRF entries.

    Parameters
    ----------
    frf
        The FRF set.
    pairs
        ``[(output, input), ...]`` DOFs; default as :func:`bode_figure`.
    title
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    plt = _pyplot()
    sel = _pairs(frf, pairs)
    fig, ax = plt.subplots(figsize=(6, 6))
    for out, inp in sel:
        h = frf.entry(out, inp)
        ax.plot(h.real, h.imag, label=f"H[{out},{inp}]", linewidth=1.2)
    out0, in0 = sel[0]
    unit = _unit(frf, out0, in0)
    ax.set_xlabel(f"real [{unit}]")
    ax.set_ylabel(f"imaginary [{unit}]")
    ax.axhline(0, color="0.6", linewidth=0.6)
    ax.axvline(0, color="0.6", linewidth=0.6)
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    if title:
        ax.set_title(textwrap.fill(title, 55), fontsize=10)
    fig.tight_layout()
    return fig


def save_figure(fig, path, dpi: int = 120) -> Path:
    """Write a figure atomically (no half-written file on failure) and close it.

    The format follows the suffix (``.png``, ``.pdf``, ``.svg``, ...). The one
    place the plot modules (FRF, coupling, stack, lobes) save figures.

    Parameters
    ----------
    fig
        A matplotlib figure (closed afterwards).
    path
        The image file.
    dpi
        Resolution of raster formats.

    Returns
    -------
    Path

    Raises
    ------
    InputError
        Unknown image suffix, or the directory does not exist.
    """
    from jointdb.io._atomic import atomic_path

    p = Path(path)
    plt = _pyplot()
    try:
        fmt = p.suffix.lower().lstrip(".")
        if fmt not in fig.canvas.get_supported_filetypes():
            raise InputError(f"plot file {str(p)!r}: unknown image type {p.suffix!r}; use .png (or .pdf, .svg)")
        with atomic_path(p) as tmp:
            fig.savefig(tmp, dpi=dpi, format=fmt)
    finally:
        plt.close(fig)
    return p


def _save(fig, path) -> Path:
    if Path(path).suffix.lower() != ".png":
        _pyplot().close(fig)
        raise InputError(f"plot file {str(path)!r} must end in .png")
    return save_figure(fig, path, dpi=120)


def save_bode(path, frf: FRF, pairs: Sequence[tuple] | None = None, title: str | None = None, **kwargs) -> Path:
    """Write a Bode plot PNG to ``path``.

    Parameters
    ----------
    path
        PNG file to write.
    frf, pairs, title
        As :func:`bode_figure`.
    **kwargs
        Further arguments of :func:`bode_figure` (``labels``, ``others``).

    Returns
    -------
    Path
    """
    return _save(bode_figure(frf, pairs, title, **kwargs), path)


def save_nyquist(path, frf: FRF, pairs: Sequence[tuple] | None = None, title: str | None = None) -> Path:
    """The Nyquist counterpart of :func:`save_bode`: :func:`nyquist_figure` written to the PNG ``path``.

    Parameters
    ----------
    path, frf, pairs, title
        As :func:`save_bode` (no overlays).

    Returns
    -------
    Path
    """
    return _save(nyquist_figure(frf, pairs, title), path)
