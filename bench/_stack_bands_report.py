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
    "Calibration v1 (joint-choice factor 0.08, prediction-path σ 2.5 %, leave-one-out errors uncapped), seed 7201: "
    "truth inside the band on 24 of 24 stacks for the peak and for the floor, median half-width 8.2 % (peak) and "
    "7.0 % (floor) against median |error| 1.1 % and 1.5 %: wider than the 3× goal. The current calibration (capped "
    "leave-one-out errors, σ 2.0 %) was then set on the tuning seeds only (22 of 24 peaks, 21 of 24 floors inside; "
    "median half-width 6.3 % / 3.7 % against median |error| 2.8 % / 1.7 %) and is reported below on seed 7201 again "
    "(its v1 result was seen, so it is not blind) and on seed 7202 (blind).",
)


#: What the reported run shows (written after reading it; review it when the bench is rerun).
FINDINGS = (
    "What this shows: the goals are met in part. Coverage: 24 and 24 of 24 on seed 7201, 20 (peak) and 18 "
    "(floor) of 24 on the blind seed 7202 — the floor misses the 80 % goal there. Width: within 3× the median "
    "error on seed 7202 (3.0× peak, 2.4× floor), not on seed 7201 (6.9×, 3.9×), whose errors are unusually "
    "small (median 1.1 %): the prediction-path term (±3.3 % at 90 %) alone exceeds 3× that. The misses are "
    "stacks between the Ø8 and Ø12 grid lines (Ø9, Ø10 short tools, errors −15 to −25 %): the leave-one-out "
    "error, estimated mostly where a diameter line is removed entirely, underestimates interpolating across "
    "shank diameter for short, joint-dominated tools. One stack (S02-21) is a prediction failure rather than "
    "a band miss: +684 % peak, a spurious, nearly undamped resonance from the per-line joints. Every stack got "
    "a band (all with interpolated joints); the joint choice dominates on 16 of 24 (7202), the prediction "
    "path on the rest.",
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
        out.append(f"| {seed} {f'({status})' if status else ''} | {label} | {q['banded']} of {q['stacks']} | {q['covered']} of {q['banded']} "
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

        lines += _summary_rows(f"all {len(results)} seeds", summary([r for res in results.values() for r in res["rows"]]))
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
