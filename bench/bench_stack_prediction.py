#!/usr/bin/env python
"""Stack prediction checked on tool tips the catalogue never saw; writes docs/validation/stack-prediction.md.

1. Writes 6 holder–spindle and 7 tool–holder IRC campaigns "measured" on a
   structurally richer truth model (``bench/_stack_validation.py``: contact
   layers at both interfaces, spindle with rotor mass on bearings, fluted
   sections with their true mass), identifies and catalogues them into a
   temporary SQLite database.
2. Predicts 6 other stacks inside the catalogued range and 2 outside it from
   the catalogue (both interfaces queried, joints interpolated between the two
   nearest) and with rigid joints, and compares the dominant-mode frequency,
   its peak amplitude and the milling lobe floor with the truth.

Run: ``OPENBLAS_NUM_THREADS=1 .venv/bin/python bench/bench_stack_prediction.py [--out docs/validation]``
(about 1–2 minutes; it catalogues twice: with the model-adequacy check and, for comparison, without it).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import numpy as np  # noqa: E402

import _stack_validation as sv  # noqa: E402

GOALS = {"freq": 0.03, "peak": 0.20, "floor": 0.20}


def _pct(x: float) -> str:
    return f"{x * 100:+.1f} %"


def report(rows: list[dict], catalogue: list[dict], seconds: float) -> str:
    inside = [r for r in rows if not r["outside"]]
    lines = [
        "# Stack prediction checked on tool tips the catalogue never saw",
        "",
        "Produced by `bench/bench_stack_prediction.py` (do not edit by hand; rerun it).",
        "",
        "## Set-up",
        "",
        "The \"measurements\" come from one finite-element model of the whole stack that is richer than the",
        "prediction path: the tool shank sits in the holder bore on a distributed **contact layer** (translation",
        "and rotation springs per unit length, growing as (T / 80 N·m)^0.5, loss factor 0.05); the holder's taper",
        "sits in the spindle nose on another contact layer (HSK-A63: 32 mm, stiff in rotation through its face",
        "contact; BT40: 65 mm, softer; growing as (F / 20 kN)^0.35 with the drawbar force F); the spindle shaft",
        "runs on two bearing sets (springs + viscous dampers) and carries its motor rotor (3 kg); fluted sections",
        "have the Kops–Vo bending stiffness but the mass of their true section (60 % of the full circle).",
        "",
        "The prediction path knows none of this: three beams (tool overhang, holder with a bonded shank, the",
        "spindle's receptance at its nose), joined at two points by 2×2 joint receptances from the catalogue.",
        "The spindle receptance (x and rotation at the nose) is given as measured on the truth spindle alone",
        "(exact, no noise: in practice it comes from `jointdb rotations`, whose noise amplification adds to the",
        "errors below).",
        "",
        f"Catalogue: {len(catalogue)} IRC campaigns on the truth model, 0.2 % noise, 6 significant digits —",
        "holder–spindle: HSK-A63 at 12 / 18 / 24 kN and BT40 at 8 / 12 / 16 kN (B = holder with a bonded Ø12",
        "arbor); tool–holder, on the HSK-A63 18 kN machine (A = holder on the spindle through that catalogued",
        "taper joint): Ø10 and Ø16 blanks at 40 / 120 N·m, Ø12 at 40 / 80 / 120 N·m, 45 mm gauge, 35 mm",
        "inserted.",
        "",
        "The contact layers make each effective joint frequency dependent. Every campaign is identified with",
        "the default method (output-error fit of constant k, c) and its model-adequacy check: the constant",
        "model's misfit of the measured assembly is compared with the noise the data show (line-to-line",
        "roughness of the residual); beyond 2× the per-line IRC joint is kept, if it also reproduces the",
        "measured dominant peaks better. *Kept* says which joint was catalogued; k, c are the constant fit",
        "of the catalogued joint over 100–5000 Hz (a summary only when the per-line joint is kept).",
        "",
        "| joint | type | k_x [N/m] | k_θ [N·m/rad] | c_x [N·s/m] | constant-model misfit / noise | kept |",
        "|---|---|---|---|---|---|---|",
    ]
    for c in catalogue:
        ratio = c.get("misfit_to_noise")
        lines.append(f"| {c['joint']} | {c['type']} | {c['k_x_n_per_m']:.3e} | {c['k_theta_nm_per_rad']:.3e} | "
                     f"{c['c_x_ns_per_m']:.0f} | {'—' if ratio is None else f'{ratio:.0f}×'} | "
                     f"{c.get('kept') or '—'} |")
    lines += [
        "",
        "Each validation stack is predicted with both interfaces queried from the catalogue (conditions:",
        "materials, torque / drawbar force, shank or taper diameter; joints interpolated between the two",
        "nearest), and with rigid joints. Dominant mode = the largest |H_xx| peak between 100 and 5000 Hz",
        "(parabolic refinement on the 10 Hz grid); lobe floor = the smallest stable depth of cut (zero-order",
        "milling lobes, 4 teeth, aluminium 7075, half immersion, down-milling, x and y = the same plane).",
        "",
        "## Results",
        "",
        "Errors relative to the truth. *Catalogue*: joints from the database, fluted mass given",
        "(`tool.fluted_area_ratio` = 0.6). *Cylinder mass*: the same joints but the default fluted model",
        "(mass of the Kops–Vo cylinder). *Rigid*: both joints rigid.",
        "",
        "| stack | truth: f [Hz] / peak [m/N] / floor [mm] | catalogue: f / peak / floor | cylinder mass: f / peak |"
        " rigid: f / peak / floor | extrapolation warning |",
        "|---|---|---|---|---|---|",
    ]
    for r in rows:
        cyl = (f"{_pct(r['cat_cylinder_mass_freq_err'])} / {_pct(r['cat_cylinder_mass_peak_err'])}"
               if r["fluted"] else "(no flutes)")
        lines.append(
            f"| {r['case']} | {r['truth_hz']:.0f} / {r['truth_peak']:.2e} / {r['truth_floor_mm']:.3f} | "
            f"{_pct(r['cat_freq_err'])} / {_pct(r['cat_peak_err'])} / {_pct(r['cat_floor_err'])} | {cyl} | "
            f"{_pct(r['rigid_freq_err'])} / {_pct(r['rigid_peak_err'])} / {_pct(r['rigid_floor_err'])} | "
            f"{'yes' if r['extrapolating'] else 'no'} |")

    def worst(key, which):
        return max(abs(r[f"{which}_{key}_err"]) for r in inside)

    def median(key, which):
        return float(np.median([abs(r[f"{which}_{key}_err"]) for r in inside]))

    met = {k: sum(abs(r[f"cat_{k}_err"]) <= g for r in inside) for k, g in GOALS.items()}
    swaps = [r for r in inside if abs(r["cat_freq_err"]) > GOALS["freq"]]
    for r in swaps:
        lines += ["", f"*{r['case']}*: the predicted resonance nearest the truth's dominant one is "
                  f"{_pct(r['cat_near_freq_err'])} off (on the 10 Hz grid); the catalogue prediction makes another of its "
                  "peaks the largest, so the dominant-mode comparison jumps to that mode (two modes of similar "
                  "height; their ratio is what the prediction gets wrong)."]
    lines += [
        "",
        f"Inside the catalogued range ({len(inside)} stacks), |error| median / worst:",
        "",
        "| | frequency | peak | lobe floor |",
        "|---|---|---|---|",
        f"| catalogue | {median('freq', 'cat'):.1%} / {worst('freq', 'cat'):.1%} | "
        f"{median('peak', 'cat'):.1%} / {worst('peak', 'cat'):.1%} | "
        f"{median('floor', 'cat'):.1%} / {worst('floor', 'cat'):.1%} |",
        f"| rigid joints | {median('freq', 'rigid'):.1%} / {worst('freq', 'rigid'):.1%} | "
        f"{median('peak', 'rigid'):.1%} / {worst('peak', 'rigid'):.1%} | "
        f"{median('floor', 'rigid'):.1%} / {worst('floor', 'rigid'):.1%} |",
        "| goal | 3 % | 20 % | 20 % |",
        f"| stacks meeting the goal (catalogue) | {met['freq']} of {len(inside)} | {met['peak']} of {len(inside)} |"
        f" {met['floor']} of {len(inside)} |",
        "",
        "Rigid / catalogue ratio of the median |error|: "
        f"frequency {median('freq', 'rigid') / max(median('freq', 'cat'), 1e-12):.0f}×, "
        f"peak {median('peak', 'rigid') / max(median('peak', 'cat'), 1e-12):.0f}×, "
        f"lobe floor {median('floor', 'rigid') / max(median('floor', 'cat'), 1e-12):.0f}×.",
        "",
        "Outside the catalogued range the query reports the extrapolation on every stack marked *yes* above",
        "(`outside the catalogued range` warning in `jointdb predict`; `extrapolating` in its JSON):",
        "",
    ]
    for r in rows:
        if r["outside"]:
            lines.append(f"- {r['case']}: " + ("; ".join(r["warnings"]) or "NO WARNING"))
    lines += ["", f"Run time: {seconds:.0f} s.", ""]
    return "\n".join(lines)


def constant_only(rows: list[dict]) -> list[str]:
    """Report lines for the ablation: the same stacks from a catalogue of constant output-error joints."""
    inside = [r for r in rows if not r["outside"]]
    lines = ["", "## Without the model-adequacy check", "",
             "The same campaigns catalogued with the check switched off (the output-error constant k, c kept",
             "for every joint, as the default did before the check), the same stacks predicted:", "",
             "| stack | constant k, c catalogue: f / peak / floor | predicted resonance nearest the truth's |",
             "|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['case']} | {_pct(r['cat_freq_err'])} / {_pct(r['cat_peak_err'])} / "
                     f"{_pct(r['cat_floor_err'])} | {_pct(r['cat_near_freq_err'])} |")
    met = {k: sum(abs(r[f"cat_{k}_err"]) <= g for r in inside) for k, g in GOALS.items()}
    med = {k: float(np.median([abs(r[f"cat_{k}_err"]) for r in inside])) for k in GOALS}
    lines += ["", f"Inside the range: median |error| frequency {med['freq']:.1%}, peak {med['peak']:.1%}, lobe floor "
              f"{med['floor']:.1%}; stacks meeting the goals {met['freq']} / {met['peak']} / {met['floor']} of "
              f"{len(inside)} (frequency / peak / floor)."]
    return lines


def _predict_all(tmp: Path, say=print) -> tuple[list[dict], list[dict]]:
    from jointdb.store import Repository

    with Repository(f"sqlite:///{tmp / 'joints.sqlite'}") as repo:
        catalogue = sv.build_catalogue(tmp, repo, say=say)
        rows = []
        for outside, cases in ((False, sv.VALIDATION), (True, sv.OUTSIDE)):
            for case in cases:
                r = sv.validate(case, repo)
                r["outside"], r["fluted"] = outside, case.fluted > 0
                rows.append(r)
                say(f"{case.name}: catalogue f {_pct(r['cat_freq_err'])}, peak {_pct(r['cat_peak_err'])}, "
                    f"floor {_pct(r['cat_floor_err'])} | rigid f {_pct(r['rigid_freq_err'])}, "
                    f"peak {_pct(r['rigid_peak_err'])}, floor {_pct(r['rigid_floor_err'])}"
                    f"{' | EXTRAPOLATING' if r['extrapolating'] else ''}")
    return catalogue, rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=HERE.parent / "docs" / "validation")
    args = ap.parse_args(argv)
    import jointdb.campaign._adequacy as adequacy

    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        print("cataloguing the campaigns measured on the truth model ...")
        catalogue, rows = _predict_all(Path(tmp))
    limit = adequacy.MISFIT_TO_NOISE_LIMIT
    with tempfile.TemporaryDirectory() as tmp:
        print("again with the model-adequacy check off (constant k, c for every joint) ...")
        adequacy.MISFIT_TO_NOISE_LIMIT = float("inf")
        try:
            _, constant_rows = _predict_all(Path(tmp))
        finally:
            adequacy.MISFIT_TO_NOISE_LIMIT = limit
    seconds = time.perf_counter() - t0
    args.out.mkdir(parents=True, exist_ok=True)
    text = report(rows, catalogue, seconds).rstrip("\n").split("\n")
    text[-1:-1] = constant_only(constant_rows) + [""]
    (args.out / "stack-prediction.md").write_text("\n".join(text) + "\n", encoding="utf-8")
    (args.out / "stack-prediction.json").write_text(
        json.dumps({"rows": rows, "catalogue": catalogue, "constant_only_rows": constant_rows}, indent=1,
                   default=str) + "\n", encoding="utf-8")
    print(f"wrote {args.out / 'stack-prediction.md'} ({seconds:.0f} s)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
