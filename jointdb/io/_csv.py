"""CSV export and import of an FRF set.

Layout: one header row, then one row per frequency line, comma-separated,
numbers with 17 significant digits (exact float64 round trip)::

    freq [Hz],Re 1x/2x accelerance [m/s^2/N],Im 1x/2x accelerance [m/s^2/N],...
    0,0,0,...
    1,-0.17515115491800001,-0.120423720701,...

Columns after the frequency come in (Re, Im) pairs, one pair per entry
``H[output, input]``, outputs outer and inputs inner. The header names the
response DOF, the excitation DOF, the quantity and the SI unit; the harmonic
convention is ``x(t) = Re{X exp(+iωt)}``.

Reading honours the units the header states, through the same unit table as
UFF58 import (:mod:`jointdb.io._units`): ``freq [kHz]``, ``[mm/N]``,
``[um/N]``, ``[g/N]``, ``[m/s^2/lbf]``, ``[rad/(N*m)]`` ... are converted to
SI (Hz, m/N, m/s²/N, rad/(N·m)); a label it does not know is refused with the
known list. A column without a ``[unit]`` is taken as SI.
"""

from __future__ import annotations

import csv
import os
import re
from pathlib import Path

import numpy as np

from jointdb.errors import InputError, NotFoundError
from jointdb.frf import FRF, Dof, Quantity
from jointdb.io._atomic import atomic_path
from jointdb.io import _units as U
from jointdb.io._units import unit_label

_FREQ_COL = re.compile(r"^\s*freq\w*\s*(?:\[(.*)\])?\s*$", re.I)
_COL = re.compile(r"^\s*(Re|Im)\s+(\S+)/(\S+)\s+(receptance|mobility|accelerance)\s*(?:\[(.*)\])?\s*$", re.I)


def write_frf_csv(path: str | os.PathLike, frf: FRF) -> None:
    """Write an FRF as CSV (layout in the module docstring), atomically.

    Parameters
    ----------
    path
        Target file; replaced if it exists.
    frf
        The FRF (any quantity; unit labels in the header).

    Raises
    ------
    InputError
        If ``frf`` is not an FRF or the target directory does not exist.
    """
    if not isinstance(frf, FRF):
        raise InputError(f"write_frf_csv needs an FRF, got {type(frf).__name__}")
    q = frf.quantity.value
    header = ["freq [Hz]"]
    for o in frf.outputs:
        for i in frf.inputs:
            u = unit_label(frf.quantity, o, i)
            header += [f"Re {o}/{i} {q} [{u}]", f"Im {o}/{i} {q} [{u}]"]
    n = frf.n_freq
    flat = frf.values.reshape(n, -1)
    table = np.empty((n, 1 + 2 * flat.shape[1]))
    table[:, 0] = frf.freq
    table[:, 1::2] = flat.real
    table[:, 2::2] = flat.imag
    with atomic_path(path) as tmp:
        with open(tmp, "w", newline="", encoding="utf-8") as fh:
            w = csv.writer(fh, lineterminator="\n")
            w.writerow(header)
            w.writerows([[repr(float(x)) for x in row] for row in table])


def read_frf_csv(path: str | os.PathLike) -> FRF:
    """Read a CSV written by :func:`write_frf_csv`.

    Parameters
    ----------
    path
        The CSV file.

    Returns
    -------
    FRF
        The FRF with the file's lines, DOF labels and quantity.

    Raises
    ------
    NotFoundError, InputError
        No such file; or a bad header (column named), unequal row lengths, non-numbers (line named), mixed
        quantities, an incomplete outputs × inputs set, or anything :class:`~jointdb.frf.FRF` refuses.
    """
    p = Path(path)
    if not p.is_file():
        raise NotFoundError(f"CSV file {p} does not exist")
    try:
        with open(p, newline="", encoding="utf-8") as fh:
            reader = csv.reader(fh)
            try:
                rows = list(reader)
            except csv.Error as exc:  # NUL bytes, a field beyond the csv module's size limit
                raise InputError(f"{p}: line {reader.line_num}: not a CSV line ({exc})") from None
    except UnicodeDecodeError as exc:
        raise InputError(f"{p}: not a UTF-8 text file (byte {exc.start})") from None
    except OSError as exc:
        raise InputError(f"cannot read {p}: {exc.strerror or exc}") from None
    if not rows:
        raise InputError(f"{p}: empty CSV file")
    header = rows[0]
    if not header or not header[0].strip().lower().startswith("freq"):
        raise InputError(f"{p}: the first column must be the frequency ('freq [Hz]'), got {header[:1]!r}")
    fm = _FREQ_COL.match(header[0])
    if not fm:
        raise InputError(f"{p}: column 1 header {header[0]!r} is not 'freq [unit]'")
    f_factor = U.frequency_factor(fm.group(1) or "", f"{p}: column 1")
    if len(header) < 3 or len(header) % 2 == 0:
        raise InputError(f"{p}: expected a frequency column and (Re, Im) column pairs, got {len(header)} columns")
    pairs: list[tuple[Dof, Dof]] = []
    factors: list[float] = []
    quantities = set()
    for k in range(1, len(header), 2):
        cols = []
        for part, col in (("Re", header[k]), ("Im", header[k + 1])):
            m = _COL.match(col)
            if not m or m.group(1).lower() != part.lower():
                raise InputError(
                    f"{p}: column {k + (part == 'Im') + 1} header {col!r} is not '{part} <out>/<in> <quantity> [unit]'"
                )
            try:
                cols.append((Dof.parse(m.group(2)), Dof.parse(m.group(3)), m.group(4).lower()))
            except InputError as exc:
                raise InputError(f"{p}: column header {col!r}: {exc}") from None
        if cols[0] != cols[1]:
            raise InputError(f"{p}: columns {header[k]!r} and {header[k + 1]!r} do not name the same entry")
        pairs.append((cols[0][0], cols[0][1]))
        quantities.add(cols[0][2])
        units = {_COL.match(header[k]).group(5), _COL.match(header[k + 1]).group(5)}
        if len(units) > 1:
            raise InputError(f"{p}: columns {header[k]!r} and {header[k + 1]!r} state different units")
        factors.append(_entry_factor(units.pop(), cols[0], f"{p}: column {k + 1} {header[k]!r}"))
    if len(quantities) > 1:
        raise InputError(f"{p}: columns mix quantities {sorted(quantities)}")
    outputs = list(dict.fromkeys(o for o, _ in pairs))
    inputs = list(dict.fromkeys(i for _, i in pairs))
    expected = [(o, i) for o in outputs for i in inputs]
    if len(set(pairs)) != len(pairs):
        dup = next(x for k, x in enumerate(pairs) if x in pairs[:k])
        raise InputError(f"{p}: entry {dup[0]}/{dup[1]} appears twice")
    if pairs != expected:
        missing = [f"{o}/{i}" for o, i in expected if (o, i) not in pairs]
        raise InputError(
            f"{p}: entries must form a full outputs x inputs set, outputs outer and inputs inner"
            + (f"; missing {', '.join(missing[:8])}" if missing else "; the order differs")
        )
    data = np.empty((len(rows) - 1, len(header)))
    for ln, row in enumerate(rows[1:], start=2):
        if len(row) != len(header):
            raise InputError(f"{p}: line {ln} has {len(row)} fields, the header has {len(header)}")
        try:
            data[ln - 2] = [float(x) for x in row]
        except ValueError:
            raise InputError(f"{p}: line {ln} holds a field that is not a number") from None
    if data.shape[0] == 0:
        raise InputError(f"{p}: no data rows")
    scale = np.asarray(factors)
    with np.errstate(invalid="ignore", over="ignore"):  # a non-finite value is refused by FRF below, naming it
        values = ((data[:, 1::2] + 1j * data[:, 2::2]) * scale).reshape(-1, len(outputs), len(inputs))
        freq = data[:, 0] * f_factor
    try:
        return FRF(freq, values, tuple(outputs), tuple(inputs), Quantity.parse(quantities.pop()))
    except InputError as exc:
        raise InputError(f"{p}: {exc}") from None


def _entry_factor(label: str | None, entry: tuple[Dof, Dof, str], where: str) -> float:
    """Factor to SI of one entry's ``[response/excitation]`` unit (1 when absent)."""
    if label is None or not label.strip():
        return 1.0
    split = U.split_frf_label(label)
    if split is None:
        raise InputError(f"{where}: unit [{label}] is not <response>/<excitation> (e.g. m/N, mm/N, m/s^2/N, "
                         f"rad/(N*m)); excitation units known: {U.known_excitation_units()}")
    out, inp, quantity = entry
    q = Quantity.parse(quantity)
    return U.response_factor(split[0], q, out, where) / U.excitation_factor(split[1], inp, where)
