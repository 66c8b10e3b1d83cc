"""``jointdb predict``: the 5–95 % band of the tool tip and the joint-choice sensitivity (issue 13),
computed by :mod:`jointdb.usecases._tip_band` (which the API's predict uses too), said on stderr."""

from __future__ import annotations

from jointdb._output import message


def band_for(result, n: int = 200, seed: int = 0):
    """A :class:`jointdb.stack._band.TipBand` when some chosen joint carries an uncertainty record, else None."""
    from jointdb.usecases._tip_band import tip_band_of

    band, notes = tip_band_of(result, n, seed)
    for note in notes:
        message(note if note.startswith("band (") else f"note: {note}")
    return band


def choice_sensitivity(result, db, freq, max_alternatives: int = 2) -> list[dict]:
    """How much the tip peak changes when a queried interface takes its next-nearest catalogued joints."""
    from jointdb.usecases._tip_band import choice_sensitivity as sensitivity

    rows, notes = sensitivity(result, db, freq, max_alternatives)
    for note in notes:
        message(note)
    return rows
