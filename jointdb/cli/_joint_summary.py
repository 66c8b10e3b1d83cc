"""``jointdb joints show`` for people: the joint's constant k, c per DOF and readable metadata."""

from __future__ import annotations

import json
from typing import Any

#: How the constant k, c of a stored joint are obtained (said in the output).
KC_METHOD = "median of Re(1/h) and of Im(1/h)/ω over every stored line"


def constant_kc(frf) -> dict[str, Any] | None:
    """Constant stiffness and damping per diagonal DOF of a joint receptance FRF, or None.

    ``k`` is the median of ``Re(1/h)`` and ``c`` the median of ``Im(1/h)/ω``
    over all stored lines (median: robust to the few noisy lines an
    identification leaves); ``misfit`` is ``‖h − 1/(k + iωc)‖ / ‖h‖`` over the
    same lines. None when the FRF is not square or a diagonal term is zero (rigid).
    Units: N/m and N·s/m (translations), N·m/rad and N·m·s/rad (rotations).
    """
    from jointdb.coupling import fit_constant_kc
    from jointdb.errors import InputError

    try:
        fit = fit_constant_kc(frf, None, method="median")
    except InputError:
        return None
    rows = []
    for dof, k, c, err in zip(fit.dofs, fit.k, fit.c, fit.error):
        rot = dof.is_rotation
        rows.append({"dof": str(dof), "k": float(k), "k_unit": "N·m/rad" if rot else "N/m",
                     "c": float(c), "c_unit": "N·m·s/rad" if rot else "N·s/m", "misfit": float(err)})
    return {"method": KC_METHOD, "band_hz": list(fit.band_hz), "n_lines": int(frf.n_freq), "dofs": rows}


def kc_rows_for_people(kc: dict[str, Any]) -> list[dict[str, Any]]:
    """One row per DOF with the unit in the header: ``k [N/m]``/``k [N·m/rad]`` share a column name
    per unit, so translations and rotations get their own columns."""
    out = []
    for r in kc["dofs"]:
        out.append({"dof": r["dof"], f"k [{r['k_unit']}]": f"{r['k']:.4g}", f"c [{r['c_unit']}]": f"{r['c']:.4g}",
                    "misfit [%]": f"{100 * r['misfit']:.2f}"})
    return out


def readable(value: Any) -> Any:
    """A JSON string of an object (as stored in the catalogue rows) as ``key=value, …`` text."""
    if not isinstance(value, str) or not value.startswith("{"):
        return value
    try:
        data = json.loads(value)
    except ValueError:
        return value
    flat: list[str] = []

    def walk(prefix: str, obj: Any) -> None:
        if isinstance(obj, dict):
            for k, v in obj.items():
                walk(f"{prefix}.{k}" if prefix else str(k), v)
        elif isinstance(obj, float):
            flat.append(f"{prefix}={obj:.4g}")
        else:
            flat.append(f"{prefix}={obj}")

    walk("", data)
    return ", ".join(flat)
