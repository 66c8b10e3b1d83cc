"""``jointdb predict``: the 5–95 % band of the tool tip from the catalogued joints' covariance (issue 13)."""

from __future__ import annotations

from jointdb.cli._output import message


def band_for(result, n: int = 200, seed: int = 0):
    """A :class:`jointdb.stack._band.TipBand` when some chosen joint carries an uncertainty record, else None."""
    from jointdb.errors import InputError
    from jointdb.stack._band import tip_band

    from jointdb.stack._band import sampleable_uncertainties

    unc, notes = sampleable_uncertainties(result.joints)
    for note in notes:
        message(f"note: {note}")
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


def choice_sensitivity(result, db, freq, max_alternatives: int = 2) -> list[dict]:
    """How much the tip peak changes when a queried interface takes its next-nearest catalogued joints."""
    from jointdb import usecases
    from jointdb.stack import JointChoice

    base = {r["direction"]: r["peak_m_per_n"] for r in result.prediction.summary()}
    rows = []
    for name, res in result.joints.items():
        if res.kind != "query" or len(res.candidates) < 2:
            continue
        for cand_name, cand_version, dist in res.candidates[1:1 + max_alternatives]:
            spec = result.spec.replace(interfaces={
                **result.spec.interfaces, name: JointChoice("catalogued", name=cand_name, version=int(cand_version))})
            alt = usecases.predict_stack(spec, db, freq).prediction.summary()
            for r in alt:
                change = r["peak_m_per_n"] / base[r["direction"]] - 1
                rows.append({"interface": name, "alternative": f"{cand_name}@{cand_version}", "distance": dist,
                             "direction": r["direction"], "peak_m_per_n": r["peak_m_per_n"],
                             "peak_hz": r["peak_hz"], "peak_change": float(change)})
            x = [r for r in rows if r["alternative"] == f"{cand_name}@{cand_version}"][0]
            message(f"{name}: with the next candidate {cand_name}@{cand_version} (distance {dist:.3f}) the tip peak "
                    f"{x['direction']} would be {x['peak_m_per_n']:.4g} m/N ({x['peak_change']:+.1%})")
    return rows
