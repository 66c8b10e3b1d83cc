"""What the web pages show of a joint version, in engineering units: conditions (N·m, kN,
mm; the taper and holder family named), the identified k, c per DOF with their standard
errors, a plain quality verdict from the stored record, and the data of the interactive
plots (FRF magnitude/phase, k(ω), c(ω)). Pure functions of the API's JSON form of a
version (:func:`jointdb.server._deps.version_json`) and of FRFs; no ``None``, no raw keys.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

#: Line colours, one per joint / version (the overlay); line styles distinguish DOFs.
COLOURS = ("#1f5fa8", "#c0392b", "#2e8b57", "#8e44ad", "#d4780f", "#138d90")
DASHES = ([], [8, 4], [2, 3], [10, 3, 2, 3])
_SUP = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")
#: Geometry keys (SI, suffix ``_m``) and what they are called on the page.
_NAMES = {"shank_diameter_m": "shank diameter", "taper_diameter_m": "taper diameter", "diameter_m": "diameter",
          "insertion_m": "insertion depth", "bore_m": "bore", "holder_family": "holder family",
          "torque_nm": "torque", "preload_n": "drawbar force / preload"}


def num(x: Any, digits: int = 4) -> str:
    """A number as people write it: ``8000.0`` → ``8000``, ``0.012`` → ``0.012``, big/small in ×10ⁿ."""
    if x is None:
        return "–"
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        return str(x)
    x = float(x)
    if not math.isfinite(x):
        return "–" if math.isnan(x) else ("∞" if x > 0 else "−∞")
    if x == 0:
        return "0"
    e = math.floor(math.log10(abs(x)))
    if -3 <= e < 6:
        text = f"{round(x, digits - 1 - e):.{max(0, digits - 1 - e)}f}"
        return text.rstrip("0").rstrip(".") if "." in text else text
    m = x / 10.0 ** e
    return f"{m:.{max(1, digits - 1)}g} × 10{str(e).translate(_SUP)}"


def force_name(joint_type: str | None) -> str:
    """The axial force of a joint type: the drawbar force of a holder–spindle taper, else preload."""
    return "drawbar force" if "spindle" in (joint_type or "") else "preload"


def humanise(key: str) -> str:
    """``shank_diameter_m`` → ``shank diameter`` (unknown keys: underscores become spaces)."""
    key = key.split(".", 1)[1] if key.startswith(("geometry.", "extra.")) else key
    if key in _NAMES:
        return _NAMES[key]
    base = key[:-2] if key.endswith("_m") else key
    return base.replace("_", " ").replace(".", " ")


def humanise_text(text: str) -> str:
    """A message of the store with its condition keys in words (``preload_n`` → drawbar force / preload)."""
    import re

    return re.sub(r"\b(?:geometry\.|extra\.)?[a-z]+(?:_[a-z]+)*_(?:m|n|nm)\b", lambda m: humanise(m.group(0)), text)


def condition_rows(conditions: dict, joint_type: str | None = None) -> list[tuple[str, str]]:
    """``(what, value with unit)`` rows of a version's conditions; absent values are left out."""
    c = conditions or {}
    rows = [("materials", " + ".join(c.get("materials") or []) or "not recorded")]
    if c.get("torque_nm") is not None:
        rows.append(("clamping torque", f"{num(c['torque_nm'])} N·m"))
    if c.get("preload_n") is not None:
        rows.append((force_name(joint_type), f"{num(c['preload_n'] / 1000.0)} kN"))
    for key, value in (c.get("geometry") or {}).items():
        rows.append((humanise(key), f"{num(value * 1000.0)} mm" if key.endswith("_m") else num(value)))
    for key, value in (c.get("extra") or {}).items():
        if isinstance(value, (str, int, float)) and not isinstance(value, bool):
            rows.append((humanise(key), num(value) if isinstance(value, (int, float)) else value))
    return rows


def conditions_line(conditions: dict, joint_type: str | None = None) -> str:
    """The conditions on one line, e.g. ``steel + steel · drawbar force 18 kN · taper HSK-A63``."""
    rows = condition_rows(conditions, joint_type)
    return " · ".join([rows[0][1]] + [f"{k} {v}" for k, v in rows[1:]])


def _units(dof: str) -> tuple[str, str]:
    """Units of k and c for a joint DOF label like ``3x`` / ``3ry``."""
    rot = dof.lstrip("0123456789").startswith("r")
    return ("N·m/rad", "N·m·s/rad") if rot else ("N/m", "N·s/m")


def uncertainty(v: dict) -> dict | None:
    """The version's stored output-error record (``jointdb-joint-uncertainty/1``), or None."""
    params = (v.get("provenance") or {}).get("parameters") or {}
    unc = params.get("uncertainty") if isinstance(params, dict) else None
    return unc if isinstance(unc, dict) and unc.get("format") == "jointdb-joint-uncertainty/1" else None


def _from_record(unc: dict) -> tuple[list[str], np.ndarray, np.ndarray, np.ndarray] | None:
    """``(names, values, standard errors, correlation)`` of a spring–damper record of order 0."""
    if unc.get("model") != "spring-damper" or not unc.get("theta_is_log") or int(unc.get("order", 0)) != 0:
        return None
    theta = np.asarray(unc["theta"], float)
    cov = np.asarray(unc["covariance"], float)
    sd = np.sqrt(np.maximum(np.diag(cov), 0.0))
    values = np.exp(theta)
    with np.errstate(divide="ignore", invalid="ignore"):
        corr = np.where(np.outer(sd, sd) > 0, cov / np.outer(sd, sd), 0.0)
    return list(unc["names"]), values, values * sd, corr


def kc_rows(v: dict, frf=None) -> tuple[list[dict], str]:
    """Rows ``{dof, k, k_sigma, k_rel, c, ...}`` (strings with units) and where they come from.

    From the stored output-error fit (value ± standard error) when the version has one; else a
    constant (k, c) fitted to the stored joint FRF over its band (no standard error recorded)."""
    unc = uncertainty(v)
    parsed = _from_record(unc) if unc else None
    rows: dict[str, dict] = {}
    if parsed is not None:
        names, values, se, _ = parsed
        for n, x, s in zip(names, values, se):
            what, _, dof = n.partition(" ")
            ku, cu = _units(dof)
            row = rows.setdefault(dof, {"dof": dof})
            unit = ku if what == "k" else cu
            row[what] = f"{num(x)} {unit}"
            row[f"{what}_sigma"] = f"± {num(s, 2)} {unit}"
            row[f"{what}_rel"] = f"{num(100 * s / x, 2)} %" if x else "–"
        source = "output-error fit of the identification (value ± standard error)"
        if unc.get("describes_catalogued_joint") is False:
            source += "; for information only: the catalogued joint is the per-line one"
        return list(rows.values()), source
    if frf is None:
        return [], "no identification record"
    from jointdb.coupling import fit_constant_kc

    try:
        fit = fit_constant_kc(frf)
    except Exception:  # noqa: BLE001 - a joint FRF that is not a spring–damper: nothing to show
        return [], "no constant (k, c) representation of this joint FRF"
    for d, k, c in zip(fit.dofs, fit.k, fit.c):
        ku, cu = _units(str(d))
        rows[str(d)] = {"dof": str(d), "k": f"{num(k)} {ku}", "k_sigma": "(σ not recorded)", "k_rel": "–",
                        "c": f"{num(c)} {cu}", "c_sigma": "(σ not recorded)", "c_rel": "–"}
    lo, hi = fit.band_hz
    return list(rows.values()), f"constant (k, c) fitted to the stored joint FRF, {num(lo)}–{num(hi)} Hz (no σ recorded)"


def verdict(v: dict) -> tuple[bool, list[str]]:
    """``(ok, sentences)``: the quality verdict of a catalogued identification, from what the
    record keeps (parameter standard errors and correlations, the model-adequacy check)."""
    from jointdb.coupling._quality import parameter_verdicts

    q = v.get("quality") or {}
    unc = uncertainty(v)
    parsed = _from_record(unc) if unc else None
    lines: list[str] = []
    if parsed is not None:
        names, values, se, corr = parsed
        with np.errstate(divide="ignore", invalid="ignore"):
            rel = np.abs(se / values)
        lines += parameter_verdicts(names, rel, corr)
    ratio, limit = q.get("model_adequacy.misfit_to_noise"), q.get("model_adequacy.misfit_to_noise_limit", 2.0)
    if ratio is not None and ratio > limit:
        lines.append(f"constant k, c misfits the measured assembly {ratio:.1f}× beyond its noise (limit {num(limit)}×)")
    if lines:
        return False, lines
    if parsed is None and ratio is None:
        return True, ["no identification record: uploaded as a joint FRF, its quality is not known"]
    parts = []
    if parsed is not None:
        k = int(np.argmax(rel))
        parts.append(f"largest standard error {rel[k]:.1%} ({names[k]})")
    if ratio is not None:
        parts.append(f"constant (k, c) misfit {ratio:.2f}× the measurement noise (limit {num(limit)}×)")
    if q.get("validation_error") is not None:
        parts.append(f"validation assembly mean deviation {q['validation_error']:.1%}")
    return True, ["OK: " + "; ".join(parts)]


def _series_x(freq: np.ndarray) -> list[float]:
    return [round(float(f), 6) for f in freq]


def _clean(y: np.ndarray) -> list[float | None]:
    return [float(f"{x:.6g}") if np.isfinite(x) else None for x in np.asarray(y, float)]


def frf_plots(curves: list[tuple[str, Any]], title: str) -> list[dict]:
    """Magnitude plots (one per unit: translation and rotation apart) and one phase plot of
    ``(legend, FRF)`` pairs: one colour per curve set, one line style per DOF. Every diagonal
    entry is drawn; curves on different grids are aligned by the page (gaps)."""
    from jointdb.io import unit_label

    mags: dict[str, list] = {}
    phase = []
    for k, (legend, frf) in enumerate(curves):
        for i in range(min(frf.values.shape[1], frf.values.shape[2])):
            h = frf.values[:, i, i]
            unit = unit_label(frf.quantity, frf.outputs[i], frf.inputs[i]).replace("*", "·")
            style = {"colour": COLOURS[k % len(COLOURS)], "dash": DASHES[i % len(DASHES)]}
            name = f"{legend} {frf.outputs[i]}/{frf.inputs[i]}"
            mags.setdefault(unit, []).append({"label": f"{name} [{unit}]", "x": _series_x(frf.freq),
                                              "y": _clean(np.abs(h)), **style})
            phase.append({"label": f"{name} [deg]", "x": _series_x(frf.freq), "y": _clean(np.degrees(np.angle(h))),
                          **style})
    out = [{"id": f"frf-mag-{n}", "title": f"{title}: |H| in {unit}", "x": "frequency [Hz]", "y": f"|H| [{unit}]",
            "log": True, "series": series} for n, (unit, series) in enumerate(mags.items())]
    return out + [{"id": "frf-phase", "title": f"{title}: phase", "x": "frequency [Hz]", "y": "phase [deg]",
                   "log": False, "series": phase}]


def kc_plots(frf, title: str) -> list[dict]:
    """k(ω) and c(ω) of the joint (``k + iωc = 1/h`` per diagonal term,
    :func:`jointdb.coupling.equivalent_stiffness_damping`), one plot each for translation
    and rotation (their units differ)."""
    from jointdb.coupling import equivalent_stiffness_damping
    from jointdb.errors import InputError

    try:
        k, c = equivalent_stiffness_damping(frf)
    except InputError:
        return []
    out = []
    for rot in (False, True):
        idx = [i for i, d in enumerate(frf.inputs) if d.direction.startswith("r") == rot]
        if not idx:
            continue
        ku, cu = _units("ry" if rot else "x")
        what = "rotation" if rot else "translation"
        for key, values, unit in (("k", k, ku), ("c", c, cu)):
            series = [{"label": f"{key} {frf.inputs[i]} [{unit}]", "x": _series_x(frf.freq), "y": _clean(values[:, i]),
                       "colour": COLOURS[n % len(COLOURS)], "dash": DASHES[n % len(DASHES)]}
                      for n, i in enumerate(idx)]
            out.append({"id": f"{key}-{what}", "title": f"{title}: {key}(ω), {what}", "x": "frequency [Hz]",
                        "y": f"{key} [{unit}]", "log": False, "series": series})
    return out
