"""``jointdb predict``: the 5–95 % band of the tool tip and the joint-choice sensitivity (issue 13),
computed by :mod:`jointdb.usecases._tip_band` (which the API's predict uses too), said on stderr."""

from __future__ import annotations

from jointdb.cli._output import message


def band_for(result, n: int = 200, seed: int = 0):
    """``(TipBand or None, BandTerms)``: the 5–95 % band of the tip from every error term the chosen joints
    carry (:data:`jointdb.usecases._stack_band.TERMS`), and each term alone; the band and which term
    dominates go to stderr, and when there is no band, the reason (:func:`jointdb.usecases._tip_band.tip_band_of`)."""
    from jointdb.usecases._tip_band import tip_band_of

    band, terms, notes = tip_band_of(result, n, seed)
    for note in notes:
        message(note if note.startswith("band") else f"note: {note}")
    return band, terms


def choice_sensitivity(result, db, freq, max_alternatives: int = 2) -> list[dict]:
    """How much the tip peak changes when a queried interface takes its next-nearest catalogued joints."""
    from jointdb.usecases._tip_band import choice_sensitivity as sensitivity

    rows, notes = sensitivity(result, db, freq, max_alternatives)
    for note in notes:
        message(note)
    return rows
