"""``jointdb predict``: the 5–95 % band of the tool tip from the catalogued joints' covariance (issue 13)."""

from __future__ import annotations

from jointdb._output import message


def band_for(result, n: int = 200, seed: int = 0):
    """A :class:`jointdb.stack._band.TipBand` when some chosen joint carries an uncertainty record, else None."""
    from jointdb.errors import InputError
    from jointdb.stack._band import tip_band

    unc = {name: r.uncertainty for name, r in result.joints.items()
           if getattr(r, "uncertainty", None) is not None and r.kind in ("catalogued", "query")}
    if not unc:
        return None
    resolved = {name: r.frf for name, r in result.joints.items() if r.frf is not None}
    try:
        b = tip_band(result.spec, resolved, unc, result.prediction.tip.freq, n=n, seed=seed)
    except InputError as exc:
        message(f"note: no band: {exc}")
        return None
    for row in b.summary():
        message(f"band ({b.samples} sampled joints of {', '.join(b.interfaces)}): tip peak {row['direction']} "
                f"{row['peak_m_per_n_p05']:.4g} – {row['peak_m_per_n_p95']:.4g} m/N (5–95 %), "
                f"{row['peak_hz_p05']:.5g} – {row['peak_hz_p95']:.5g} Hz")
    return b
