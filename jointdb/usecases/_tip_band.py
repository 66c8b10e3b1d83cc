"""What ``jointdb predict`` adds to a prediction, for the CLI and the API alike: the 5–95 % band of
the tool tip from the chosen joints' covariance, and how the tip changes with the next-nearest
catalogued joints (issue 13)."""

from __future__ import annotations


def tip_band_of(result, n: int = 200, seed: int = 0):
    """``(band, notes)``: a :class:`jointdb.stack._band.TipBand` when some chosen joint carries an
    uncertainty record (else None), and the notes on what was or could not be sampled.

    Parameters
    ----------
    result
        A :class:`jointdb.usecases.StackPrediction`.
    n, seed
        Sampled joint sets and the seed of the sampling.
    """
    from jointdb.errors import InputError
    from jointdb.stack._band import sampleable_uncertainties, tip_band

    unc, notes = sampleable_uncertainties(result.joints)
    notes = list(notes)
    if not unc:
        return None, notes
    resolved = {name: r.frf for name, r in result.joints.items() if r.frf is not None}
    try:
        b = tip_band(result.spec, resolved, unc, result.prediction.tip.freq, n=n, seed=seed)
    except InputError as exc:
        return None, [*notes, f"no band: {exc}"]
    for row in b.summary():
        notes.append(f"band ({b.samples} sampled joints of {', '.join(b.interfaces)}): tip peak {row['direction']} "
                     f"{row['peak_m_per_n_p05']:.4g} – {row['peak_m_per_n_p95']:.4g} m/N (5–95 %), "
                     f"{row['peak_hz_p05']:.5g} – {row['peak_hz_p95']:.5g} Hz")
    return b, notes


def choice_sensitivity(result, repo, freq, max_alternatives: int = 2) -> tuple[list[dict], list[str]]:
    """``(rows, notes)``: how much the tip peak changes when a queried interface takes its
    next-nearest catalogued joints (``repo``: a repository, URL or path, as :func:`predict_stack`)."""
    from jointdb.stack import JointChoice
    from jointdb.usecases._stack import predict_stack

    base = {r["direction"]: r["peak_m_per_n"] for r in result.prediction.summary()}
    rows, notes = [], []
    for name, res in result.joints.items():
        if res.kind != "query" or len(res.candidates) < 2:
            continue
        for cand_name, cand_version, dist in res.candidates[1:1 + max_alternatives]:
            spec = result.spec.replace(interfaces={
                **result.spec.interfaces, name: JointChoice("catalogued", name=cand_name, version=int(cand_version))})
            alt = predict_stack(spec, repo, freq).prediction.summary()
            for r in alt:
                change = r["peak_m_per_n"] / base[r["direction"]] - 1
                rows.append({"interface": name, "alternative": f"{cand_name}@{cand_version}", "distance": dist,
                             "direction": r["direction"], "peak_m_per_n": r["peak_m_per_n"],
                             "peak_hz": r["peak_hz"], "peak_change": float(change)})
            x = [r for r in rows if r["alternative"] == f"{cand_name}@{cand_version}"][0]
            notes.append(f"{name}: with the next candidate {cand_name}@{cand_version} (distance {dist:.3f}) the tip "
                         f"peak {x['direction']} would be {x['peak_m_per_n']:.4g} m/N ({x['peak_change']:+.1%})")
    return rows, notes
