"""Tool-tip inputs for ``jointdb lobes`` as engineers have them (issue 13, item 5).

- A tip file with only the xx and yy driving-point FRFs (the usual tap test) is read as a
  diagonal 2×2 FRF: the cross terms are taken as zero, with a note.
- ``--op turning`` uses ``--frf-y`` (its driving point joins the x one as a second
  direction), and refuses a ``--frf-y`` it cannot use.
- Cutting coefficients that are implausible in N/m² get a warning naming the likely unit.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from jointdb.errors import InputError
from jointdb.frf import FRF, Quantity

#: Specific cutting coefficients of metals lie between ~1e8 N/m² (aluminium, radial) and
#: ~1e10 N/m² (hardened steel, titanium with a worn edge); outside a decade beyond that a
#: value is almost certainly in another unit.
PLAUSIBLE_N_PER_M2 = (1e7, 1e11)


def read_tool_tip(path: Path) -> tuple[FRF, list[str]]:
    """A tool-tip FRF from UFF58 / HDF5 / CSV; a UFF58 file with only driving points becomes diagonal.

    Returns
    -------
    (FRF, notes)
        ``notes`` says what was assumed (cross terms zero).

    Raises
    ------
    InputError, NotFoundError
        As :func:`jointdb.usecases.read_frf_file`, or for a file that is neither a full matrix nor
        driving points only.
    """
    from jointdb.usecases import frf_format, read_frf_file

    try:
        return read_frf_file(path), []
    except InputError as exc:
        if frf_format(Path(path)) != "uff58" or "incomplete" not in str(exc):
            raise
        original = exc
    from jointdb.io import frf_from_records, read_uff58

    records = [r for r in read_uff58(path) if r.function_type in (0, 4)]
    if not records or any(r.response != r.reference for r in records):
        raise original
    parts = []
    for r in records:
        try:
            parts.append(frf_from_records([r], source=str(path)).frf)
        except InputError:
            raise original from None
    q = parts[0].quantity
    parts = [p if p.quantity == q else p.to(q) for p in parts]
    freq = parts[0].freq
    if any(p.freq.shape != freq.shape or not np.allclose(p.freq, freq, rtol=1e-9) for p in parts):
        raise InputError(f"{path}: the driving-point records are on different frequency grids; resample them")
    labels = [p.outputs[0] for p in parts]
    values = np.zeros((freq.size, len(parts), len(parts)), complex)
    for k, p in enumerate(parts):
        values[:, k, k] = p.values[:, 0, 0]
    note = (f"note: {path.name} holds only the driving points {', '.join(f'{d}/{d}' for d in labels)}; "
            "cross terms taken as zero")
    return FRF(freq, values, tuple(labels), tuple(labels), q), [note]


def has_cross_terms(frf: FRF) -> bool:
    """Whether ``frf`` has an x and a y driving point and a non-zero x–y cross entry between them
    (the entries :func:`jointdb.stability.tool_tip_matrix` would use)."""
    from jointdb.stability import tool_tip_matrix

    _, phi, (has_x, has_y) = tool_tip_matrix(frf, cross_terms=True)
    return has_x and has_y and bool(np.any(phi[:, 0, 1]) or np.any(phi[:, 1, 0]))


def turning_frf(frf: FRF, frf_y: FRF | None, path_y: Path | None) -> tuple[FRF, list[str]]:
    """The turning FRF: ``frf``'s translational entries, plus the y driving point of ``--frf-y``.

    Raises
    ------
    InputError
        ``--frf-y`` without a driving point, on another grid, or when ``frf`` already has y.
    """
    if frf_y is None:
        return frf, []
    ry = frf_y.to(Quantity.RECEPTANCE)
    d = next((o for o in ry.outputs if o in ry.inputs and o.direction == "y"), None) or next(
        (o for o in ry.outputs if o in ry.inputs and not o.is_rotation), None)
    if d is None:
        raise InputError(f"--frf-y {path_y}: no translational driving-point FRF (same output and input DOF)")
    rx = frf.to(Quantity.RECEPTANCE)
    if d in rx.outputs or d in rx.inputs:
        raise InputError(f"--frf-y {path_y}: {d} is already in the main tool-tip file; give --frf-y only "
                         "when the main file lacks the y direction")
    if rx.freq.shape != ry.freq.shape or not np.allclose(rx.freq, ry.freq, rtol=1e-9):
        raise InputError(f"--frf-y {path_y}: {ry.n_freq} lines {ry.freq[0]:g}–{ry.freq[-1]:g} Hz but the tool-tip "
                         f"file has {rx.n_freq} lines {rx.freq[0]:g}–{rx.freq[-1]:g} Hz; resample onto one grid")
    drive = [o for o in rx.outputs if o in rx.inputs and not o.is_rotation]
    if not drive:
        raise InputError("turning needs a translational driving point in the tool-tip file")
    labels = drive + [d]
    n = len(labels)
    values = np.zeros((rx.n_freq, n, n), complex)
    values[:, : n - 1, : n - 1] = rx.block(drive, drive)
    values[:, n - 1, n - 1] = ry.entry(d, d)
    note = f"note: turning with {' '.join(map(str, drive))} and {d} from --frf-y (cross terms zero)"
    return FRF(rx.freq, values, tuple(labels), tuple(labels), Quantity.RECEPTANCE), [note]


def coefficient_warnings(**coefficients: float | None) -> list[str]:
    """Warnings for cutting coefficients outside the plausible N/m² range, naming the likely unit."""
    out = []
    lo, hi = PLAUSIBLE_N_PER_M2
    for name, value in coefficients.items():
        if value is None or not np.isfinite(value) or value <= 0:
            continue
        if value < lo:
            unit = ("it looks like N/mm² (= MPa): in N/m² that is " + f"{value * 1e6:g}") if value < 1e5 else \
                "check the unit (N/m² expected)"
            out.append(f"warning: --{name} {value:g} N/m² is implausibly small for a cutting coefficient "
                       f"(metals: ~1e8–1e10 N/m²); {unit}")
        elif value > hi:
            out.append(f"warning: --{name} {value:g} N/m² is implausibly large for a cutting coefficient "
                       "(metals: ~1e8–1e10 N/m²); check the unit (N/m² expected)")
    return out
