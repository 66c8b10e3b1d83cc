"""Markdown tables of ``bench/bench_stack_bands.py --rows-out`` files: coverage per seed, and what changed per stack
against an earlier rows file of the same seeds (e.g. before a band term was added).

    python bench/_stack_bands_table.py ROWS.json [ROWS2.json ...] [--before OLD.json] [--label 7305=held-out]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np


def _seeds(paths) -> dict[str, dict]:
    out = {}
    for p in paths:
        got = json.loads(Path(p).read_text(encoding="utf-8"))
        out.update({k: v for k, v in got.items() if isinstance(v, dict) and "rows" in v})
    return out


def _cells(rows, key) -> tuple[int, int, float, float]:
    banded = [r for r in rows if r.get(f"{key}_band")]
    inside = sum(bool(r[f"{key}_covered"]) for r in banded)
    half = float(np.median([r[f"{key}_half"] for r in banded])) if banded else float("nan")
    err = float(np.median([abs(r[f"{key}_err"]) for r in banded])) if banded else float("nan")
    return inside, len(banded), half, err


def coverage_table(seeds: dict[str, dict], labels: dict[str, str]) -> str:
    """One row per seed (and per label group, and all): peak and floor inside, median half-width / median |error|."""
    lines = ["| seed | peak inside | median half-width / median abs error | floor inside | half-width / error |",
             "|---|---|---|---|---|"]

    def row(name, rows):
        cells = []
        for key in ("peak", "floor"):
            i, n, h, e = _cells(rows, key)
            cells += [f"{i} / {n} ({i / n:.0%})" if n else "–", f"{h:.1%} / {e:.1%} ({h / e:.1f}×)" if n else "–"]
        lines.append(f"| {name} | " + " | ".join(cells) + " |")

    for seed, v in seeds.items():
        row(f"{seed} ({labels.get(seed, 'seen')})", v["rows"])
    groups: dict[str, list] = {}
    for seed, v in seeds.items():
        groups.setdefault(labels.get(seed, "seen"), []).extend(v["rows"])
    if len(groups) > 1:
        for g, rows in groups.items():
            row(f"all {g} ({len(rows)})", rows)
    row(f"all {sum(len(v['rows']) for v in seeds.values())}", [r for v in seeds.values() for r in v["rows"]])
    return "\n".join(lines)


def change_table(seeds: dict[str, dict], before: dict[str, dict]) -> str:
    """Stacks whose peak or floor verdict changed against ``before`` (same seeds, same stacks)."""
    lines = ["| stack | peak error | band ± before → now | in before → now | floor in before → now | dominant term now |",
             "|---|---|---|---|---|---|"]
    yes = {True: "yes", False: "**no**"}
    for seed, v in seeds.items():
        old = {r["case"]: r for r in before.get(seed, {}).get("rows", [])}
        for r in v["rows"]:
            o = old.get(r["case"])
            if o is None or (o["peak_covered"] == r["peak_covered"] and o["floor_covered"] == r["floor_covered"]):
                continue
            lines.append(f"| {r['case']} | {r['peak_err']:+.1%} | {o['peak_half']:.1%} → {r['peak_half']:.1%} | "
                         f"{yes[o['peak_covered']]} → {yes[r['peak_covered']]} | "
                         f"{yes[o['floor_covered']]} → {yes[r['floor_covered']]} | {r['dominant_term']} |")
    return "\n".join(lines)


def misses(seeds: dict[str, dict]) -> str:
    """The rows with a miss: case, peak error and band, floor error, dominant term, the damping-law term alone, and
    (rows that record them) the truth's and the prediction's dominant-peak frequencies."""
    lines = ["| stack | peak error | peak band ± | in | floor error | in | dominant term | damping law alone ± | "
             "dominant peak truth / predicted [Hz] |", "|---|---|---|---|---|---|---|---|---|"]
    yes = {True: "yes", False: "**no**"}
    for v in seeds.values():
        for r in v["rows"]:
            if r.get("peak_covered", True) and r.get("floor_covered", True):
                continue
            law = (r.get("half_widths") or {}).get("damping law") or {}
            lines.append(f"| {r['case']} | {r['peak_err']:+.1%} | {r['peak_half']:.1%} | {yes[r['peak_covered']]} | "
                         f"{r['floor_err']:+.1%} | {yes[r['floor_covered']]} | {r['dominant_term']} | "
                         f"{law.get('x', 0.0):.1%} | {_hz(r)} |")
    return "\n".join(lines)


def _hz(r: dict) -> str:
    return f"{r['truth_hz']:.0f} / {r['pred_hz']:.0f}" if "truth_hz" in r else "–"


def lines_table(seeds: dict[str, dict]) -> str:
    """Per seed: the grid's last line and how close the truths' dominant peaks come to it."""
    lines = ["| seed | last line [Hz] | largest truth dominant-peak frequency [Hz] | its share of the last line | "
             "truths' dominant |H| on the last line | predictions' |", "|---|---|---|---|---|---|"]
    for seed, v in seeds.items():
        rows = [r for r in v["rows"] if "truth_hz" in r]
        if not rows:
            continue
        top = rows[0]["grid_hz"][1]
        fmax = max(r["truth_hz"] for r in rows)
        lines.append(f"| {seed} | {top:.0f} | {fmax:.0f} | {fmax / top:.2f} | "
                     f"{sum(r['truth_hz'] >= top - 1e-6 for r in rows)} | {sum(r['pred_hz'] >= top - 1e-6 for r in rows)} |")
    return "\n".join(lines)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("rows", type=Path, nargs="+")
    ap.add_argument("--before", type=Path, nargs="*", default=None)
    ap.add_argument("--label", nargs="*", default=[], help="SEED=label (default label: seen)")
    args = ap.parse_args(argv)
    seeds = _seeds(args.rows)
    labels = dict(x.split("=", 1) for x in args.label)
    print(coverage_table(seeds, labels))
    if args.before:
        print()
        print(change_table(seeds, _seeds(args.before)))
    print()
    print(misses(seeds))
    print()
    print(lines_table(seeds))


if __name__ == "__main__":
    main()
