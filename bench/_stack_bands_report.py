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
    "Calibration v3: whole lines left out, scaled by the gap product, multiplicative draws, the "
    "passivity guard. Its factor was chosen on the tuning seeds 7101 and 7102 only (48 stacks): factors 0.5 / "
    "0.75 / 1.0 / 1.5 put the truth inside on 44 / 46 / 46 / 48 peaks and 42 / 44 / 43 / 46 floors, at "
    "half-width / error 2.5 / 3.1 / 3.7 / 5.6× (peak) and 2.2 / 2.8 / 3.4 / 4.7× (floor); 0.5 is the largest "
    "within the 3× goal. Seeds 7203 and 7204 were drawn for the first time after that (blind; 7204 after 7203's "
    "result was read, with the calibration unchanged). Its results (the band centred on the prediction): 7201 22 / "
    "23 of 24 (peak / floor, 3.7× / 2.6×), 7202 22 / 22 (1.9× / 1.7×), 7203 (blind) 17 (71 %) / 16 (67 %) (0.9× / "
    "0.9×), 7204 (blind) 22 / 22 (1.9× / 1.7×). 7203 missed the goal; its misses under-estimated the peak (the "
    "prediction did so on 21 of its 24 stacks).",
    "Calibration v4 (this one): the joint-choice draws of a line left out lean the way its signed error points, "
    "mean amplitude β = LINE_BIAS times the request's gap ratio (the second-order correction of the interpolation "
    "is β = 1). Chosen on the tuning seeds before 7205 and 7206 were drawn: 7101 and 7102 (48 stacks) and, for "
    "more data, the first 16 stacks of 7105 and of 7106 (stopped for time); see *What this shows*.",
)


#: What the reported run shows (written after reading it; review it when the bench is rerun).
FINDINGS = (
    "What this shows: the two blind seeds of calibration v4 meet both goals: 7205 has the truth inside the 90 % band "
    "for 24 of 24 peaks and 23 of 24 floors (half-width 1.9× / 1.6× the median error), 7206 for 23 and 22 of 24 "
    "(2.8× / 2.0×); every stack, interpolated on both joints or one, carries a band. Their misses: S06-22 (Ø13 end "
    "mill, 41 mm gauge, 40 N·m: −13.4 % peak against a ±6.1 % band; a short tool between the Ø12 and Ø16 lines and "
    "near the 30 N·m line, where the torque and diameter errors add), and two floors missed by less than 0.5 % of "
    "the floor (S05-05, S06-11).",
    "The seen seeds, rerun with v4 (not evidence for it: 7203's misses motivated it): 7201 24 / 23 of 24 (peak / "
    "floor), 7202 24 / 21, 7203 21 (88 %) / 20 (83 %), 7204 23 / 22 — all ≥ 80 %; half-width / error 4.3× on "
    "7201's peak (its errors are unusually small, median 1.1 %) and 1.0–2.5× elsewhere. Against v3, v4 brings inside "
    "14 peaks or floors that v3 missed (among them 7203's S03-05, S03-08, S03-11, S03-14, S03-17 and 7202's S02-05, "
    "S02-21) and loses two floors by less than 0.5 % (S02-06, S02-20). Still outside: 7203's S03-07 (Ø8 × 30 mm), "
    "S03-15 and S03-18 (Ø13), all at 35 N·m, just above the 30 N·m line. There the torque axis is the one that "
    "errs: the contact stiffness saturates in torque, 1 − exp(−T/55 N·m), which in ln T bends one way below "
    "≈ 55 N·m and the other above, so the 70 N·m line left out between 30 and 150 N·m averages the two and shows "
    "little — a three-line torque grid cannot tell the band how wrong the interpolation is near its low end, and "
    "only a catalogued line near 45–50 N·m would.",
    "Cause of v3's misses (`bench/stack_bands_cause.py`, output in `docs/validation/stack-bands-cause.json`; "
    "tuning seeds 7101 and 7102 only): the error is set by "
    "where the stack lies against the *diameter* lines. On a diameter line (21 stacks) the peak error's median is "
    "+0.2 %, none beyond 5 %, 9 of 21 under-estimated; between Ø8 and Ø12 (16) the median is −6.2 %, 15 "
    "under-estimated, 10 beyond 5 %; between Ø12 and Ø16 (11) −2.7 %, 10 under-estimated, 3 beyond 5 %. Insertion "
    "(32–34 / 35 / 36–38 mm: medians −0.8 / −2.1 / −1.5 %) and fluted or blank (−1.5 / −1.0 %) do not separate the "
    "errors; short gauges amplify them (≤ 40 mm: median −3.6 %, 7 of 14 beyond 5 %; the tip depends more on the "
    "joint). On catalogued conditions (no joint choice at all) carrying a per-line joint to a tool unlike its "
    "campaign's (gauge 30–65 mm instead of 45, inserted 32 or 38 mm instead of 35, fluted) errs by 0–3.3 %, at most "
    "4.6 % (Ø8, 30 mm gauge, 32 mm inserted): within what the prediction-path term (σ 2 %) carries, so neither the "
    "insertion held at 35 mm nor the joint's transfer to another tool is the cause. The cause is interpolating "
    "across the diameter gap: the contact stiffness grows ∝ d while the interpolation is linear in ln d, so every "
    "joint between two diameter lines comes out too stiff and its peak too low — one-sided, and the Ø12 line left "
    "out shows that error *with its sign*. Calibration v4 lets the band lean that way (`LINE_BIAS`; "
    "`tests/stack/test_band_bias.py` checks on a k ∝ T^0.5 catalogue that the lean is the signed interpolation "
    "error to second order and that the leaning band's median is ≥ 3× closer to the true tip peak).",
    "Its tuning (tuning seeds only; factor 0.5 unless said): on 7101 and 7102 (48 stacks) a lean of 0 / 0.5 / 1, and "
    "0.5 with factor 0.75, put the truth inside on 44 / 46 / 47 / 48 peaks and 42 / 44 / 45 / 46 floors at "
    "half-width / error 2.5 / 2.8 / 3.4 / 3.5× (peak) and 2.2 / 2.5 / 3.0 / 2.9× (floor); on the first 16 stacks of "
    "7105 and of 7106, 31 / 31 / 30 of 32 peaks and 27 / 29 / 30 floors at 2.4 / 3.5 / 4.9× and 1.5 / 1.7 / 2.3×. The "
    "rule (most coverage within the 3× goal) picked a lean of 0.5 with factor 0.5, frozen before 7205 and 7206 were "
    "first drawn (the pooled 75 stacks then read 3.0× / 2.6×).",
    "Blind seeds 7207 and 7208 (first drawn after the spindle-estimate and substructure-model terms were committed, "
    "calibration v4 unchanged), exact spindle: 7207 22 / 22 of 24 (peak / floor; half-width 2.3× / 1.5× the "
    "median error), 7208 24 / 22 (1.8× / 1.4×) — both goals met again. 7207's misses: S07-13 (Ø13 end mill, 49 mm, "
    "60 N·m, 11.5 kN), +307 % peak against a ±117 % band whose lower edge is still +73 %: the prediction puts a "
    "sharp (passive) mode at 4,990 Hz, the grid's last line but one, where the truth's mode lies above 5 kHz, and "
    "that mode becomes the dominant one — a dominant-mode swap at the band edge (the largest |H| is compared "
    "whatever its frequency: the truth's at 2,540 Hz, the prediction's at 4,990 Hz), not a band too narrow; S07-14 by 0.2 % of the peak; the floors of "
    "S07-14, S07-16, S08-05 and S08-24 by 1.4–4.2 % of the floor.",
    "The spindle estimated from extension-bar taps (same seeds, `--spindle-estimate`): the goals are **not** met. "
    "7207: 17 (71 %) peaks and 19 (79 %) floors of 24 inside (half-width 4.0× / 3.7× the median error); 7208: 16 "
    "(67 %) and 22 (92 %) (3.2× / 3.3×). The spindle-estimate term dominates on 13 and 18 stacks; the median |peak "
    "error| rises from 2.1 / 2.3 % (exact spindle) to 6.6 / 8.1 %, and the prediction over-estimates the peak on 15 "
    "and 16 of 24 (8 and 6 with the exact spindle). Every peak miss is such an over-estimate (+4.8 % to +180 %) with "
    "the band above the truth. Cause: the extension method estimates the spindle line by line, and 0.2 % noise on "
    "the taps becomes 1.6 % per line on h and 2–3 % on the rotational entries (medians; 90th percentiles 4 % and "
    "10 %; one stack's taps); the tip FRF "
    "inherits these as spikes, which only ever raise its largest |H|, so the prediction's dominant peak lies above "
    "the truth, and every resampled spindle carries the nominal estimate's spikes plus its own, so the band lies "
    "higher still. Per line the term is calibrated (`tests/stack/test_spindle_band.py`: the exact spindle's tip |H| "
    "inside the band on 89 % of lines); for the peak it is not. The remedy is to smooth the estimate before "
    "predicting: on the first six stacks of tuning seed 7101, a modal fit of the taps (`jointdb.modal.fit_modes`) "
    "before the extension method cut the spindle-induced peak errors of +14 / +20 / +15 % to +4 / +8 / +6 % (the "
    "exact spindle: 0 / −1 / +3 %); jointdb does not do this yet, so a spindle from raw taps should be read as "
    "this section says.",
    "Terms: with the exact spindle the prediction path dominates on 13–15 of 24 stacks of each blind seed, the joint "
    "choice on the others (the stacks between lines); no stack is dominated by measurement noise (0.2 % in the "
    "campaigns). The substructure-model term is 0 here (family B's campaigns record no validation assembly; "
    "`tests/stack/test_model_error_band.py` checks it on known answers and on the fixture campaign that has one, "
    "0.36 % at its dominant peaks). Weak: where the "
    "diameter gap is wide (Ø9–Ø10 stacks) the leaning draws have a long upper tail — half-widths of ±132 % to "
    "±610 % on the peak (S06-01, S06-07; S05-09 ±214 %); the median stays within 3×, but such a band says only "
    "that the joint choice dominates there, and the peak error itself (−7 to −10 %) is what a planner should read. "
    "The prediction still under-estimates the peak on most stacks (14 of 24 of 7205, 22 of 24 of 7206): v4 widens "
    "the band that way but does not correct the prediction.",
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

    base = str(seed).split("+")[0]
    status = ("" if not base.isdigit() else "seen" if int(base) in tb.SEEN_SEEDS else "blind")
    if status and "+" in str(seed):
        status += ", spindle estimated from taps"
        seed = base
    out = []
    for key, label in (("peak", "dominant peak magnitude"), ("floor", "lobe floor")):
        q = s[key]
        out.append(f"| {seed}{f' ({status})' if status else ''} | {label} | {q['banded']} of {q['stacks']} | "
                   f"{q['covered']} of {q['banded']} "
                   f"({q['covered'] / max(q['banded'], 1):.0%}) | {q['median_half']:.1%} | "
                   f"{q['median_abs_err']:.1%} | {q['median_half'] / max(q['median_abs_err'], 1e-12):.1f}× |")
    return out


def section(results: dict, seconds: float) -> str:
    """Markdown of the reported seeds' rows and summaries (``results``: seed → {rows, summary})."""
    import _stack_truth_b as tb
    from jointdb.store._loo import CAP_OVER_MEDIAN
    from jointdb.usecases._stack import CHOICE_CALIBRATION, LINE_CALIBRATION
    from jointdb.usecases._stack_band import LINE_BIAS, MODEL_FORM_SIGMA

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
             f"calibration (joint-choice factor {LINE_CALIBRATION:g} and lean {LINE_BIAS:g} for lines left out, "
             f"{CHOICE_CALIBRATION:g} "
             f"for single joints, leave-one-out errors capped at "
             f"{CAP_OVER_MEDIAN:g}× their median per line, prediction-path σ {MODEL_FORM_SIGMA:.1%}) was set on the "
             f"tuning seeds {', '.join(map(str, tb.TUNING_SEEDS))} only.", "",
             "The band is the 5–95 % range of 200 samples: measurement noise (the fit covariance of joints kept "
             "as constant k, c), joint choice, the damping law of joints kept as constant k, c (0 on family B: "
             "all its catalogued joints are per-line), the spindle's estimate, the substructure model and the "
             "prediction path's own model-form error (docs/stacks.md, *Bands*). Family B's spindle is its exact receptance "
             "(spindle term 0) except on the seeds marked *spindle estimated from taps*: there each stack's spindle "
             "is what the extension method makes of its own taps on a Ø40 × 100 mm bar (tapped at 50 and 100 mm, "
             "0.2 % noise and 6 digits like the campaigns, the noise level estimated from the taps; "
             "`estimated_spindle`), the catalogue unchanged. Family B's campaigns record no validation assembly, "
             "so the substructure-model term is 0 throughout. The joint-choice "
             "term leaves out whole condition lines of the catalogue (each interior diameter, torque, drawbar force "
             "line; `jointdb/store/_loo.py`), interpolates them across the gap as a request between lines is "
             "interpolated, and scales each such error by the request's gap product over the line's, "
             "(r − v₋)(v₊ − r) / ((v − v₋)(v₊ − v)) in ln units: zero on a catalogued line, largest mid-way, one "
             "independent draw per axis (an axis with two lines only: a quarter of the difference between them at "
             "mid-way). The draws of a line left out are not centred: their mean is "
             f"{LINE_BIAS:g} × the request's gap ratio (`LINE_BIAS`), so the band leans the way the catalogue's own "
             "line errors point (a draw of 1 × the gap ratio is the interpolation's second-order correction). "
             "A prediction whose dominant tip peak is not passive (Im H > 0 near it: a negatively damped "
             "resonance from per-line joints) is redone with the joints' constant k, c fit "
             "(`jointdb/usecases/_stack_guard.py`), marked *constant k, c fallback* below. "
             "*Dominant term*: the term whose band alone is widest. Goals: truth inside on ≥ 80 % of the stacks, "
             "median half-width ≤ 3× the median |error|.", "",
             "| seed | quantity | stacks with a band | truth inside the 90 % band | median half-width | "
             "median abs error | half-width / error |", "|---|---|---|---|---|---|---|"]
    for seed, res in results.items():
        lines += _summary_rows(seed, res["summary"])
    exact = [k for k in results if isinstance(k, int)]
    if len(exact) > 1:  # the seeds with the exact spindle; those with an estimated one are another case
        from bench_stack_bands import summary

        pooled = [r for k in exact for r in results[k]["rows"]]
        lines += _summary_rows(f"all {len(exact)} seeds, exact spindle", summary(pooled))
    lines += ["", "History: " + " ".join(HISTORY), ""]
    for paragraph in FINDINGS:
        lines += [paragraph, ""]
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
