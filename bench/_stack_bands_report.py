"""The *Bands* section of docs/validation/stack-prediction.md, written by ``bench/bench_stack_bands.py``
between two markers (``bench/bench_stack_prediction.py`` keeps it when it rewrites the page)."""

from __future__ import annotations

from pathlib import Path

BEGIN, END = "<!-- bands:begin -->", "<!-- bands:end -->"


def kept_section(page: Path) -> str:
    """The marked section of ``page`` (with a leading blank line), or '' if it has none."""
    if not page.exists():
        return ""
    text = page.read_text(encoding="utf-8")
    if BEGIN not in text or END not in text:
        return ""
    return "\n" + text[text.index(BEGIN):text.index(END) + len(END)] + "\n"


def _pct(x) -> str:
    return f"{x:+.1%}"


#: Earlier reported runs, kept as they came out (the calibration changed after them).
HISTORY = (
    "Calibration v1 (single joints left out, scaled by distance; factor 0.08, prediction-path σ 2.5 %, errors "
    "uncapped), seed 7201: truth inside the band on 24 of 24 stacks for the peak and for the floor, median "
    "half-width 8.2 % / 7.0 % against median |error| 1.1 % / 1.5 %.",
    "Calibration v2 (the same, errors capped at 3× their median, σ 2.0 %): seed 7201 24 / 24 of 24 (6.9× / 3.9×); "
    "seed 7202, then blind, 20 (83 %) peaks and 18 (75 %) floors of 24 (3.0× / 2.4×). Its misses were stacks "
    "between the Ø8 and Ø12 lines (Ø9, Ø10 short tools, errors −15 to −25 %: a joint left out alone is "
    "interpolated from neighbours on its own lines, which says nothing of interpolating *across* a diameter gap) "
    "and S02-21, +684 % peak from a negatively damped resonance of the per-line joints.",
    "Calibration v3 (this one): whole lines left out, scaled by the gap product, multiplicative draws, the "
    "passivity guard. Its factor was chosen on the tuning seeds 7101 and 7102 only (48 stacks): factors 0.5 / "
    "0.75 / 1.0 / 1.5 put the truth inside on 44 / 46 / 46 / 48 peaks and 42 / 44 / 43 / 46 floors, at "
    "half-width / error 2.5 / 3.1 / 3.7 / 5.6× (peak) and 2.2 / 2.8 / 3.4 / 4.7× (floor); 0.5 is the largest "
    "within the 3× goal. Seeds 7203 and 7204 were drawn for the first time after that (blind; 7204 after 7203's result was read, "
    "with the calibration unchanged); 7201 and 7202 are seen.",
)


#: What the reported run shows (written after reading it; review it when the bench is rerun).
FINDINGS = (
    "What this shows: over all 96 stacks the truth is inside the 90 % band for 83 of 96 peaks and 83 of 96 floors "
    "(86 %), with median half-width ≤ 3× the median error on every seed but 7201's peak (3.7×, its errors are "
    "unusually small, median 1.1 %). Of the two blind seeds, 7204 meets both goals (22 and 22 of 24, 92 %, "
    "1.9× / 1.7×); 7203 does not: 17 (71 %) peaks and 16 (67 %) floors, the band narrower than the error (0.9×). "
    "Seeds 7201 and 7202 (seen): 22 of 24 peaks and 23 / 22 of 24 floors (≥ 92 %). The line leave-out covers the "
    "stacks between the Ø8 and Ø12 lines that v2 missed (S02-10, S02-15, S02-16, S02-17, S02-19 now inside), and "
    "the passivity guard turns S02-21 from +684 % into −7.1 % (both joints' constant k, c on the 27 lines within "
    "4740–5000 Hz around the spurious 4980 Hz peak, the per-line joints elsewhere; still just outside its ±4.9 % "
    "band); S04-24 (inside its band) and a stack of the reduced catalogue of tests/stack/test_band_truth_b.py are "
    "repaired the same way.",
    "Seed 7203's misses are short or joint-dominated tools close to catalogued lines (Ø8 × 30 mm, Ø13 × 40 mm, "
    "35 N·m stacks), peak errors −5 to −8 %, where the joint choice adds little and the prediction-path term "
    "(±3.3 %) is all the band has: the error of carrying a per-line joint from its campaign's tool to another "
    "tool grows with how much the tip depends on the joint, which a constant σ does not know. The peak errors are "
    "also one-sided (the prediction under-estimates the peak on 21 of 24 stacks of 7203, 17 of 24 of 7204), "
    "which a band centred on the prediction cannot represent. A joint-transfer term (every catalogued joint's Z "
    "scaled by exp(σξ), σ = 5 %) was tried on the tuning seeds and dropped: it widened every band (median "
    "half-width 3.9 → 6.5 %) without covering more stacks there. Sensitivity, after the fact and not the "
    "reported calibration: with the joint-choice factor 0.75 (the next one on the tuning grid, 3.1× wide there) "
    "seed 7203 would have 20 and 20 of 24 inside (83 %), half-width 5.2 % / 6.7 % against errors 4.9 % / 5.5 %.",
)


def _rows_table(rows: list[dict]) -> list[str]:
    lines = ["| stack | joints (tool–holder / holder–spindle) | peak error | peak band ± | in | floor error | "
             "floor band ± | in | dominant term |", "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if r.get("peak_band") is None:
            lines.append(f"| {r['case']} | no band | | | | | | | |")
            continue
        lines.append(f"| {r['case']} | {r['methods'].get('tool-holder')} / {r['methods'].get('holder-spindle')} | "
                     f"{_pct(r['peak_err'])} | {r['peak_half']:.1%} | {'yes' if r['peak_covered'] else '**no**'} | "
                     f"{_pct(r['floor_err'])} | {r['floor_half']:.1%} | {'yes' if r['floor_covered'] else '**no**'} | "
                     f"{r['dominant_term']} |")
    return lines


def _summary_rows(seed, s: dict) -> list[str]:
    import _stack_truth_b as tb

    status = "seen" if seed in tb.SEEN_SEEDS else "blind" if isinstance(seed, int) else ""
    out = []
    for key, label in (("peak", "dominant peak magnitude"), ("floor", "lobe floor")):
        q = s[key]
        out.append(f"| {seed} {f'({status})' if status else ''} | {label} | {q['banded']} of {q['stacks']} | "
                   f"{q['covered']} of {q['banded']} "
                   f"({q['covered'] / max(q['banded'], 1):.0%}) | {q['median_half']:.1%} | "
                   f"{q['median_abs_err']:.1%} | {q['median_half'] / max(q['median_abs_err'], 1e-12):.1f}× |")
    return out


def section(results: dict, seconds: float) -> str:
    """Markdown of the reported seeds' rows and summaries (``results``: seed → {rows, summary})."""
    import _stack_truth_b as tb
    from jointdb.store._loo import CAP_OVER_MEDIAN
    from jointdb.usecases._stack import CHOICE_CALIBRATION, LINE_CALIBRATION
    from jointdb.usecases._stack_band import MODEL_FORM_SIGMA

    lines = [BEGIN, "", "## Bands: do they contain the truth? (issue 22)", "",
             "Produced by `bench/bench_stack_bands.py --report docs/validation/stack-prediction.md` (do not edit "
             "this section by hand).", "",
             "A second truth family built for this check, `bench/_stack_truth_b.py` (family B), differs from the "
             "one above in contact law (tool–holder contact saturating in torque, ∝ shank Ø, loss factor 0.08; "
             "taper contact ∝ 1 + 0.45 ln(F/15 kN), loss factor 0.03), holder geometry (55 mm × Ø36 nose, "
             "20 mm × Ø63 flange) and spindle (Ø80/Ø65 shaft on three bearing sets, 5 kg rotor). Its catalogue: "
             f"{len(tb.HS_CAMPAIGNS)} holder–spindle campaigns (10–25 kN) and {len(tb.TH_CAMPAIGNS)} tool–holder "
             "campaigns (machines at 10 and 25 kN; Ø8 / Ø12 / Ø16 at 30 / 70 / 150 N·m), 0.2 % noise. Stacks are "
             "drawn inside that range (Ø8–16 mm, 30–150 N·m, 10–25 kN, insertion 32–38 mm, fluted or blank); "
             "the "
             f"calibration (joint-choice factor {LINE_CALIBRATION:g} for lines left out, {CHOICE_CALIBRATION:g} "
             f"for single joints, leave-one-out errors capped at "
             f"{CAP_OVER_MEDIAN:g}× their median per line, prediction-path σ {MODEL_FORM_SIGMA:.1%}) was set on the "
             f"tuning seeds {', '.join(map(str, tb.TUNING_SEEDS))} only.", "",
             "The band is the 5–95 % range of 200 samples: measurement noise (the fit covariance of joints kept "
             "as constant k, c), joint choice and the prediction path's own model-form error. The joint-choice "
             "term leaves out whole condition lines of the catalogue (each interior diameter, torque, drawbar force "
             "line; `jointdb/store/_loo.py`), interpolates them across the gap as a request between lines is "
             "interpolated, and scales each such error by the request's gap product over the line's, "
             "(r − v₋)(v₊ − r) / ((v − v₋)(v₊ − v)) in ln units: zero on a catalogued line, largest mid-way, one "
             "independent draw per axis (an axis with two lines only: a quarter of the difference between them at "
             "mid-way). A prediction whose dominant tip peak is not passive (Im H > 0 near it: a negatively damped "
             "resonance from per-line joints) is redone with the joints' constant k, c fit "
             "(`jointdb/usecases/_stack_guard.py`), marked *constant k, c fallback* below. "
             "*Dominant term*: the term whose band alone is widest. Goals: truth inside on ≥ 80 % of the stacks, "
             "median half-width ≤ 3× the median |error|.", "",
             "| seed | quantity | stacks with a band | truth inside the 90 % band | median half-width | "
             "median abs error | half-width / error |", "|---|---|---|---|---|---|---|"]
    for seed, res in results.items():
        lines += _summary_rows(seed, res["summary"])
    if len(results) > 1:
        from bench_stack_bands import summary

        pooled = [r for res in results.values() for r in res["rows"]]
        lines += _summary_rows(f"all {len(results)} seeds", summary(pooled))
    lines += ["", "History: " + " ".join(HISTORY), "", *FINDINGS, ""]
    for seed, res in results.items():
        dom: dict[str, int] = {}
        for r in res["rows"]:
            dom[r["dominant_term"]] = dom.get(r["dominant_term"], 0) + 1
        lines += [f"### Seed {seed}", "", *_rows_table(res["rows"]), "",
                  "Dominant term over the stacks: " + ", ".join(f"{k}: {v}" for k, v in sorted(dom.items())) + ".", ""]
    lines += [f"Run time: {seconds:.0f} s.", "", END]
    return "\n".join(lines)


def write_section(page: Path, result: dict, seconds: float) -> None:
    """Replace (or append) the marked section of ``page``."""
    text = page.read_text(encoding="utf-8") if page.exists() else ""
    new = section(result, seconds)
    if BEGIN in text and END in text:
        text = text[:text.index(BEGIN)] + new + text[text.index(END) + len(END):]
    else:
        text = text.rstrip("\n") + "\n\n" + new + "\n"
    page.write_text(text, encoding="utf-8")
