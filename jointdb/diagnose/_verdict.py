"""Plain-language texts of a diagnosis: where the mismatch is, what explains it,
how sure that is, and which measurement would settle a close call."""

from __future__ import annotations

import numpy as np

from jointdb.diagnose._compare import Signature

__all__ = ["shift_text", "separating_measurement", "where_text", "implausibility_text", "levels_text",
           "level_table_text", "explained_verdict", "unexplained_verdict", "not_better_verdict"]


def shift_text(sig: Signature) -> str:
    """Where and how the recording departs from the model, mode by mode, in words."""
    if not sig.pairs:
        return "no resonance of the model could be paired with one in the recording"
    low, high, same = [], [], []
    for p in sig.pairs:
        s = 100 * p.shift
        (same if abs(s) < 0.7 else low if s < 0 else high).append((p.mode, abs(s)))

    def grp(items, word):
        modes = ", ".join(str(m) for m, _ in items)
        vals = [v for _, v in items]
        rng = f"{min(vals):.1f} %" if len(vals) == 1 or max(vals) - min(vals) < 0.3 else \
            f"{min(vals):.1f}–{max(vals):.1f} %"
        return f"mode{'s' if len(items) > 1 else ''} {modes} {'is' if len(items) == 1 else 'are'} {rng} {word}"

    parts = []
    if low:
        parts.append(grp(low, "low in the recording"))
    if high:
        parts.append(grp(high, "high in the recording"))
    if same:
        m = ", ".join(str(m) for m, _ in same)
        parts.append(f"mode{'s' if len(same) > 1 else ''} {m} {'is' if len(same) == 1 else 'are'} "
                     "unchanged in frequency")
    text = "; ".join(parts)
    damp = [p.damping_ratio for p in sig.pairs if np.isfinite(p.damping_ratio)]
    if damp and (max(damp) > 1.4 or min(damp) < 0.7):
        text += "; recorded damping is " + ", ".join(f"×{d:.2g}" for d in damp) + " the model's (by mode)"
    if abs(sig.gain_db) > 0.5:
        text += f"; away from resonances the recording is {sig.gain_db:+.1f} dB off"
    if sig.delay_r2 > 0.5 and abs(sig.delay_s) > 3e-6:
        text += f"; its phase drifts in proportion to frequency (≈ {sig.delay_s * 1e6:.0f} µs)"
    if sig.extra_peaks:
        text += "; extra recorded peak(s) at " + ", ".join(f"{f:.0f}" for f in sig.extra_peaks) + " Hz"
    if sig.missing_peaks:
        text += "; model peak(s) missing in the recording at " + ", ".join(f"{f:.0f}" for f in sig.missing_peaks) \
            + " Hz"
    return text



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
        parts.append(f"{name} {q.fmt(fit.values[name])}, plausible {lo * q.show:.3g}–{hi * q.show:.3g} {unit}")
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
        parts.append(f"mode {t.mode} {f} Hz, ζ {z} %")
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
               f"{implausibility_text(best)}; mismatch {100 * mis0:.1f} % → {100 * mis1:.1f} %.{lv}")
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
