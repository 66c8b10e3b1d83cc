"""Say when the tool tip's dominant mode may lie outside the lines predicted (issue 22).

A prediction only knows the lines it was asked for: when the largest |H| of the tip is on the first or the last
line, what is called the "dominant peak" is the flank of a mode below or above the grid, and the lobes computed
from it miss that mode. The same holds for the band when its samples' dominant-peak frequencies reach an edge.
One wording for the CLI (text and ``--json``), the API and the band: :func:`edge_note`.
"""

from __future__ import annotations

import numpy as np

#: Share of the band's samples whose dominant |H| is on an edge line from which the band says so: about where its
#: 5 % / 95 % quantile of the dominant-peak frequency reaches that line.
BAND_EDGE_SHARE = 0.05

_SIDE = {"first": ("below", "lower frequency.min (--fmin)"), "last": ("above", "extend frequency.max (--fmax)")}


def edge_note(direction: str, edge: str, freq_hz: float, share: float | None = None) -> str:
    """The note for a dominant |H| on an edge line.

    Parameters
    ----------
    direction
        The tip direction, ``"x"`` or ``"y"``.
    edge
        ``"first"`` or ``"last"``.
    freq_hz
        That line's frequency [Hz].
    share
        For the band: the share of its samples (0–1) whose dominant |H| is there; None for the nominal tip.

    Returns
    -------
    str
    """
    side, fix = _SIDE[edge]
    where = "" if share is None else f" in {share:.0%} of the band's samples"
    return (f"{'band: ' if share is not None else ''}the largest |H| of the tip ({direction}) is at the {edge} line "
            f"predicted ({freq_hz:g} Hz){where}: a mode may lie {side} it; {fix} (the catalogued joints' lines "
            f"allowing)")


def _edge_index(freq: np.ndarray, mag: np.ndarray) -> np.ndarray:
    """Per row of ``mag`` (``(..., n_freq)``): 0 for a dominant |H| on the first line, 1 on the last, -1 inside."""
    k = np.argmax(mag, axis=-1)
    return np.where(k == 0, 0, np.where(k == freq.size - 1, 1, -1))


def tip_edge_notes(tip) -> tuple[str, ...]:
    """Notes for every direction whose largest tip |H| is on the first or last line of ``tip``.

    Parameters
    ----------
    tip
        The predicted tip receptance (:class:`jointdb.frf.FRF`, values ``(n_freq, n_out, n_in)``; the diagonal
        terms are the directions).

    Returns
    -------
    tuple of str
        One note per direction at an edge; empty when every dominant |H| lies inside the lines.
    """
    f = np.asarray(tip.freq, dtype=float)
    if f.size < 3:
        return ()
    n = min(tip.values.shape[1], tip.values.shape[2])
    mags = np.abs(tip.values[:, np.arange(n), np.arange(n)]).T  # (n_dir, n_freq)
    out = []
    for dof, e in zip(tip.outputs[:n], _edge_index(f, mags)):
        if e >= 0:
            edge = ("first", "last")[e]
            out.append(edge_note(dof.direction, edge, float(f[0] if e == 0 else f[-1])))
    return tuple(out)


def band_edge_notes(band, tip=None) -> tuple[str, ...]:
    """Notes for every direction where at least :data:`BAND_EDGE_SHARE` of the band's samples have their dominant
    |H| on the first or last line (about where the band's 5 % or 95 % dominant-peak frequency reaches it), unless
    the nominal ``tip`` already is there (its note says so).

    Parameters
    ----------
    band
        A :class:`jointdb.stack.TipBand` (``tips[direction]``: ``(samples, n_freq)``), or None.
    tip
        The nominal tip receptance (:class:`jointdb.frf.FRF`), or None.

    Returns
    -------
    tuple of str
    """
    if band is None:
        return ()
    f = np.asarray(band.freq, dtype=float)
    if f.size < 3:
        return ()
    said = set(tip_edge_notes(tip)) if tip is not None else set()
    out = []
    for direction, samples in band.tips.items():
        e = _edge_index(f, np.abs(np.asarray(samples)))
        for k, edge in enumerate(("first", "last")):
            share = float(np.mean(e == k))
            line = float(f[0] if k == 0 else f[-1])
            if share >= BAND_EDGE_SHARE and edge_note(direction, edge, line) not in said:
                out.append(edge_note(direction, edge, line, share))
    return tuple(out)
