"""``jointdb predict``: the 5–95 % band of the tool tip from the catalogued joints' covariance (issue 13)."""

from __future__ import annotations

from jointdb._output import message


def band_for(result, n: int = 200, seed: int = 0):
    """``(TipBand or None, BandTerms)``: the 5–95 % band of the tip from every error term the chosen joints
    carry (measurement noise, joint choice), and each term alone; the band and which term dominates go to
    stderr, and when there is no band, the reason."""
    from jointdb.usecases._stack_band import band_terms

    terms = band_terms(result, n=n, seed=seed)
    for note in terms.notes:
        message(f"note: {note}")
    b = terms.band
    if b is None:
        return None, terms
    for row in b.summary():
        d = row["direction"]
        parts = ", ".join(f"{t} alone ±{w[d]:.1%}" for t, w in terms.half_width.items() if t != "all" and d in w)
        message(f"band ({b.samples} samples: {', '.join(b.interfaces)}): tip peak {d} "
                f"{row['peak_m_per_n_p05']:.4g} – {row['peak_m_per_n_p95']:.4g} m/N (5–95 %), "
                f"{row['peak_hz_p05']:.5g} – {row['peak_hz_p95']:.5g} Hz; {parts}")
    if terms.dominant:
        message(f"band: the dominant term is {terms.dominant}")
    return b, terms


def choice_sensitivity(result, db, freq, max_alternatives: int = 2) -> list[dict]:
    """How much the tip peak changes when a queried interface takes its next-nearest catalogued joints."""
    from jointdb import usecases
    from jointdb.stack import JointChoice

    base = {r["direction"]: r["peak_m_per_n"] for r in result.prediction.summary()}
    rows = []
    for name, res in result.joints.items():
        if res.kind not in ("query", "interpolated") or len(res.candidates) < 2:
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
            message(f"{name}: with the candidate {cand_name}@{cand_version} alone (distance {dist:.3f}) the tip peak "
                    f"{x['direction']} would be {x['peak_m_per_n']:.4g} m/N ({x['peak_change']:+.1%})")
    return rows
