"""Figures of a stack prediction: tool-tip FRF with the database joints against rigid joints.

matplotlib (Agg), imported lazily by the CLI and the main job only.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from jointdb.plots._axes import percent
from jointdb.plots._frf import _pyplot, save_figure

__all__ = ["save_tip_comparison", "tip_comparison_figure", "save_joint_distances", "joint_choice_figure",
           "joints_legend", "rigid_reason"]


def joints_legend(resolutions) -> str:
    """Short legend text naming the joints used: ``"tool-holder: th-er32-carbide-120nm v1"``, or for an
    interpolated joint its neighbours and weights (``"… v1 (w=0.550), … v1 (w=0.450)"``); rigid joints omitted.

    Parameters
    ----------
    resolutions
        Interface name → :class:`jointdb.usecases.JointResolution`.

    Returns
    -------
    str
        ``"rigid"`` when every joint is rigid.
    """
    parts = []
    for name, res in resolutions.items():
        method = getattr(res, "method", "") or ""
        used = getattr(res, "neighbours", ()) or ()
        if res.kind == "interpolated" and used:
            text = ", ".join(f"{n} v{v} (w={w:.3f})" for n, v, w, _ in used)
            parts.append(f"{name}: {method or 'interpolated'} {text}")
        elif res.kind == "interpolated":
            text = res.description.split(" from ", 1)[-1]
            parts.append(f"{name}: interpolated {text}")
        elif res.name:
            parts.append(f"{name}: {res.name} v{res.version}" + (f" ({method})" if method in ("nearest", "edge")
                                                                  else ""))
        elif res.kind == "explicit":
            parts.append(f"{name}: explicit k, c")
    return "; ".join(parts) or "rigid"


#: Micrometres per metre: every panel of the tip figure is in µm/N.
_UM = 1e6


def rigid_reason(tip_peak: tuple[float, float], rigid_peak: tuple[float, float]) -> str:
    """One line saying how the rigid-joint peak differs from the catalogued one, and why.

    Parameters
    ----------
    tip_peak, rigid_peak
        ``(|H| [m/N], frequency [Hz])`` of the largest peak with catalogued and with rigid joints.

    Returns
    -------
    str
    """
    ratio = rigid_peak[0] / tip_peak[0] if tip_peak[0] > 0 else float("inf")
    where = f"at {rigid_peak[1]:.0f} Hz instead of {tip_peak[1]:.0f} Hz"
    if ratio >= 1:
        return (f"rigid joints: peak {ratio:.1f}× higher, {where}: no joint compliance (modes move up), "
                "no joint damping (only the materials' loss factor)")
    return (f"rigid joints: peak {1 / ratio:.1f}× lower, {where}: no joint compliance (modes move up, "
            "the tip is stiffer)")


def _peak(frf, dof) -> tuple[float, float]:
    mag = np.abs(frf.entry(dof, dof))
    k = int(np.argmax(mag))
    return float(mag[k]), float(frf.freq[k])


def save_tip_comparison(path, prediction, **kwargs) -> Path:
    """Write :func:`tip_comparison_figure` of ``prediction`` to the PNG file ``path``.

    Parameters
    ----------
    path
        PNG file to write.
    prediction, **kwargs
        As :func:`tip_comparison_figure` (``title``, ``extra``, ``label``, ``band``).

    Returns
    -------
    Path
    """
    return save_figure(tip_comparison_figure(prediction, **kwargs), path, dpi=120)


def tip_comparison_figure(prediction, *, title: str | None = None, extra: Sequence[tuple[str, object]] = (),
                          label: str = "with catalogued joints", band=None):
    """Tool-tip receptance with the catalogued joints; the rigid-joint comparison in a panel of its own.

    Per direction (x, and y when it differs) three panels, all in µm/N: |H| on a linear scale with
    the 5–95 % band (annotated when thinner than the line), Re and Im, and |H| (log) with
    catalogued against rigid joints under a one-line reason (:func:`rigid_reason`) — the rigid peak
    is often several times higher and would flatten the others.

    Parameters
    ----------
    prediction
        :class:`jointdb.stack.Prediction`.
    title
        Figure title.
    extra
        Further ``(label, FRF)`` curves on the same tip DOFs (e.g. interpolated joints, a measurement),
        drawn in the first two panels.
    label
        Legend of the prediction: name the joint versions (and interpolation
        weights), e.g. with :func:`joints_legend`.
    band
        Optional :class:`jointdb.stack._band.TipBand`: its 5–95 % |H| band is shaded.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import textwrap

    plt = _pyplot()
    tip, rigid = prediction.tip, prediction.rigid
    directions = ["x"]
    if not np.allclose(tip.entry("1y", "1y"), tip.entry("1x", "1x")):
        directions.append("y")
    fig, axes = plt.subplots(3, len(directions), figsize=(7.5 * len(directions), 10.5), sharex=True, squeeze=False,
                             height_ratios=(3, 2, 2))
    curves = [(label, tip, "C0", "-"), *((name, frf, f"C{2 + i}", ":") for i, (name, frf) in enumerate(extra))]
    for col, d in enumerate(directions):
        _tip_panels(axes[:, col], d, curves, rigid, band)
    # one legend for all panels, below them: its labels name joint versions and weights and are long
    handles, names = axes[0, 0].get_legend_handles_labels()
    h2, n2 = axes[2, 0].get_legend_handles_labels()
    handles, names = handles + h2[1:], names + n2[1:]
    names = ["\n".join(textwrap.wrap(n, 110)) for n in names]
    leg = fig.legend(handles, names, loc="lower center", fontsize=7.5, ncol=1, frameon=False)
    fig.suptitle("\n".join(textwrap.wrap(title or "Predicted tool-tip FRF", 100)))
    fig.canvas.draw()
    legend_h = leg.get_window_extent().height / fig.dpi / fig.get_figheight()
    fig.tight_layout(rect=(0, min(0.45, legend_h + 0.02), 1, 1))
    for col, d in enumerate(directions):
        if band is not None and d in band.magnitude:
            _note_thin_band(axes[0, col], band, d)
    return fig


def _tip_panels(axes, d: str, curves, rigid, band) -> None:
    """The three panels of one direction ``d``: |H| with the band, Re/Im, catalogued against rigid."""
    import textwrap

    dof = f"1{d}"
    ax_m, ax_c, ax_r = axes
    for name, frf, colour, style in curves:
        h = frf.entry(dof, dof) * _UM
        ax_m.plot(frf.freq, np.abs(h), style, color=colour, lw=1.4, label=name)
        ax_c.plot(frf.freq, h.real, style, color=colour, lw=1.1)
        ax_c.plot(frf.freq, h.imag, style, color=colour, lw=1.1, alpha=0.45)
    if band is not None and d in band.magnitude:  # 5–95 % of every term of usecases._stack_band.TERMS
        p05, p50, p95 = band.peak[d]
        width = (p95 - p05) / 2 / p50 if p50 > 0 else 0.0
        ax_m.fill_between(band.freq, band.magnitude[d][0] * _UM, band.magnitude[d][2] * _UM, color="tab:orange",
                          alpha=0.45, lw=0, zorder=1.5,
                          label=f"5–95 % band ({band.samples} samples), peak {p05 * _UM:#.3g}–{p95 * _UM:#.3g} µm/N "
                                f"(±{percent(width)})")
    ax_m.set_ylim(0, None)
    ax_m.set_ylabel(f"|H_{d}{d}| [µm/N]")
    ax_m.set_title(f"tool tip, {d} direction")
    ax_c.set_ylabel("Re (dark), Im (light) [µm/N]")
    ax_c.axhline(0, color="0.6", lw=0.6)
    tip = curves[0][1]
    ax_r.semilogy(tip.freq, np.abs(tip.entry(dof, dof)) * _UM, "-", color="C0", lw=1.2, label=curves[0][0])
    ax_r.semilogy(rigid.freq, np.abs(rigid.entry(dof, dof)) * _UM, "--", color="C3", lw=1.2, label="rigid joints")
    ax_r.set_ylabel(f"|H_{d}{d}| [µm/N], log")
    ax_r.set_title("\n".join(textwrap.wrap(rigid_reason(_peak(tip, dof), _peak(rigid, dof)), 100)), fontsize=8.5)
    ax_r.set_xlabel("frequency [Hz]")
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)


def _note_thin_band(ax, band, d: str) -> None:
    """Annotate the band when, at the peak, it is thinner on this axis than twice the line (1.4 pt)."""
    p05, p50, p95 = band.peak[d]
    px_per_unit = ax.get_window_extent().height / (ax.get_ylim()[1] - ax.get_ylim()[0])
    points = (p95 - p05) * _UM * px_per_unit * 72.0 / ax.figure.dpi
    if points < 2 * 1.4:
        width = (p95 - p05) / 2 / p50 if p50 > 0 else 0.0
        ax.annotate(f"band ±{percent(width)} at the peak: narrower than the line", xy=(0.99, 0.97),
                    xycoords="axes fraction", ha="right", va="top", fontsize=8, color="tab:orange")


def save_joint_distances(path, resolutions, **kwargs) -> Path:
    """Write :func:`joint_choice_figure` of ``resolutions`` to the PNG file ``path``.

    Parameters
    ----------
    path
        PNG file to write.
    resolutions, **kwargs
        As :func:`joint_choice_figure` (``title``, ``conditions``).

    Returns
    -------
    Path
    """
    return save_figure(joint_choice_figure(resolutions, **kwargs), path, dpi=120)


def joint_choice_figure(resolutions, *, title: str | None = None,
                        conditions: Mapping[str, Mapping[str, Any]] | None = None):
    """The candidate joints of each queried interface by condition distance, on one scale.

    One panel per queried interface, all with the same distance axis; each bar carries its value,
    the joint(s) used are coloured (with the weight when interpolated) and the method and any
    condition outside the catalogue are named; the requested conditions head each panel.

    Parameters
    ----------
    resolutions
        Interface name → :class:`jointdb.usecases.JointResolution`.
    title
        Figure title.
    conditions
        Interface name → the query's conditions (e.g. ``{"torque_nm": 100.0, "materials": [...]}``,
        SI units), shown as the request; None: not shown.

    Returns
    -------
    matplotlib.figure.Figure
    """
    plt = _pyplot()
    queried = [(n, r) for n, r in resolutions.items() if r.candidates]
    fig, axes = plt.subplots(1, max(1, len(queried)), figsize=(6.5 * max(1, len(queried)), 4.2), squeeze=False,
                             sharex=True)
    longest = max((d for _, r in queried for *_, d in r.candidates), default=1.0)
    for ax, (name, res) in zip(axes[0], queried):
        _choice_panel(ax, res, (conditions or {}).get(name))
        ax.set_xlim(0, 1.25 * longest if longest > 0 else 1.0)
    if not queried:
        axes[0, 0].text(0.5, 0.5, "no interface was queried", ha="center", va="center")
        axes[0, 0].set_axis_off()
    fig.suptitle(title or "Joint choice: catalogued joints nearest to the request")
    fig.tight_layout()
    return fig


def _choice_panel(ax, res, request: Mapping[str, Any] | None) -> None:
    """One interface: bars of distance with values, the joints used coloured, the request as subtitle."""
    import textwrap

    weights = {(n, v): w for n, v, w, _ in (getattr(res, "neighbours", ()) or ())}
    if not weights and res.name:
        weights = {(res.name, res.version): 1.0}
    names, dist, colours = [], [], []
    for n, v, dd in res.candidates:
        w = weights.get((n, v))
        names.append(f"{n}@{v}" + (f"  (w={w:.2f})" if w is not None and len(weights) > 1 else ""))
        dist.append(dd)
        colours.append("C0" if w is not None else "0.7")
    bars = ax.barh(names[::-1], dist[::-1], color=colours[::-1])
    ax.bar_label(bars, labels=[f"{x:.3f}" for x in dist[::-1]], padding=3, fontsize=8)
    ax.set_xlabel("condition distance [-] (0: the requested conditions)")
    method = getattr(res, "method", "") or res.kind
    head = f"{res.interface}: {method}"
    if res.extrapolating:
        head += f"; OUTSIDE the catalogue in {', '.join(res.outside_range)}"
    lines = [head]
    if request:
        lines += textwrap.wrap("request: " + _conditions_text(request), 80)
    terms = getattr(res, "per_condition", None) or {}
    if terms:
        lines += textwrap.wrap("distance of the joint used, by condition: "
                               + ", ".join(f"{_key_name(k)} {v:.3g}" for k, v in terms.items()), 80)
    ax.set_title("\n".join(lines), fontsize=9)
    ax.grid(True, axis="x", alpha=0.3)


def _conditions_text(conditions: Mapping[str, Any]) -> str:
    """Conditions in the units a planner uses: ``torque 100 N·m, materials carbide/steel, shank Ø 12 mm``."""
    shown = []
    for key, value in conditions.items():
        if isinstance(value, Mapping):
            shown += [_condition(f"{key}.{k}" if key != "geometry" else k, v) for k, v in value.items()]
        else:
            shown.append(_condition(key, value))
    return ", ".join(shown)


#: Condition-key suffixes (SI) → the unit shown and its factor.
_UNITS = (("_nm", "N·m", 1.0), ("_n", "kN", 1e-3), ("_m", "mm", 1e3))


def _key_name(key: str) -> str:
    """``geometry.shank_diameter_m`` → ``shank diameter``."""
    key = key.removeprefix("geometry.")
    for suffix, _, _ in _UNITS:
        if key.endswith(suffix):
            key = key[: -len(suffix)]
            break
    return key.replace("_", " ")


def _condition(key: str, value: Any) -> str:
    if isinstance(value, (list, tuple)):
        return f"{_key_name(key)} {'/'.join(map(str, value))}"
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        for suffix, unit, factor in _UNITS:
            if key.endswith(suffix):
                return f"{_key_name(key)} {value * factor:g} {unit}"
        return f"{_key_name(key)} {value:g}"
    return f"{_key_name(key)} {value}"
