"""Grouping dataset-58 FRF records into one FRF matrix (outputs x inputs on one grid)."""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from jointdb.errors import InputError
from jointdb.frf import FRF, Dof, Quantity
from jointdb.io._uff58_read import UffRecord, read_uff58

_GRID_RTOL = 1e-9


@dataclass(frozen=True, eq=False)
class UffImport:
    """An FRF matrix read from UFF58 records, with what was done to get it.

    Attributes
    ----------
    frf
        The FRF (SI, positive directions, requested quantity).
    records
        The records placed in the matrix, in file order.
    skipped
        One note per dataset-58 record that is not an FRF (coherence, spectra, ...).
    conversions
        Every change made on import: sign flips, unit scaling, quantity
        conversion, entries filled by reciprocity.
    """

    frf: FRF
    records: tuple[UffRecord, ...]
    skipped: tuple[str, ...]
    conversions: tuple[str, ...]


def _pairs(items: Sequence[tuple[Dof, Dof]]) -> str:
    shown = ", ".join(f"{o}/{i}" for o, i in items[:8])
    return shown + (f" and {len(items) - 8} more" if len(items) > 8 else "")


def frf_from_records(
    records: Sequence[UffRecord],
    quantity: Quantity | str | None = None,
    *,
    file_quantity: Quantity | str | None = None,
    fill: str = "error",
    source: str = "UFF58 records",
) -> UffImport:
    """Group FRF records into one rectangular FRF (outputs × inputs, common grid).

    Outputs and inputs are ordered by first appearance in ``records``.

    Parameters
    ----------
    records
        Records from :func:`read_uff58`; records that are not FRFs (function
        type other than 4) are skipped and listed in ``skipped``.
    quantity
        Quantity to return; the data are converted exactly (``(iω)^p``) when the
        file holds another one. ``None`` keeps the file's quantity.
    file_quantity
        Quantity of records whose data-type codes do not say (numerator code 0
        or 1). An error if it contradicts a record's codes.
    fill
        ``"error"`` (default): every (output, input) pair must be present.
        ``"reciprocity"``: a missing ``H[o, i]`` is taken from a measured
        ``H[i, o]`` (noted in ``conversions``).
    source
        Name used in error messages (the file name).

    Returns
    -------
    UffImport
        ``frf`` (SI units) with the ``conversions`` and ``skipped`` notes.

    Raises
    ------
    InputError
        No FRF record; scalar DOFs; unknown or mixed quantities; inconsistent
        frequency grids; duplicate pairs; missing pairs (named); 0 Hz when a
        conversion to receptance would divide by zero.
    """
    if fill not in ("error", "reciprocity"):
        raise InputError(f"fill must be 'error' or 'reciprocity', got {fill!r}")
    fq = Quantity.parse(file_quantity) if file_quantity is not None else None
    used, skipped = _frf_records(records, fq, source)
    quantities, notes = _quantities(used, fq, source)
    grid = _common_grid(used, source)
    # one quantity per matrix
    file_q = quantities[0]
    if any(q is not file_q for q in quantities):
        if quantity is None:
            mixed = sorted({q.value for q in quantities})
            raise InputError(f"{source}: the FRF records mix quantities ({', '.join(mixed)}); "
                             "pass quantity= to convert them to one")
    outputs, inputs, where_pair = _layout(used, source)
    target = Quantity.parse(quantity) if quantity is not None else file_q
    values, missing = _matrix_values(used, quantities, target, grid, outputs, inputs, where_pair, fill, source,
                                     notes)
    if missing:
        raise InputError(
            f"{source}: the FRF matrix {len(outputs)} outputs x {len(inputs)} inputs is incomplete; "
            f"missing {len(missing)} pair(s) response/reference: {_pairs(missing)}"
            + ("" if fill == "reciprocity" else " (fill='reciprocity' may complete it)")
        )
    try:
        frf = FRF(grid, values, tuple(outputs), tuple(inputs), target)
    except InputError as exc:
        raise InputError(f"{source}: {exc}") from None
    return UffImport(frf, tuple(used), tuple(skipped), tuple(notes))


def _matrix_values(used, quantities, target: Quantity, grid, outputs, inputs, where_pair, fill: str, source: str,
                   notes: list[str]):
    """The FRF matrix in the ``target`` quantity (``(iω)^p`` conversions noted in ``notes``), with
    missing pairs filled by reciprocity when ``fill`` says so; and the pairs still missing."""
    values = np.zeros((grid.size, len(outputs), len(inputs)), dtype=np.complex128)
    oi = {d: k for k, d in enumerate(outputs)}
    ii = {d: k for k, d in enumerate(inputs)}
    iw = 2j * np.pi * grid
    for r, q in zip(used, quantities):
        v = r.values
        dp = target.power - q.power
        if dp != 0:
            if dp < 0 and grid[0] == 0.0:
                raise InputError(
                    f"{source}: cannot convert {q.value} to {target.value} at 0 Hz (division by iω); "
                    "read it as it is and drop the 0 Hz line with frf.band(fmin=...) before converting"
                )
            v = v * iw**dp
            notes.append(f"dataset #{r.index} ({r.label}): converted {q.value} -> {target.value} (x(iω)^{dp})")
        values[:, oi[r.response], ii[r.reference]] = v  # type: ignore[index]
    missing = [(o, i) for o in outputs for i in inputs if (o, i) not in where_pair]
    if missing and fill == "reciprocity":
        still = []
        for o, i in missing:
            if (i, o) in where_pair:
                values[:, oi[o], ii[i]] = values[:, oi[i], ii[o]]
                notes.append(f"H[{o}, {i}] filled by reciprocity from H[{i}, {o}] (dataset #{where_pair[(i, o)].index})")
            else:
                still.append((o, i))
        missing = still
    return values, missing


def _frf_records(records: Sequence[UffRecord], fq: Quantity | None, source: str):
    """The records that are FRFs, and a note for each one skipped (InputError when none is)."""
    used: list[UffRecord] = []
    skipped: list[str] = []
    for r in records:
        if r.function_type == 4 or (r.function_type == 0 and (r.quantity is not None or fq is not None)):
            used.append(r)
        else:
            skipped.append(f"dataset #{r.index} ({r.label}): {r.function_name} (function type "
                           f"{r.function_type}) is not an FRF; skipped")
    if not used:
        kinds = sorted({f"{r.function_name} ({r.function_type})" for r in records}) or ["none"]
        raise InputError(f"{source}: no FRF records (function type 4) among the dataset-58 records; "
                         f"found: {', '.join(kinds)}")
    return used, skipped


def _quantities(used: list[UffRecord], fq: Quantity | None, source: str):
    """Each record's quantity (its codes, else ``file_quantity``) and the notes on how it was read."""
    notes: list[str] = []
    quantities: list[Quantity] = []
    for r in used:
        where = f"{source}: dataset #{r.index} ({r.label})"
        if r.response is None or r.reference is None:
            raise InputError(f"{where}: a scalar DOF (direction code 0) cannot be placed in an FRF matrix")
        q = r.quantity
        if q is None:
            if fq is None:
                raise InputError(
                    f"{where}: the data-type codes (numerator {r.data_types[1]}, denominator "
                    f"{r.data_types[2]}) do not say receptance, mobility or accelerance; pass file_quantity="
                )
            q = fq
            notes.append(f"dataset #{r.index} ({r.label}): quantity {fq.value} taken from file_quantity")
        elif fq is not None and q is not fq:
            raise InputError(f"{where}: the file says {q.value} but file_quantity={fq.value}")
        quantities.append(q)
        if r.function_type == 0:
            notes.append(f"dataset #{r.index} ({r.label}): function type 0 (general) read as an FRF "
                         "(response over force by its data-type codes)")
        notes.extend(f"dataset #{r.index} ({r.label}): {c}" for c in r.conversions)
    return quantities, notes


def _common_grid(used: list[UffRecord], source: str) -> np.ndarray:
    """The records' one frequency grid (InputError naming two records that differ)."""
    ref = used[0]
    grid = ref.freq
    for r in used[1:]:
        same = r.freq.shape == grid.shape and np.allclose(
            r.freq, grid, rtol=0.0, atol=_GRID_RTOL * max(abs(grid[-1]), 1.0)
        )
        if not same:
            raise InputError(
                f"{source}: inconsistent frequency grids: dataset #{r.index} ({r.label}) has {r.freq.size} lines "
                f"{r.freq[0]:g}–{r.freq[-1]:g} Hz, dataset #{ref.index} ({ref.label}) has {grid.size} lines "
                f"{grid[0]:g}–{grid[-1]:g} Hz; resample them onto one grid first"
            )
    return grid


def _layout(used: list[UffRecord], source: str):
    """Outputs and inputs in order of first appearance, and the record of each (output, input) pair."""
    outputs: list[Dof] = []
    inputs: list[Dof] = []
    where_pair: dict[tuple[Dof, Dof], UffRecord] = {}
    for r in used:
        key = (r.response, r.reference)
        if key in where_pair:
            raise InputError(f"{source}: the pair {r.label} appears twice (datasets #{where_pair[key].index} "
                             f"and #{r.index}); remove one")
        where_pair[key] = r  # type: ignore[index]
        if r.response not in outputs:
            outputs.append(r.response)  # type: ignore[arg-type]
        if r.reference not in inputs:
            inputs.append(r.reference)  # type: ignore[arg-type]
    return outputs, inputs, where_pair


def import_uff58(
    path: str | os.PathLike,
    quantity: Quantity | str | None = None,
    *,
    file_quantity: Quantity | str | None = None,
    fill: str = "error",
    assume_si: bool = False,
) -> UffImport:
    """Read a UFF58 file into one FRF matrix, with the import notes.

    See :func:`read_uff58` (reading, units, signs) and :func:`frf_from_records`
    (grouping, ``quantity``, ``file_quantity``, ``fill``).

    Parameters
    ----------
    path
        The ``.uff`` / ``.unv`` file (ASCII 58 or binary 58b).
    quantity
        Quantity to return (converted exactly); None keeps the file's.
    file_quantity
        Quantity of records whose data-type codes do not say.
    fill
        ``"error"`` or ``"reciprocity"`` (see :func:`frf_from_records`).
    assume_si
        Ignore unit labels and take the values as SI (see :func:`read_uff58`).

    Returns
    -------
    UffImport
        ``frf`` (SI units), ``conversions`` and ``skipped`` notes.
    """
    records = read_uff58(path, assume_si=assume_si)
    return frf_from_records(records, quantity, file_quantity=file_quantity, fill=fill, source=str(path))


def read_frf_uff58(path: str | os.PathLike, quantity: Quantity | str | None = None, *,
                   file_quantity: Quantity | str | None = None, fill: str = "error", assume_si: bool = False) -> FRF:
    """Read a UFF58 file (ASCII or 58b) into one :class:`~jointdb.frf.FRF`.

    Directions are normalised (a −X record is negated and labelled +X), units
    are SI, and all FRF records must form a full outputs × inputs matrix on one
    frequency grid. Use :func:`import_uff58` to also get the notes of what was
    converted, or :func:`read_uff58` for the individual records.

    Parameters
    ----------
    path, quantity, file_quantity, fill, assume_si
        As for :func:`import_uff58`: the file, the quantity to return (None: the file's),
        the quantity of records whose codes do not say, ``"error"`` or ``"reciprocity"``
        for missing pairs, and whether to ignore unit labels.

    Returns
    -------
    FRF
        ``(n_freq, n_out, n_in)`` in SI units.

    Raises
    ------
    NotFoundError, InputError
        See :func:`read_uff58` and :func:`frf_from_records`.
    """
    return import_uff58(path, quantity, file_quantity=file_quantity, fill=fill, assume_si=assume_si).frf


def coherence_from_records(records: Sequence[UffRecord], frf: FRF, *, source: str = "UFF58 records") -> np.ndarray | None:
    """Ordinary coherence (function type 6 records) arranged like ``frf``.

    Parameters
    ----------
    records
        Records from :func:`read_uff58`.
    frf
        The FRF matrix whose lines and DOFs the coherence must cover.
    source
        Name used in error messages (the file name).

    Returns
    -------
    numpy.ndarray or None
        Real array ``(n_freq, n_out, n_in)`` on ``frf``'s lines and DOFs, or
        ``None`` when there is no coherence record. A record of a negative
        direction is relabelled positive without changing its sign (coherence
        is a squared magnitude).

    Raises
    ------
    InputError
        A coherence record on another frequency grid, a duplicate or missing
        pair (named), or values outside 0..1.
    """
    recs = [r for r in records if r.function_type == 6]
    if not recs:
        return None
    coh = np.full(frf.values.shape, np.nan)
    oi = {d: k for k, d in enumerate(frf.outputs)}
    ii = {d: k for k, d in enumerate(frf.inputs)}
    atol = _GRID_RTOL * max(abs(float(frf.freq[-1])), 1.0)
    for r in recs:
        where = f"{source}: coherence dataset #{r.index} ({r.label})"
        if r.response not in oi or r.reference not in ii:
            continue  # a pair outside this FRF matrix
        if r.freq.shape != frf.freq.shape or not np.allclose(r.freq, frf.freq, rtol=0.0, atol=atol):
            raise InputError(f"{where}: its {r.freq.size} lines differ from the FRF's {frf.n_freq} lines")
        o, i = oi[r.response], ii[r.reference]  # type: ignore[index]
        if not np.isnan(coh[0, o, i]):
            raise InputError(f"{where}: the pair {r.label} has two coherence records; remove one")
        values = r.values * (r.response_sign * r.reference_sign)  # undo the sign normalisation
        if np.any(values.imag != 0) or np.any(values.real < 0) or np.any(values.real > 1):
            raise InputError(f"{where}: coherence must be real and within 0..1")
        coh[:, o, i] = values.real
    missing = [(o, i) for o in frf.outputs for i in frf.inputs if np.isnan(coh[0, oi[o], ii[i]])]
    if missing:
        raise InputError(f"{source}: coherence records missing for {len(missing)} pair(s) "
                         f"response/reference: {_pairs(missing)}")
    return coh


def read_coherence_uff58(path: str | os.PathLike, frf: FRF | None = None, *, assume_si: bool = False) -> np.ndarray | None:
    """Read the coherence records (UFF58 function type 6) of a file, arranged like its FRF.

    Written by ``write_uff58(..., coherence=...)``; errors as :func:`coherence_from_records`.

    Parameters
    ----------
    path
        The ``.uff`` file.
    frf
        The FRF matrix to arrange the coherence like (default: the file's own,
        :func:`read_frf_uff58`).
    assume_si
        As :func:`read_uff58`.

    Returns
    -------
    ndarray or None
        Real ``(n_freq, n_out, n_in)`` coherence 0..1, or None when the file has none.
    """
    records = read_uff58(path, assume_si=assume_si)
    if frf is None:
        frf = frf_from_records(records, source=str(path)).frf
    return coherence_from_records(records, frf, source=str(path))
