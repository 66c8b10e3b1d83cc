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


def section(result: dict, seconds: float) -> str:
    """Markdown of the reported seed's rows and summary."""
    import _stack_truth_b as tb
    from jointdb.usecases._stack import CHOICE_CALIBRATION
    from jointdb.usecases._stack_band import MODEL_FORM_SIGMA

    rows, s = result["rows"], result["summary"]
    lines = [BEGIN, "", "## Bands: do they contain the truth? (issue 22)", "",
             "Produced by `bench/bench_stack_bands.py --report docs/validation/stack-prediction.md` (do not edit "
             "this section by hand).", "",
             "A second truth family built for this check, `bench/_stack_truth_b.py` (family B), differs from the "
             "one above in contact law (tool–holder contact saturating in torque, ∝ shank Ø, loss factor 0.08; "
             "taper contact ∝ 1 + 0.45 ln(F/15 kN), loss factor 0.03), holder geometry (55 mm × Ø36 nose, "
             "20 mm × Ø63 flange) and spindle (Ø80/Ø65 shaft on three bearing sets, 5 kg rotor). Its catalogue: "
             f"{len(tb.HS_CAMPAIGNS)} holder–spindle campaigns (10–25 kN) and {len(tb.TH_CAMPAIGNS)} tool–holder "
             "campaigns (machines at 10 and 25 kN; Ø8 / Ø12 / Ø16 at 30 / 70 / 150 N·m), 0.2 % noise. Stacks are "
             f"drawn inside that range; the calibration (joint-choice factor {CHOICE_CALIBRATION:g}, prediction-path "
             f"σ {MODEL_FORM_SIGMA:.1%}) was set on the tuning seeds {', '.join(map(str, tb.TUNING_SEEDS))} only; "
             f"the table is seed {tb.REPORT_SEED}, never used for tuning.", "",
             "The band is the 5–95 % range of 200 samples: measurement noise (the fit covariance of joints kept "
             "as constant k, c), joint choice (the catalogue's leave-one-out errors, scaled by the request's "
             "distance over theirs, `jointdb/store/_loo.py`) and the prediction path's own model-form error. "
             "*Dominant term*: the term whose band alone is widest.", "",
             "| stack | joints (tool–holder / holder–spindle) | peak error | peak band ± | in | floor error | "
             "floor band ± | in | dominant term |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if r.get("peak_band") is None:
            lines.append(f"| {r['case']} | no band | | | | | | | |")
            continue
        lines.append(f"| {r['case']} | {r['methods'].get('tool-holder')} / {r['methods'].get('holder-spindle')} | "
                     f"{_pct(r['peak_err'])} | {r['peak_half']:.1%} | {'yes' if r['peak_covered'] else '**no**'} | "
                     f"{_pct(r['floor_err'])} | {r['floor_half']:.1%} | {'yes' if r['floor_covered'] else '**no**'} | "
                     f"{r['dominant_term']} |")
    lines += ["", "| quantity | stacks with a band | truth inside the 90 % band | median half-width | "
              "median abs error | half-width / error |", "|---|---|---|---|---|---|"]
    for key, label in (("peak", "dominant peak |H|"), ("floor", "lobe floor")):
        q = s[key]
        lines.append(f"| {label} | {q['banded']} of {q['stacks']} | {q['covered']} of {q['banded']} "
                     f"({q['covered'] / max(q['banded'], 1):.0%}) | {q['median_half']:.1%} | "
                     f"{q['median_abs_err']:.1%} | {q['median_half'] / max(q['median_abs_err'], 1e-12):.1f}× |")
    dom: dict[str, int] = {}
    for r in rows:
        dom[r["dominant_term"]] = dom.get(r["dominant_term"], 0) + 1
    lines += ["", "Dominant term over the stacks: " + ", ".join(f"{k}: {v}" for k, v in sorted(dom.items())) + ".",
              "", f"Run time: {seconds:.0f} s.", "", END]
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
