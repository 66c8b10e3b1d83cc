"""The main job's bands: tool-tip and lobe percentiles from the chosen joints' covariance, the joint-choice
error estimated from the catalogue by leave-one-out, the peak's sensitivity to where the chosen tool–holder joint's
features sit, the damping law of constant k, c joints away from their
campaigns' modes, the spindle's estimate and the substructure model's error shown by the campaigns' assemblies,
when there are any, and the prediction path (issues 13 and 22)."""

from __future__ import annotations

from collections.abc import Callable

N_TIP_SAMPLES = 200
N_LOBE_SAMPLES = 100


def journey_bands(spec, resolutions, grid, say: Callable[[str], None], lobe_grid=None):
    """``(TipBand | None, make_lobe_band | None, summary dict)`` for the stack's queried/pinned joints.

    The tip band is sampled on ``grid`` (the nominal prediction's lines).
    ``make_lobe_band(cut, speeds)`` computes the lobe band from ``N_LOBE_SAMPLES`` sampled
    tips (ZOA per sample) on ``lobe_grid`` (default ``grid``): give it the lines and speeds the
    nominal lobes use, so that band and nominal limit are computed alike.
    """
    from jointdb.stability._band import milling_lobes_band
    from jointdb.stack import predict_tool_tip
    from jointdb.stack._band import sampleable_uncertainties, tip_band
    from jointdb.usecases._stack_band import (
        MODEL_FORM_SIGMA,
        choice_perturbation,
        damping_laws,
        feature_position,
        model_error,
        spindle_estimate,
    )

    unc, notes = sampleable_uncertainties(resolutions)
    for note in notes:
        say(f"      note: {note}")
    est, why = spindle_estimate(spec)
    m_sigma, sources = model_error(resolutions)
    none = ("0 — no campaign of the joints used recorded a validation assembly, and no tool–holder joint used "
            "records its identification assembly's peak error")
    laws, law_why = damping_laws(resolutions)
    say(f"      spindle estimate: {'sampled from its taps' if est is not None else '0 — ' + why}; "
        f"substructure model: {'; '.join(sources) if sources else none}")
    say("      damping law: " + ("; ".join(f"{n}: between viscous and hysteretic about {f:.4g} Hz"
                                          for n, (f, _) in laws.items())
                                 or "0 — " + ("; ".join(f"{n}: {w}" for n, w in law_why.items()) or "no joint")))

    def choice(lines):
        out = {n: choice_perturbation(r, lines) for n, r in resolutions.items()}
        return {n: c for n, c in out.items() if c is not None}

    if not unc and not choice(grid) and est is None and m_sigma == 0 and not laws:
        say("      no band: the chosen joints carry no parameter covariance and no joint-choice error")
        return None, None, {}
    resolved = {n: r.frf for n, r in resolutions.items() if r.frf is not None}
    f_sigma, f_notes = feature_position(spec, resolutions, predict_tool_tip(spec, resolved, grid).tip)
    say("      feature position: " + ("; ".join(f_notes) or "0 — no per-line tool–holder joint is chosen for "
                                                                  "conditions it was not identified at"))
    b = tip_band(spec, resolved, unc, grid, n=N_TIP_SAMPLES, choice=choice(grid), tip_sigma=MODEL_FORM_SIGMA,
                 spindle_estimate=est, model_sigma=m_sigma, damping=laws, feature_sigma=f_sigma)
    for row in b.summary():
        say(f"      5–95 % band ({b.samples} samples of {b.sources}): "
            "tip peak "
            f"{row['direction']} {row['peak_m_per_n_p05']:.3e} – {row['peak_m_per_n_p95']:.3e} m/N, "
            f"{row['peak_hz_p05']:.0f} – {row['peak_hz_p95']:.0f} Hz")
    summary = {"tip": b.summary()}

    def make(cut, speeds):
        lb = b if lobe_grid is None else tip_band(
            spec, resolved, unc, lobe_grid, n=N_LOBE_SAMPLES, choice=choice(lobe_grid), tip_sigma=MODEL_FORM_SIGMA,
            spindle_estimate=est, model_sigma=m_sigma, damping=laws, feature_sigma=f_sigma)
        xs, ys = lb.tip_frfs("x")[:N_LOBE_SAMPLES], lb.tip_frfs("y")[:N_LOBE_SAMPLES]
        return milling_lobes_band(xs, ys, cut, speeds)

    return b, make, summary
