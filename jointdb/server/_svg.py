"""Server-side SVG plot of FRF entries: magnitude (log scale) and phase against frequency,
with axis units; several versions overlaid in distinct colours. No JavaScript."""

from __future__ import annotations

import html
import math

import numpy as np

COLOURS = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#17becf")
W, H, LEFT, RIGHT, TOP, GAP, PANEL = 760, 520, 80, 20, 30, 50, 200


def _ticks(lo: float, hi: float, n: int = 5) -> list[float]:
    return list(np.linspace(lo, hi, n))


def _path(x: np.ndarray, y: np.ndarray) -> str:
    pts = [f"{a:.1f},{b:.1f}" for a, b in zip(x, y) if math.isfinite(a) and math.isfinite(b)]
    return "M" + " L".join(pts) if pts else ""


def frf_svg(curves: list[tuple[str, object]], title: str = "") -> str:
    """``curves``: ``(legend, FRF)`` pairs; every diagonal entry of each FRF is drawn.

    Returns an ``<svg>`` element (magnitude panel above, phase panel below).
    """
    from jointdb.io import unit_label

    lines = []
    for k, (legend, frf) in enumerate(curves):
        for i in range(min(frf.values.shape[1], frf.values.shape[2])):
            h = frf.values[:, i, i]
            unit = unit_label(frf.quantity, frf.outputs[i], frf.inputs[i])
            lines.append((f"{legend} {frf.outputs[i]}/{frf.inputs[i]} [{unit}]", frf.freq, h, unit,
                          COLOURS[(k * 2 + i) % len(COLOURS)], "" if k == 0 else "6,3"))
    fmin = min(float(f[0]) for _, f, *_ in lines)
    fmax = max(float(f[-1]) for _, f, *_ in lines)
    mags = np.concatenate([np.abs(h)[np.abs(h) > 0] for _, _, h, *_ in lines])
    lo, hi = math.floor(math.log10(mags.min())), math.ceil(math.log10(mags.max()))
    hi = hi if hi > lo else lo + 1
    pw = W - LEFT - RIGHT

    def sx(f):
        return LEFT + (np.asarray(f) - fmin) / (fmax - fmin or 1.0) * pw

    def sy_mag(h):
        return TOP + (hi - np.log10(np.maximum(np.abs(h), 10.0**lo))) / (hi - lo) * PANEL

    top2 = TOP + PANEL + GAP

    def sy_phase(h):
        return top2 + (180 - np.degrees(np.angle(h))) / 360 * PANEL

    units = sorted({u for *_, u, _, _ in lines})
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {W} {H + 20 * len(lines)}" '
           f'class="frf-plot" role="img" aria-label="{html.escape(title)}">',
           f'<text x="{LEFT}" y="18" class="title">{html.escape(title)}</text>']
    for top in (TOP, top2):
        out.append(f'<rect x="{LEFT}" y="{top}" width="{pw}" height="{PANEL}" class="frame"/>')
        for f in _ticks(fmin, fmax):
            x = float(sx(f))
            out.append(f'<line x1="{x:.1f}" y1="{top}" x2="{x:.1f}" y2="{top + PANEL}" class="grid"/>')
            out.append(f'<text x="{x:.1f}" y="{top + PANEL + 14}" class="tick" text-anchor="middle">{f:.0f}</text>')
    for e in range(lo, hi + 1):
        y = TOP + (hi - e) / (hi - lo) * PANEL
        out.append(f'<line x1="{LEFT}" y1="{y:.1f}" x2="{LEFT + pw}" y2="{y:.1f}" class="grid"/>')
        out.append(f'<text x="{LEFT - 6}" y="{y + 4:.1f}" class="tick" text-anchor="end">1e{e}</text>')
    for deg in (-180, -90, 0, 90, 180):
        y = top2 + (180 - deg) / 360 * PANEL
        out.append(f'<line x1="{LEFT}" y1="{y:.1f}" x2="{LEFT + pw}" y2="{y:.1f}" class="grid"/>')
        out.append(f'<text x="{LEFT - 6}" y="{y + 4:.1f}" class="tick" text-anchor="end">{deg}</text>')
    out.append(f'<text x="16" y="{TOP + PANEL / 2}" class="axis" transform="rotate(-90 16 {TOP + PANEL / 2})" '
               f'text-anchor="middle">|H| [{html.escape(", ".join(units))}]</text>')
    out.append(f'<text x="16" y="{top2 + PANEL / 2}" class="axis" transform="rotate(-90 16 {top2 + PANEL / 2})" '
               f'text-anchor="middle">phase [deg]</text>')
    out.append(f'<text x="{LEFT + pw / 2}" y="{top2 + PANEL + 32}" class="axis" text-anchor="middle">'
               'frequency [Hz]</text>')
    for n, (legend, f, h, _, colour, dash) in enumerate(lines):
        style = f'stroke="{colour}" fill="none" stroke-width="1.5"' + (f' stroke-dasharray="{dash}"' if dash else "")
        out.append(f'<path class="curve" d="{_path(sx(f), sy_mag(h))}" {style}/>')
        out.append(f'<path class="curve" d="{_path(sx(f), sy_phase(h))}" {style}/>')
        y = H + 20 * n + 6
        out.append(f'<line x1="{LEFT}" y1="{y}" x2="{LEFT + 30}" y2="{y}" {style}/>')
        out.append(f'<text x="{LEFT + 36}" y="{y + 4}" class="legend">{html.escape(legend)}</text>')
    out.append("</svg>")
    return "\n".join(out)
