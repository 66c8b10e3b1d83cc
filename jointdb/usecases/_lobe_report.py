"""Stability lobes as the API and the jobs give them: the CLI's checks and outputs in one call.

``jointdb lobes`` (the CLI) and ``POST /api/v1/lobes`` / ``POST /api/v1/jobs/lobes`` answer
the same things: the method (milling ZOA or SD, turning), refinement near the minima and
pockets, a summary (floor, deepest pocket, flips and folds), the table, and notes — among
them a cutting coefficient given in N/mm² (= MPa), which is recognised, converted to N/m²
and said so.
"""

from __future__ import annotations

from typing import Any, Callable

import numpy as np

from jointdb.errors import InputError

#: Specific cutting coefficients of metals lie between ~1e8 N/m² and ~1e10 N/m²; a value
#: below this bound is read as N/mm² (1 N/mm² = 1e6 N/m²): 796 N/mm² is 7.96e8 N/m².
N_PER_MM2_BELOW = 1e5
PLAUSIBLE_N_PER_M2 = (1e7, 1e11)


def coefficients_si(notes: list[str], **coefficients: float | None) -> dict[str, float | None]:
    """The cutting coefficients in N/m²: a value below :data:`N_PER_MM2_BELOW` is taken as N/mm²
    and converted, with a note appended to ``notes``; an implausibly large one gets a warning."""
    out: dict[str, float | None] = {}
    lo, hi = PLAUSIBLE_N_PER_M2
    for name, value in coefficients.items():
        if value is not None and not np.isfinite(value):
            raise InputError(f"{name} must be a finite number, got {value}")
        if value is not None and 0 < value < N_PER_MM2_BELOW:
            notes.append(f"warning: {name} {value:g} is implausibly small in N/m² (metals: ~1e8–1e10 N/m²); "
                         f"taken as N/mm² (= MPa) and converted to {value * 1e6:g} N/m²")
            value = value * 1e6
        elif value is not None and value > hi:
            notes.append(f"warning: {name} {value:g} N/m² is implausibly large for a cutting coefficient "
                         "(metals: ~1e8–1e10 N/m²); check the unit (N/m² expected)")
        elif value is not None and 0 < value < lo:
            notes.append(f"warning: {name} {value:g} N/m² is implausibly small for a cutting coefficient "
                         "(metals: ~1e8–1e10 N/m²); check the unit (N/m² expected)")
        out[name] = value
    return out


def lobe_summary(res, n_base: int) -> dict:
    """Summary of a lobe result in SI units: the smallest limiting depth (the floor on this grid),
    the deepest pocket, counts of speeds, flips and folds. Folds (multiplier +1) are not chatter
    limits and are left out of the floor and the pocket."""
    from jointdb.stability import plottable_depth

    d = plottable_depth(res)
    out: dict = {"method": res.method, "speeds": int(res.spindle_speed_rpm.size),
                 "speeds_added_by_refinement": int(res.spindle_speed_rpm.size - n_base),
                 "speed_range_rpm": [float(res.spindle_speed_rpm[0]), float(res.spindle_speed_rpm[-1])]}
    if np.isfinite(d).any():
        i = int(np.nanargmin(d))
        j = int(np.nanargmax(d))
        out |= {"min_depth_m": float(d[i]), "min_depth_speed_rpm": float(res.spindle_speed_rpm[i]),
                "min_depth_chatter_freq_hz": float(res.chatter_freq_hz[i]), "min_depth_kind": str(res.kind[i]),
                "best_pocket_depth_m": float(d[j]), "best_pocket_speed_rpm": float(res.spindle_speed_rpm[j])}
    out |= {"flip_speeds": int(np.sum(res.kind == "flip")), "fold_speeds_not_limits": int(np.sum(res.kind == "fold")),
            "no_limit_speeds": int(np.sum(~np.isfinite(res.depth_m)))}
    return out


def best_speeds(res, count: int = 5) -> list[dict[str, float]]:
    """The ``count`` speeds of the deepest stable pockets (local maxima of the limiting depth)."""
    from jointdb.stability import plottable_depth

    d = np.asarray(plottable_depth(res), float)
    s = res.spindle_speed_rpm
    finite = np.where(np.isfinite(d), d, -np.inf)
    if d.size < 3:
        return []
    peak = (finite[1:-1] >= finite[:-2]) & (finite[1:-1] >= finite[2:]) & np.isfinite(d[1:-1])
    idx = np.flatnonzero(peak) + 1
    idx = idx[np.argsort(-finite[idx])][:count]
    return [{"spindle_speed_rpm": float(s[i]), "depth_m": float(d[i])} for i in sorted(idx)]


def _sd_chunks(model, cut, speeds: np.ndarray, n_intervals: int, progress, n_chunks: int = 20):
    """``milling_lobes_sd`` in chunks of speeds (each speed is independent), reporting progress."""
    from jointdb.stability import LobeResult, milling_lobes_sd

    chunks = np.array_split(speeds, min(n_chunks, speeds.size))
    parts = []
    for k, chunk in enumerate(chunks):
        parts.append(milling_lobes_sd(model, cut, chunk, n_intervals=n_intervals))
        progress((k + 1) / len(chunks), f"SD lobes: {sum(p.spindle_speed_rpm.size for p in parts)} speeds")
    info = dict(parts[0].info)
    info["evaluations"] = int(sum(p.info.get("evaluations", 0) for p in parts))
    return LobeResult(parts[0].method, *(np.concatenate([getattr(p, a) for p in parts]) for a in
                      ("spindle_speed_rpm", "depth_m", "chatter_freq_hz", "lobe", "kind")), (), info)


def _tip_entries(frf, notes: list[str]):
    """A tool-tip FRF's translational part; refuses an FRF with none (a joint's rotation-only FRF)."""
    outs = [d for d in frf.outputs if not d.is_rotation]
    ins = [d for d in frf.inputs if not d.is_rotation]
    if not outs or not ins:
        raise InputError("frf: stability lobes need a translational tool-tip FRF (x, y); this one has outputs "
                         f"{' '.join(map(str, frf.outputs))}")
    if len(outs) < len(frf.outputs) or len(ins) < len(frf.inputs):
        notes.append("note: rotational DOFs of the tip FRF are ignored")
        frf = frf.select(outs, ins)
    return frf


def lobes_report(frf, *, op: str = "milling", method: str = "zoa", teeth: int = 2, kt: float | None = None,
                 kr: float | None = None, kf: float | None = None, immersion: float = 1.0, up: bool = False,
                 rpm_min: float = 2000.0, rpm_max: float = 20000.0, n_speeds: int = 300, refine: int = 3,
                 intervals: int = 40, modes: int | None = None, band: tuple[float, float] | None = None,
                 max_order: int = 30, cross_terms: bool | None = None,
                 progress: Callable[[float, str], None] | None = None) -> dict[str, Any]:
    """Stability lobes of a tool-tip FRF with the CLI's checks, summary and notes (JSON-ready, SI).

    Parameters
    ----------
    frf
        Tool-tip receptance [m/N], shape ``(n_freq, n, n)``, x and/or y at the tool tip.
    op, method
        ``"milling"`` (``method`` ``"zoa"`` or ``"sd"``) or ``"turning"``.
    teeth, kt, kr, kf, immersion, up
        The cut: cutting coefficients in N/m² (a value below 1e5 is taken as N/mm² and
        converted, with a note), radial immersion a_e/D in (0, 1], up-milling.
    rpm_min, rpm_max, n_speeds, refine
        The speed grid [rev/min] and the rounds of extra speeds near minima and pockets.
    intervals, modes, band, max_order
        SD: intervals per tooth period, modes per direction, modal-fit band [Hz], pLSCF order.
    cross_terms
        ZOA: use the x–y cross FRFs (default: when the FRF has non-zero ones).
    progress
        Called with (fraction 0..1, message) as the work goes on.

    Returns
    -------
    dict
        ``method``, ``info``, ``summary`` (as ``jointdb lobes --json``), ``rows`` (depth in m,
        non-finite values as None), ``best_speeds`` and ``notes``.
    """
    from jointdb import stability

    report = progress or (lambda fraction, message: None)
    notes: list[str] = []
    if not (np.isfinite(rpm_max) and 0 < rpm_min < rpm_max) or n_speeds < 2:
        raise InputError("need finite 0 < rpm_min < rpm_max and n_speeds >= 2")
    if method not in ("zoa", "sd"):
        raise InputError(f"method must be zoa or sd, got {method!r}")
    co = coefficients_si(notes, kf=kf, kt=kt, kr=kr)
    speeds = np.linspace(rpm_min, rpm_max, n_speeds)
    frf = _tip_entries(frf, notes)
    if op == "turning":
        if co["kf"] is None:
            raise InputError("turning needs kf (cutting coefficient in N/m²)")
        res = stability.refine_lobes(lambda s: stability.turning_lobes(frf, co["kf"], None, spindle_speed_rpm=s),
                                     speeds, rounds=refine)
    elif op == "milling":
        if co["kt"] is None or co["kr"] is None:
            raise InputError("milling needs kt and kr (cutting coefficients in N/m²)")
        cut = stability.MillingCut(teeth, co["kt"], co["kr"], immersion, not up)
        res = _milling(frf, cut, method, speeds, refine, cross_terms, notes, report,
                       intervals=intervals, modes=modes, band=band, max_order=max_order)
    else:
        raise InputError(f"op must be milling or turning, got {op!r}")
    rows = [{k: (None if isinstance(v, float) and not np.isfinite(v) else v) for k, v in row.items()}
            for row in res.table()]
    return {"method": res.method, "info": _jsonable(res.info), "summary": lobe_summary(res, n_speeds), "rows": rows,
            "best_speeds": best_speeds(res), "notes": notes,
            "coefficients_n_per_m2": {k: v for k, v in co.items() if v is not None}}


def _milling(frf, cut, method, speeds, refine, cross_terms, notes, report, *, intervals, modes, band, max_order):
    from jointdb import stability
    from jointdb.modal import fit_tool_tip

    _, phi, (has_x, has_y) = stability.tool_tip_matrix(frf, cross_terms=True)
    present = has_x and has_y and bool(np.any(phi[:, 0, 1]) or np.any(phi[:, 1, 0]))
    if method == "zoa":
        use = present if cross_terms is None else bool(cross_terms)
        if present and cross_terms is None:
            notes.append("note: the tip FRF's x–y cross terms are used (cross_terms: false drops them)")
        report(0.1, "ZOA lobes")
        return stability.refine_lobes(lambda s: stability.milling_lobes_zoa(
            frf, cut, cross_terms=use, spindle_speed_rpm=s), speeds, rounds=refine)
    if present:
        notes.append("note: SD fits the x and y planes separately; the tip FRF's x–y cross terms are not used")
    report(0.02, "modal fit of the tool tip")
    model, fits = fit_tool_tip(frf, None, modes, band, max_order=max_order)
    for fit in fits:
        notes.append(f"modal fit {fit.model.outputs[0]}: {fit.model.n_modes} modes; NMSE "
                     f"{fit.quality.nmse_total:.2e}, FRAC {fit.quality.frac_min:.4f}")
    state = {"pass": 0}

    def compute(s):
        state["pass"] += 1
        k = state["pass"]
        span = (0.05, 0.8) if k == 1 else (0.8, 0.99)
        return _sd_chunks(model, cut, s, intervals, lambda f, m: report(
            span[0] + (span[1] - span[0]) * f, f"{m} (pass {k})"))

    return stability.refine_lobes(compute, speeds, rounds=refine)


def _jsonable(value):
    from jointdb._output import to_jsonable

    return to_jsonable(value)
