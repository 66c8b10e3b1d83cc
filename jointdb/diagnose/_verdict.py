"""Plain-language texts of a diagnosis: where the mismatch is, what explains it,
how sure that is, and which measurement would settle a close call."""

from __future__ import annotations

import numpy as np

from jointdb.diagnose._compare import Signature

__all__ = ["shift_text", "separating_measurement", "where_text", "implausibility_text", "levels_text",
           "level_table_text", "explained_verdict", "unexplained_verdict", "not_better_verdict", "rank_text",
           "unidentified_verdict"]


def shift_text(sig: Signature) -> str:
    """Where and how the recording departs from the model, mode by mode, in words."""
    if not sig.pairs:
        return "no resonance of the model could be paired with one in the recording"
    low, high, same = [], [], []
    for p in sig.pairs:
        s = 100 * p.shift
        # named by the recorded frequency (what the engineer sees in the data), the model's in brackets
        (same if abs(s) < 0.7 else low if s < 0 else high).append((mode_name(p.recorded.freq_hz), abs(s),
                                                                     p.model.freq_hz))

    def grp(items, word):
        vals = [v for _, v, _ in items]
        rng = f"{min(vals):.1f} %" if len(vals) == 1 or max(vals) - min(vals) < 0.3 else \
            f"{min(vals):.1f}–{max(vals):.1f} %"
        model = ", ".join(f"{fm:.0f}" for _, _, fm in items)
        return f"{_names(items)} ({model} Hz in the model) {'is' if len(items) == 1 else 'are'} {rng} {word}"

    parts = []
    if low:
        parts.append(grp(low, "low in the recording"))
    if high:
        parts.append(grp(high, "high in the recording"))
    if same:
        parts.append(f"{_names(same)} {'is' if len(same) == 1 else 'are'} unchanged in frequency")
    text = "; ".join(parts)
    # damping only where the recording visibly departs from the model around that mode (a ratio of two
    # half-power estimates on a mode that matches is noise, not an effect)
    damp = [(mode_name(p.recorded.freq_hz), p.damping_ratio) for p in sig.pairs
            if np.isfinite(p.damping_ratio) and p.mismatch >= SHOWS and not 0.7 <= p.damping_ratio <= 1.4]
    if damp:
        text += "; recorded damping is " + ", ".join(f"×{d:.2g} the model's at {m}" for m, d in damp)
    if abs(sig.gain_db) > 0.5 and sig.overall >= SHOWS:
        text += f"; away from resonances the recording is {sig.gain_db:+.1f} dB off"
    if sig.delay_r2 > 0.5 and abs(sig.delay_s) > 3e-6 and sig.overall >= SHOWS:
        text += f"; its phase drifts in proportion to frequency (≈ {sig.delay_s * 1e6:.0f} µs)"
    if sig.extra_peaks:
        text += "; extra recorded peak(s) at " + ", ".join(f"{f:.0f}" for f in sig.extra_peaks) + " Hz"
    if sig.missing_peaks:
        text += "; model peak(s) missing in the recording at " + ", ".join(f"{f:.0f}" for f in sig.missing_peaks) \
            + " Hz"
    return text



#: A mismatch (weighted RMS |log ratio|) below this is not "shown" by the recording: no effect is stated.
SHOWS = 0.08


def mode_name(freq_hz: float) -> str:
    """``the 98 Hz mode`` (whole hertz; 2 significant figures below 10 Hz)."""
    return f"the {freq_hz:.0f} Hz mode" if freq_hz >= 10 else f"the {freq_hz:.2g} Hz mode"


def _names(items) -> str:
    """``the 98 Hz mode`` / ``the 98 and 410 Hz modes`` from ``[(mode_name, …), …]``."""
    names = [it[0] for it in items]
    if len(names) == 1:
        return names[0]
    hz = [n.removeprefix("the ").removesuffix(" mode") for n in names]
    return "the " + ", ".join(h.removesuffix(" Hz") for h in hz[:-1]) + " and " + hz[-1] + " modes"


def where_text(candidate) -> str:
    """`` at <location>`` for located candidates (the first part of a combination), else ``""``."""
    c = candidate.parts[0] if hasattr(candidate, "parts") else candidate
    loc = getattr(c, "location", None)
    return f" at {loc}" if loc else ""


def _kind(family: str) -> str:
    if family.startswith("joint") or family == "softening_joint":
        return "joint"
    return family


def separating_measurement(best, alt, n_levels: int, n_points: int) -> str:
    """What extra measurement would tell ``best`` and ``alt`` (two :class:`Fit` s) apart."""
    kinds = {_kind(best.family.split(" + ")[0]), _kind(alt.family.split(" + ")[0])}
    pos = [getattr(f.candidate, "position", None) for f in (best, alt)]
    if "softening_joint" in (best.family, alt.family) and n_levels < 3:
        return "record at another excitation level (an amplitude-dependent joint moves with the level, a " \
               "linear effect does not)"
    if kinds == {"joint"} and None not in pos and abs(pos[0] - pos[1]) > 1e-9:
        z = 0.5 * (pos[0] + pos[1])
        return (f"measure at a point between z = {min(pos) * 1e3:.4g} and {max(pos) * 1e3:.4g} mm (e.g. "
                f"{z * 1e3:.4g} mm): the mode shapes there differ between the two joint positions")
    if "joint" in kinds and "fluted_diameter" in kinds:
        return ("measure on both sides of the interface (a joint puts a kink in the mode shape there, a wrong "
                "diameter does not)")
    if "sensor_mass" in kinds:
        return "repeat the tap test with a lighter sensor or with the sensor moved (only added mass follows it)"
    if kinds & {"gain", "delay"}:
        return "check the measurement chain with a calibrated reference (a known mass or a back-to-back test)"
    if "joint" in kinds:
        return "add a measurement point near the suspected interface" + (
            "" if n_points > 1 else " (one recorded point cannot locate it)")
    return "add a measurement point or an excitation level where the two explanations predict different FRFs"


def implausibility_text(fit) -> str:
    """`` (outside the plausible range: diameter 10.9 mm, plausible 11.6–12.4 mm)`` or ``""``."""
    bad = getattr(fit, "implausible", {}) or {}
    if not bad:
        return ""
    c = fit.candidate
    params = {q.name: q for q in c.params}
    parts = []
    for name in bad:
        q = params.get(name)
        if q is None or q.plausible is None:
            parts.append(name)
            continue
        lo, hi = q.plausible
        unit = q.show_unit or q.unit
        # enough digits that the value visibly lies outside the range it is compared with
        v = fit.values[name] * q.show
        parts.append(f"{name} {v:.4g} {unit}, plausible {lo * q.show:.4g}–{hi * q.show:.4g} {unit}")
    return " (outside the physically plausible range: " + "; ".join(parts) + ")"


def levels_text(analysis) -> str:
    """What the excitation levels show, from the local modal fits (``LevelAnalysis``)."""
    if analysis is None or not analysis.tracks:
        return ""
    moving = [t for t in analysis.tracks if t.differs]
    if not moving:
        return "; the excitation levels agree within their noise (no level dependence)"
    o = list(analysis.order)
    parts = []
    for t in moving:
        f = " → ".join(f"{t.freq_hz[k]:.5g}" for k in o)
        z = " → ".join(f"{100 * t.zeta[k]:.3g}" for k in o)
        parts.append(f"{mode_name(t.freq_hz[o[0]])} {f} Hz, ζ {z} %" + "".join(
            f" (level {analysis.levels[k] if analysis.levels[k] is not None else k + 1}: {t.freq_hz[k]:.5g} Hz "
            "is off its neighbours' trend, an outlier left out)" for k in t.outliers))
    return "; with rising excitation level " + "; ".join(parts)


def level_table_text(rows: list) -> str:
    """`` Per level: 0.5: k_x … N/µm, k_ry … kN·m/rad, η …, slip … µm; …`` (empty without rows)."""
    if not rows:
        return ""
    out = []
    for i, r in enumerate(rows):
        name = r["level"] if r["level"] is not None else i + 1
        if "k_contact_n_per_m2" in r:
            text = f"{name}: k' {r['k_contact_n_per_m2'] / 1e9:.3g} GN/m²"
        else:
            text = f"{name}: k_x {r['k_x_n_per_m'] / 1e6:.3g} N/µm, k_ry {r['k_ry_nm_per_rad'] / 1e3:.3g} kN·m/rad"
        text += f", η {r['loss_factor']:.3g}"
        slip = r.get("slip_amplitude_m", float("nan"))
        if np.isfinite(slip):
            text += f", slip {slip * 1e6:.3g} µm"
        out.append(text)
    return " Per level: " + "; ".join(out) + "."


def not_better_verdict(best, where: str, mis0: float, mis1: float, min_improvement: float) -> str:
    """The verdict when the best candidate improves the fit lines but not the whole band enough."""
    return (f"The recording differs from the model ({where}; mismatch {100 * mis0:.1f} %). The best "
            f"candidate, {best.describe()}, improves the fit lines but brings the whole band only to "
            f"{100 * mis1:.1f} % (less than {min_improvement:g}× better). Nothing is added.")


def unexplained_verdict(fits: list, runner, nominal_mismatch: float, level_dependent: bool, where: str,
                        mis0: float) -> str:
    """The verdict when no candidate is accepted: no mismatch, or none that candidate physics explains
    (``runner``: the best eligible fit)."""
    if nominal_mismatch < 0.08 or runner is None:
        return (f"No significant mismatch: model and recording agree to {100 * mis0:.1f} % "
                f"({where}); no physics is added.")
    if level_dependent and not any(f.candidate.per_level for f in fits):
        return (f"The recording differs from the model ({where}; mismatch {100 * mis0:.1f} %) and changes "
                "with the excitation level, but no amplitude-dependent candidate could be fitted. "
                "Nothing is added.")
    return (f"The recording differs from the model ({where}; mismatch {100 * mis0:.1f} %), but no "
            f"candidate physics explains it well: the best, {runner.describe()}, only brings it to "
            f"{100 * runner.mismatch:.1f} % on the fit lines. Nothing is added.")


def explained_verdict(best, ok: list, level_table: list, obs, where: str, mis0: float, mis1: float,
                      close_call: float):
    """The verdict naming ``best``, and a close alternative (an accepted fit of another physics within
    ``close_call`` × its mismatch) with the measurement that separates them."""
    alternative, advice = None, ""
    lv = level_table_text(level_table)
    verdict = (f"{where[0].upper() + where[1:]}. Best explained by {best.describe()}"
               f"{implausibility_text(best)}; whole-band mismatch {100 * mis0:.1f} % → {100 * mis1:.1f} %.{lv}")
    rivals = [f for f in ok if f is not best and f.candidate.slot != best.candidate.slot
              and f.family.split(" + ")[0] != best.family.split(" + ")[0]
              and f.mismatch <= close_call * best.mismatch]
    if rivals:
        alternative = rivals[0]
        advice = separating_measurement(best, alternative, len(obs.levels), len(set(obs.out_points)))
        verdict += (f" A close alternative is {alternative.describe()}{implausibility_text(alternative)} "
                    f"(mismatch {100 * alternative.mismatch:.1f} % against {100 * best.mismatch:.1f} % on the "
                    f"fit lines); to tell them apart, {advice}.")
    return verdict, alternative, advice


def _kind_phrase(fit) -> str:
    """What kind of change a fit adds, in a few words ("a joint compliance", "an added mass", …)."""
    fam = fit.family.split(" + ")[0]
    return {"joint_compliance": "a joint compliance", "joint_damping": "a damped joint compliance",
            "softening_joint": "an amplitude-dependent joint", "sensor_mass": "an added mass",
            "fluted_diameter": "a change of section", "gain": "a gain error", "delay": "a time delay"}.get(
        fam, "a change")


def unidentified_verdict(fit, bad: dict, where: str, mis0: float, advice: str) -> str:
    """The verdict when the best explanation's key parameters are not identified: say what size of change
    sits where, that it is not identifiable, and which measurement would identify it."""
    loc = where_text(fit.candidate)
    params = {q.name: q for q in fit.candidate.params}
    what = "; ".join(f"{params[n].label} {params[n].fmt(fit.values[n])}"
                     + (" at the bound of its range" if not np.isfinite(r) else f" ± {100 * r:.0f} %")
                     for n, r in bad.items())
    return (f"The recording differs from the model ({where}; mismatch {100 * mis0:.1f} %). "
            f"{_kind_phrase(fit)[0].upper() + _kind_phrase(fit)[1:]} of this size{loc or ' somewhere here'} "
            f"would bring the fit lines to {100 * fit.mismatch:.1f} %, but it is not identifiable from these "
            f"measurements ({what}), so nothing is named. To identify it, {advice}.")


def rank_text(best, nxt, eligible, unresolved=None) -> str:
    """One sentence: why the named explanation (rank 1) ranks above the next one."""
    out = ""
    if unresolved is not None and unresolved is not best:
        out += (f" It is named instead of {unresolved.candidate.explanation}, which fits slightly better "
                "but whose parameters these measurements do not identify.")
    if nxt is None or nxt is unresolved:
        return out
    b, n = 100 * best.mismatch, 100 * nxt.mismatch
    if not eligible(nxt):
        why = "cannot follow the recorded change with the excitation level"
    elif nxt.implausible and not best.implausible:
        why = "needs physically implausible values"
    elif n > b:
        why = f"leaves {n:.1f} % on the fit lines against {b:.1f} %"
    elif nxt.p > best.p:
        why = (f"fits the lines only slightly better ({n:.1f} % against {b:.1f} %) with {nxt.p} parameters "
               f"against {best.p}: not enough to justify them")
    else:
        why = f"scores lower (ΔBIC {nxt.score - best.score:+.0f})"
    return out + f" The next ranked, {nxt.candidate.explanation}, {why}."
