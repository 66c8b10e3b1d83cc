"""The band on truth family C (never used to tune it): the page docs/validation/stack-bands-family-c.md.

The stacks are predicted by ``bench/bench_stack_bands.py --family c`` (the same pipeline as family B: catalogue
through ``usecases.catalogue_campaign``, stacks drawn with a seed, ``predict_stack`` + ``band_terms``); this
script adds what explains the result and writes the page's generated part and its JSON:

- the catalogue's joints: which model each campaign kept (constant k, c or per-line), how far constant k, c
  misfits its own campaign (× the noise) and how well the kept joint reproduces the campaign's assembly;
- a *transfer sweep*, stacks ON catalogued conditions (no joint choice at all): each tool–holder campaign's own
  stack (does the catalogued joint give back the stack it was identified on?), and Ø6 / Ø10 / Ø20 at 60 N·m on
  the 8 kN machine at other gauges than the campaigns' 50 mm (the error of carrying a catalogued joint to another
  tool); only the prediction-path term of the band can carry either.

One command, the reported run (≈ 25 min on a loaded 2-core machine, catalogue included):

    python bench/bench_stack_bands.py --family c --n 24 --catalogue /tmp/c --rows-out /tmp/c-rows.json
    python bench/bench_stack_bands.py --n 0 --seeds 7101 --catalogue /tmp/b    # family B's catalogue only
    python bench/bench_stack_bands_c.py --catalogue /tmp/c --rows /tmp/c-rows.json --b-catalogue /tmp/b \
        --what-if per_line /tmp/c-irc --what-if gauge_4d /tmp/c-4d --doc docs/validation/stack-bands-family-c.md

(``--no-transfer`` skips the sweep, ≈ 5 min loaded; each ``--what-if`` ≈ 10 min loaded, see :data:`WHAT_IF`).
The page's text outside the generated markers is kept.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections import Counter
from dataclasses import replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import _stack_truth_c as tc  # noqa: E402
import _stack_validation as sv  # noqa: E402
import bench_stack_bands as bb  # noqa: E402

BEGIN, END = "<!-- family-c:begin -->", "<!-- family-c:end -->"
DIAMETERS = tuple(d for d, _ in tc.TH_GRID)
TORQUES = tc.TH_GRID[0][1]


def joint_rows(repo, family=tc) -> list[dict]:
    """Per catalogued joint of ``family`` (a truth module): the model its campaign kept and how well it fits that
    campaign."""
    out = []
    for case in [*family.HS_CAMPAIGNS, *family.TH_CAMPAIGNS]:
        v = repo.get(case.name)
        q = {k.removeprefix("model_adequacy."): x for k, x in (v.quality or {}).items()}
        out.append({"joint": case.name,
                    "kept": "constant k, c" if v.provenance.method.startswith("output-error") else "per-line",
                    "misfit_to_noise": q.get("misfit_to_noise"), "constant_peak_score": q.get("constant_peak_score"),
                    "per_line_peak_score": q.get("per_line_peak_score"),
                    "reconstruction_error_mean": q.get("reconstruction_error_mean")})
    return out


def transfer_cases() -> list[sv.Case]:
    """On catalogued conditions (no joint choice): every tool–holder campaign's own stack (its blank, 50 mm gauge,
    40 mm inserted), then each catalogued Ø at 60 N·m, 8 kN at gauges of 3, 4 and 5 Ø."""
    out = [replace(c, name=f"{c.name}: its own stack") for c in tc.TH_CAMPAIGNS]
    for d in DIAMETERS:
        for g in sorted({round(min(max(k * d, 0.025), 0.090), 3) for k in (3.0, 4.0, 5.0)} - {tc.CAMPAIGN_GAUGE}):
            name = f"Ø{d * 1e3:.0f} blank, {g * 1e3:.0f} mm gauge ({g / d:.1f} Ø), 40 mm in, 60 N·m, 8 kN"
            out.append(sv.Case(name, d, g, tc.CAMPAIGN_INSERTION, 60.0, "BT40", 8e3))
    return out


#: Diagnostics (not band results): the same stacks on a catalogue built another way. name → (what it tests,
#: the attributes of ``_stack_truth_c`` it replaces while the catalogue is built).
WHAT_IF = {
    "per_line": ("every campaign identified with `options.method: irc` (no constant k, c anywhere): the adequacy "
                 "check's choice", lambda: {"CAMPAIGN_OPTIONS": {**tc.CAMPAIGN_OPTIONS, "method": "irc"}}),
    "gauge_4d": ("every tool–holder campaign's blank at 4 Ø gauge (Ø6: 25 mm, Ø10: 40 mm, Ø20: 80 mm) instead of "
                 "50 mm for all: the campaigns' test tool", lambda: {"TH_CAMPAIGNS": [
                     replace(c, gauge=max(round(4 * c.diameter, 3), 0.025)) for c in tc.TH_CAMPAIGNS]}),
}


def what_if(name: str, folder: Path, n: int, seeds) -> dict:
    """The stacks of ``seeds`` predicted on the catalogue of :data:`WHAT_IF` ``name``, built in ``folder`` (reused
    with its rows, ``folder/rows.json``, when they are there)."""
    from jointdb.store import Repository

    rows = folder / "rows.json"
    if rows.exists():
        return json.loads(rows.read_text(encoding="utf-8"))
    changes = WHAT_IF[name][1]()
    old = {k: getattr(tc, k) for k in changes}
    for k, v in changes.items():
        setattr(tc, k, v)
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with Repository(f"sqlite:///{folder / 'b.sqlite'}") as repo:
            if not repo.list_joints():
                tc.build_catalogue(folder, repo, say=lambda s: None)
            out = {str(k): v for k, v in bb._seeds(repo, n, bb.N_SAMPLES, seeds, print).items()}
    finally:
        for k, v in old.items():
            setattr(tc, k, v)
    rows.write_text(json.dumps(out, default=str) + "\n", encoding="utf-8")
    return out


def where(case: sv.Case) -> dict:
    """Where a stack lies against the catalogue's lines (diameter and torque: on a line or the gap between)."""
    def gap(v, lines):
        if any(abs(v - x) < 1e-9 * max(1.0, x) for x in lines):
            return "on a line"
        lo = max(x for x in lines if x < v)
        hi = min(x for x in lines if x > v)
        return f"{lo:g}–{hi:g}"
    return {"diameter_gap": gap(case.diameter * 1e3, [d * 1e3 for d in DIAMETERS]),
            "torque_gap": gap(case.torque, TORQUES), "gauge_over_d": case.gauge / case.diameter}


def _misses_table(results: dict) -> list[str]:
    lines = ["| stack | Ø gap [mm] | torque gap [N·m] | gauge / Ø | peak error | peak band ± | floor error | "
             "floor band ± | missed | dominant term |", "|---|---|---|---|---|---|---|---|---|---|"]
    for seed, res in results.items():
        cases = {c.name: c for c in tc.draw(len(res["rows"]), int(seed))}
        for r in res["rows"]:
            missed = [k for k in ("peak", "floor") if r.get(f"{k}_band") and not r[f"{k}_covered"]]
            if not missed:
                continue
            w = where(cases[r["case"]])
            lines.append(f"| {r['case']} | {w['diameter_gap']} | {w['torque_gap']} | {w['gauge_over_d']:.1f} | "
                         f"{r['peak_err']:+.1%} | {r['peak_half']:.1%} | {r['floor_err']:+.1%} | "
                         f"{r['floor_half']:.1%} | "
                         f"{' and '.join(missed)} | {r['dominant_term']} |")
    return lines


def _by_gap(results: dict) -> list[str]:
    """Coverage and median |error| by where the stack lies against the diameter lines."""
    groups: dict[str, list[dict]] = {}
    for seed, res in results.items():
        cases = {c.name: c for c in tc.draw(len(res["rows"]), int(seed))}
        for r in res["rows"]:
            groups.setdefault(where(cases[r["case"]])["diameter_gap"], []).append(r)
    lines = ["| Ø against the lines | stacks | peak inside | peak median abs error | floor inside | "
             "floor median abs error |", "|---|---|---|---|---|---|"]
    for key in sorted(groups):
        s = bb.summary(groups[key])
        lines.append(f"| {key} | {len(groups[key])} | {s['peak']['covered']} | {s['peak']['median_abs_err']:.1%} | "
                     f"{s['floor']['covered']} | {s['floor']['median_abs_err']:.1%} |")
    return lines


def _own_stack_bound(extra: dict) -> str:
    """Does the kept joint's recorded dominant-peak score (× the 25 % amplitude tolerance) bound the peak error of
    its own stack?"""
    from jointdb.coupling._quality import PEAK_AMPLITUDE_TOL

    kept = {j["joint"]: j["constant_peak_score"] if j["kept"].startswith("constant") else j["per_line_peak_score"]
            for j in extra["catalogue"]}
    own = [(r, kept[r["case"].split(":")[0]]) for r in extra["transfer"] if r["case"].endswith("its own stack")]
    n = sum(abs(r["peak_err"]) <= score * PEAK_AMPLITUDE_TOL for r, score in own)
    return (f"The kept joint's recorded dominant-peak score (quality `model_adequacy.*_peak_score`) × the "
            f"{PEAK_AMPLITUDE_TOL:.0%} amplitude tolerance bounds the peak error of its own stack on {n} of "
            f"{len(own)} tool–holder joints.")


def _joints_table(joints: list[dict]) -> list[str]:
    lines = ["| joint | kept | constant k, c misfit / noise | dominant peaks (constant / per-line, × tolerance) | "
             "assembly reconstruction error (mean) |", "|---|---|---|---|---|"]
    for j in joints:
        lines.append(f"| {j['joint']} | {j['kept']} | {j['misfit_to_noise']:.1f} | {j['constant_peak_score']:.2f} / "
                     f"{j['per_line_peak_score']:.2f} | {j['reconstruction_error_mean']:.1%} |")
    return lines


def _summary_table(results: dict, label: str) -> list[str]:
    from _stack_bands_report import _summary_rows

    lines = ["| seed | quantity | stacks with a band | truth inside the 90 % band | median half-width | "
             "median abs error | half-width / error |", "|---|---|---|---|---|---|---|"]
    for seed, res in results.items():
        lines += _summary_rows(int(seed), res["summary"])
    pooled = [r for res in results.values() for r in res["rows"]]
    return lines + _summary_rows(f"{label} ({len(pooled)} stacks)", bb.summary(pooled))


def section(results: dict, extra: dict) -> str:
    """The generated part of the page: ``results`` {seed: {rows, summary}}; ``extra``: catalogue, catalogue_b,
    transfer (each may be None) and what_if ({name: results})."""
    from _stack_bands_report import _rows_table

    lines = [BEGIN, "", "Generated by `bench/bench_stack_bands_c.py` from the rows of "
             "`bench/bench_stack_bands.py --family c` (do not edit between the markers).", "",
             *_summary_table(results, "both seeds")]
    pooled = [r for res in results.values() for r in res["rows"]]
    no_band = [r["case"] for r in pooled if r.get("peak_band") is None]
    interp = [r for r in pooled if any("interpolation" in m for m in r["methods"].values())]
    lines += ["", f"Interpolated predictions: {len(interp)} of {len(pooled)}; with a band: "
              f"{sum(r.get('peak_band') is not None for r in interp)} of {len(interp)}"
              + (f"; no band: {', '.join(no_band)}" if no_band else "") + ".", "",
              "### Misses and their conditions", "", *_misses_table(results), "",
              "### By position against the diameter lines (both seeds)", "", *_by_gap(results), ""]
    for seed, res in results.items():
        terms = Counter(r["dominant_term"] for r in res["rows"])
        lines += [f"### Seed {seed}", "", *_rows_table(res["rows"]), "", "Dominant term over the stacks: "
                  + ", ".join(f"{term}: {count}" for term, count in sorted(terms.items())) + ".", ""]
    lines += ["### The catalogue's joints", "", *_joints_table(extra["catalogue"])]
    if extra.get("catalogue_b"):
        lines += ["", "For comparison, family B's catalogue (`bench/_stack_truth_b.py`, built the same way):", "",
                  *_joints_table(extra["catalogue_b"])]
    if extra.get("transfer"):
        lines += ["", "### Transfer sweep: catalogued conditions (no joint choice): each campaign's own stack, "
                  "then other gauges", "", *_rows_table(extra["transfer"]), "", _own_stack_bound(extra)]
    for name, what in (extra.get("what_if") or {}).items():
        lines += ["", f"### Diagnostic ({name}): the same stacks on a catalogue built another way", "",
                  f"{WHAT_IF[name][0][0].upper()}{WHAT_IF[name][0][1:]}; not a band result.", "",
                  *_summary_table(what, "both seeds"), "",
                  *_rows_table([r for res in what.values() for r in res["rows"]])]
    lines += ["", END]
    return "\n".join(lines)


def write(doc: Path, results: dict, extra: dict) -> None:
    text = doc.read_text(encoding="utf-8") if doc.exists() else "# The band on truth family C\n"
    new = section(results, extra)
    if BEGIN in text and END in text:
        text = text[:text.index(BEGIN)] + new + text[text.index(END) + len(END):]
    else:
        text = text.rstrip("\n") + "\n\n" + new + "\n"
    doc.write_text(text, encoding="utf-8")
    payload = {"seeds": results, **extra}
    doc.with_suffix(".json").write_text(json.dumps(payload, indent=1, default=str) + "\n", encoding="utf-8")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--catalogue", type=Path, required=True, help="the --catalogue folder of the family-C run")
    ap.add_argument("--rows", type=Path, nargs="+", required=True, help="--rows-out files of the family-C run")
    ap.add_argument("--doc", type=Path, required=True)
    ap.add_argument("--no-transfer", action="store_true")
    ap.add_argument("--b-catalogue", type=Path, default=None,
                    help="a family-B --catalogue folder of bench/bench_stack_bands.py: list its joints for comparison")
    ap.add_argument("--what-if", nargs=2, action="append", default=[], metavar=("NAME", "FOLDER"),
                    help=f"also predict the stacks on another catalogue ({', '.join(WHAT_IF)}), kept in FOLDER "
                         "with its rows (≈ 10 min loaded each; reused when there)")
    args = ap.parse_args(argv)
    from jointdb.store import Repository

    bb.tb = tc
    results: dict = {}
    for part in args.rows:
        got = json.loads(part.read_text(encoding="utf-8"))
        results.update({k: v for k, v in got.items() if k.isdigit()})
    results = dict(sorted(results.items()))
    t0 = time.time()
    extra: dict = {"catalogue_b": None, "transfer": None, "what_if": {}}
    with Repository(f"sqlite:///{args.catalogue / 'b.sqlite'}") as repo:
        extra["catalogue"] = joint_rows(repo)
        if not args.no_transfer:
            extra["transfer"] = []
            for case in transfer_cases():
                r = bb.band_row(case, repo)
                extra["transfer"].append(r)
                print(f"  {r['case']}: peak {r['peak_err']:+.1%} ±{r['peak_half']:.1%}, "
                      f"floor {r['floor_err']:+.1%} ±{r['floor_half']:.1%}", flush=True)
    if args.b_catalogue is not None:
        import _stack_truth_b as tb

        with Repository(f"sqlite:///{args.b_catalogue / 'b.sqlite'}") as repo:
            extra["catalogue_b"] = joint_rows(repo, tb)
    n = len(next(iter(results.values()))["rows"])
    for name, folder in args.what_if:
        if name not in WHAT_IF:
            ap.error(f"--what-if {name}: use one of {', '.join(WHAT_IF)}")
        extra["what_if"][name] = what_if(name, Path(folder), n, [int(s) for s in results])
    extra["seconds"] = time.time() - t0
    write(args.doc, results, extra)
    print(f"wrote {args.doc} and {args.doc.with_suffix('.json')} ({extra['seconds']:.0f} s)")


if __name__ == "__main__":
    main()
