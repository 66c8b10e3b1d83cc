"""What ``jointdb predict`` adds to a prediction, for the CLI and the API alike: the 5–95 % band of
the tool tip from the chosen joints' covariance, and how the tip changes with the next-nearest
catalogued joints (issue 13)."""

from __future__ import annotations


def tip_band_of(result, n: int = 200, seed: int = 0):
    """``(band, terms, notes)``: the 5–95 % band of the tool tip from every error term the prediction
    carries — measurement noise, joint choice (leave-one-out over the catalogue), the damping law of joints kept
    as constant k, c away from the frequency they were identified at, the spindle's estimate
    from extension-bar taps, the substructure model's error shown by validation assemblies and the prediction
    path's model error (:func:`jointdb.usecases._stack_band.band_terms`) — each term alone, and the
    notes that say what was sampled, which terms are 0 and why, which term dominates, or why there is no band.

    Parameters
    ----------
    result
        A :class:`jointdb.usecases.StackPrediction`.
    n
        Number of sampled joint sets.
    seed
        Seed of the sampling.

    Returns
    -------
    tuple
        ``(TipBand or None, BandTerms, list of str)``.
    """
    from jointdb.usecases._stack_band import band_terms

    terms = band_terms(result, n=n, seed=seed)
    notes = list(terms.notes)
    b = terms.band
    if b is None:
        return None, terms, notes
    for row in b.summary():
        d = row["direction"]
        parts = ", ".join(f"{t} alone ±{w[d]:.1%}" for t, w in terms.half_width.items() if t != "all" and d in w)
        notes.append(f"band ({b.samples} samples of {b.sources}): tip peak {d} "
                     f"{row['peak_m_per_n_p05']:.4g} – {row['peak_m_per_n_p95']:.4g} m/N (5–95 %), "
                     f"{row['peak_hz_p05']:.5g} – {row['peak_hz_p95']:.5g} Hz; {parts}")
    for term, why in (terms.zero or {}).items():
        notes.append(f"band: {term} 0 — {why}")
    if terms.dominant:
        notes.append(f"band: the dominant term is {terms.dominant}")
    return b, terms, notes


def choice_sensitivity(result, repo, freq, max_alternatives: int = 2) -> tuple[list[dict], list[str]]:
    """``(rows, notes)``: how much the tip peak changes when a queried interface takes its
    next-nearest catalogued joints (``repo``: a repository, URL or path, as :func:`predict_stack`)."""
    from jointdb.stack import JointChoice
    from jointdb.usecases._stack import predict_stack

    base = {r["direction"]: r["peak_m_per_n"] for r in result.prediction.summary()}
    rows, notes = [], []
    for name, res in result.joints.items():
        if res.kind not in ("query", "interpolated") or len(res.candidates) < 2:
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
            notes.append(f"{name}: with the candidate {cand_name}@{cand_version} alone (distance {dist:.3f}) the tip "
                         f"peak {x['direction']} would be {x['peak_m_per_n']:.4g} m/N ({x['peak_change']:+.1%})")
    return rows, notes
