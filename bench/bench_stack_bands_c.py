"""The band on truth family C (never used to tune it): the page docs/validation/stack-bands-family-c.md.

The stacks are predicted by ``bench/bench_stack_bands.py --family c`` (the same pipeline as family B: catalogue
through ``usecases.catalogue_campaign``, stacks drawn with a seed, ``predict_stack`` + ``band_terms``); this
script adds what explains the result and writes the page's generated part and its JSON:

- the catalogue's joints: which model each campaign kept (constant k, c or per-line), how far constant k, c
  misfits its own campaign (× the noise) and how well the kept joint reproduces the campaign's assembly;
- a *transfer sweep*: stacks ON catalogued conditions (Ø6 / Ø10 / Ø20 at 60 N·m on the 8 kN machine, no joint
  choice at all) at other gauges than the campaigns' 50 mm: the error of carrying a catalogued joint to another
  tool, which only the prediction-path term of the band can carry.

One command, the reported run (≈ 25 min on a loaded 2-core machine, catalogue included):

    python bench/bench_stack_bands.py --family c --n 24 --catalogue /tmp/c --rows-out /tmp/c-rows.json
    python bench/bench_stack_bands_c.py --catalogue /tmp/c --rows /tmp/c-rows.json --doc docs/validation/stack-bands-family-c.md

(add ``--no-transfer`` to skip the sweep, ≈ 5 min). The page's text outside the generated markers is kept.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import _stack_truth_c as tc  # noqa: E402
import _stack_validation as sv  # noqa: E402
import bench_stack_bands as bb  # noqa: E402

BEGIN, END = "<!-- family-c:begin -->", "<!-- family-c:end -->"
DIAMETERS = tuple(d for d, _ in tc.TH_GRID)
TORQUES = tc.TH_GRID[0][1]


def joint_rows(repo) -> list[dict]:
    """Per catalogued joint of family C: the model its campaign kept and how well it fits that campaign."""
    out = []
    for case in [*tc.HS_CAMPAIGNS, *tc.TH_CAMPAIGNS]:
        v = repo.get(case.name)
        q = {k.removeprefix("model_adequacy."): x for k, x in (v.quality or {}).items()}
        out.append({"joint": case.name,
                    "kept": "constant k, c" if v.provenance.method.startswith("output-error") else "per-line",
                    "misfit_to_noise": q.get("misfit_to_noise"), "constant_peak_score": q.get("constant_peak_score"),
                    "per_line_peak_score": q.get("per_line_peak_score"),
                    "reconstruction_error_mean": q.get("reconstruction_error_mean")})
    return out


def transfer_cases() -> list[sv.Case]:
    """On catalogued conditions (no joint choice): each catalogued Ø at 60 N·m, 8 kN, gauges 3, 4, 5 Ø and 50 mm."""
    out = []
    for d in DIAMETERS:
        for g in sorted({round(min(max(k * d, 0.025), 0.090), 3) for k in (3.0, 4.0, 5.0)} | {tc.CAMPAIGN_GAUGE}):
            out.append(sv.Case(f"Ø{d * 1e3:.0f} blank, {g * 1e3:.0f} mm gauge ({g / d:.1f} Ø), 40 mm in, 60 N·m, 8 kN",
                               d, g, tc.CAMPAIGN_INSERTION, 60.0, "BT40", 8e3))
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
                         f"{r['peak_err']:+.1%} | {r['peak_half']:.1%} | {r['floor_err']:+.1%} | {r['floor_half']:.1%} | "
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


def section(results: dict, joints: list[dict], transfer: list[dict] | None) -> str:
    from _stack_bands_report import _rows_table, _summary_rows

    lines = [BEGIN, "", "Generated by `bench/bench_stack_bands_c.py` from the rows of "
             "`bench/bench_stack_bands.py --family c` (do not edit between the markers).", "",
             "| seed | quantity | stacks with a band | truth inside the 90 % band | median half-width | "
             "median abs error | half-width / error |", "|---|---|---|---|---|---|---|"]
    for seed, res in results.items():
        lines += _summary_rows(int(seed), res["summary"])
    pooled = [r for res in results.values() for r in res["rows"]]
    lines += _summary_rows(f"both seeds ({len(pooled)} stacks)", bb.summary(pooled))
    no_band = [r["case"] for r in pooled if r.get("peak_band") is None]
    interp = [r for r in pooled if any("interpolation" in m for m in r["methods"].values())]
    lines += ["", f"Interpolated predictions: {len(interp)} of {len(pooled)}; with a band: "
              f"{sum(r.get('peak_band') is not None for r in interp)} of {len(interp)}"
              + (f"; no band: {', '.join(no_band)}" if no_band else "") + ".", "",
              "### Misses and their conditions", "", *_misses_table(results), "",
              "### By position against the diameter lines (both seeds)", "", *_by_gap(results), ""]
    for seed, res in results.items():
        dom: dict[str, int] = {}
        for r in res["rows"]:
            dom[r["dominant_term"]] = dom.get(r["dominant_term"], 0) + 1
        lines += [f"### Seed {seed}", "", *_rows_table(res["rows"]), "",
                  "Dominant term over the stacks: " + ", ".join(f"{k}: {v}" for k, v in sorted(dom.items())) + ".", ""]
    lines += ["### The catalogue's joints", "", "| joint | kept | constant k, c misfit / noise | dominant peaks "
              "(constant / per-line, × tolerance) | assembly reconstruction error (mean) |", "|---|---|---|---|---|"]
    for j in joints:
        lines.append(f"| {j['joint']} | {j['kept']} | {j['misfit_to_noise']:.1f} | {j['constant_peak_score']:.2f} / "
                     f"{j['per_line_peak_score']:.2f} | {j['reconstruction_error_mean']:.1%} |")
    if transfer:
        lines += ["", "### Transfer sweep: catalogued conditions, other gauges (no joint choice)", "",
                  *_rows_table(transfer)]
    lines += ["", END]
    return "\n".join(lines)


def write(doc: Path, results: dict, joints: list[dict], transfer: list[dict] | None, seconds: float) -> None:
    text = doc.read_text(encoding="utf-8") if doc.exists() else "# The band on truth family C\n"
    new = section(results, joints, transfer)
    if BEGIN in text and END in text:
        text = text[:text.index(BEGIN)] + new + text[text.index(END) + len(END):]
    else:
        text = text.rstrip("\n") + "\n\n" + new + "\n"
    doc.write_text(text, encoding="utf-8")
    payload = {"seeds": results, "catalogue": joints, "transfer": transfer, "transfer_seconds": seconds}
    doc.with_suffix(".json").write_text(json.dumps(payload, indent=1, default=str) + "\n", encoding="utf-8")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--catalogue", type=Path, required=True, help="the --catalogue folder of the family-C run")
    ap.add_argument("--rows", type=Path, nargs="+", required=True, help="--rows-out files of the family-C run")
    ap.add_argument("--doc", type=Path, required=True)
    ap.add_argument("--no-transfer", action="store_true")
    args = ap.parse_args(argv)
    from jointdb.store import Repository

    results: dict = {}
    for part in args.rows:
        got = json.loads(part.read_text(encoding="utf-8"))
        results.update({k: v for k, v in got.items() if k.isdigit()})
    t0 = time.time()
    with Repository(f"sqlite:///{args.catalogue / 'b.sqlite'}") as repo:
        joints = joint_rows(repo)
        transfer = None
        if not args.no_transfer:
            bb.tb = tc
            transfer = []
            for case in transfer_cases():
                transfer.append(bb.band_row(case, repo))
                r = transfer[-1]
                print(f"  {r['case']}: peak {r['peak_err']:+.1%} ±{r['peak_half']:.1%}, "
                      f"floor {r['floor_err']:+.1%} ±{r['floor_half']:.1%}", flush=True)
    write(args.doc, dict(sorted(results.items())), joints, transfer, time.time() - t0)
    print(f"wrote {args.doc} and {args.doc.with_suffix('.json')} ({time.time() - t0:.0f} s)")


if __name__ == "__main__":
    main()
