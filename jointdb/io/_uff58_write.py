"""Writing an FRF matrix as UFF dataset-58 records: ASCII 58 with pyuff, binary 58b directly.

Precision of the format (this decides what "exact" means):

* Binary 58b stores values as IEEE float64 and, for an uneven abscissa, the
  frequencies as float64 too: the round trip is bit-exact.
* ASCII 58 stores double-precision values as ``E20.12`` (12 significant
  digits): the round trip is exact for values with at most 12 significant
  digits and within a relative 5e-12 otherwise.
* The abscissa of an even grid is stored as minimum and increment in
  ``E13.5`` (6 significant digits), an ASCII uneven abscissa per line as
  ``E13.5``. ``abscissa="auto"`` writes an even grid only when the grid read
  back equals the FRF's to 1e-12 (relative); otherwise an uneven one. If
  ASCII cannot hold the frequencies to that accuracy, writing is refused
  unless ``round_freq=True`` (then each line is rounded to 6 significant
  digits, a relative error <= 5e-6); binary never needs that.
"""

from __future__ import annotations

import os

import numpy as np

from jointdb.errors import InputError
from jointdb.frf import FRF
from jointdb.io import _units as U
from jointdb.io._atomic import atomic_path

_FREQ_RTOL = 1e-12


def _e13(x: float) -> float:
    return float("%13.5e" % x)


def _even_grid(freq: np.ndarray) -> np.ndarray:
    """The grid a reader reconstructs from an even-abscissa header (min, increment in E13.5)."""
    if freq.size == 1:
        return np.array([_e13(freq[0])])
    return _e13(freq[0]) + np.arange(freq.size) * _e13(freq[1] - freq[0])


def _close(a: np.ndarray, b: np.ndarray) -> bool:
    return bool(np.all(np.abs(a - b) <= _FREQ_RTOL * max(float(np.max(np.abs(b))), 1.0)))


def _choose_spacing(freq: np.ndarray, binary: bool, abscissa: str, round_freq: bool) -> bool:
    """True for even spacing; raises when the choice cannot hold the grid."""
    even_ok = _close(_even_grid(freq), freq)
    if abscissa == "even":
        if not even_ok:
            raise InputError(
                "the frequency grid is not evenly spaced in the precision of UFF58 (minimum and increment "
                "as E13.5); write abscissa='uneven' or 'auto'"
            )
        return True
    if abscissa == "auto" and even_ok:
        return True
    if freq.size == 1:
        raise InputError("a single frequency line can only be written with an even abscissa; "
                         f"{freq[0]!r} Hz has more than 6 significant digits")
    if not binary and not round_freq:
        rounded = np.array([_e13(f) for f in freq])
        if not _close(rounded, freq):
            k = int(np.argmax(np.abs(rounded - freq)))
            raise InputError(
                f"ASCII UFF58 keeps 6 significant digits of each frequency; line {k} ({freq[k]!r} Hz) would "
                "change. Write binary=True (exact), use a grid with <= 6 significant digits, or pass "
                "round_freq=True to accept the rounding"
            )
    return False


def _dataset(frf: FRF, o: int, i: int, even: bool, binary: bool, description: str | None) -> dict:
    out, inp = frf.outputs[o], frf.inputs[i]
    q = frf.quantity
    id1 = description if description else f"jointdb {q.value} H({out},{inp})"
    freq = frf.freq
    x = freq if freq.size > 1 else np.array([freq[0], freq[0] + 1.0])  # pyuff reads x[1]-x[0]
    return {
        "type": 58,
        "binary": 1 if binary else 0,
        "id1": id1[:80], "id2": "NONE", "id3": "NONE", "id4": "NONE", "id5": "NONE",
        "func_type": 4, "func_id": 0, "ver_num": 0, "load_case_id": 0,
        "rsp_ent_name": "NONE", "rsp_node": out.node, "rsp_dir": out.uff_code,
        "ref_ent_name": "NONE", "ref_node": inp.node, "ref_dir": inp.uff_code,
        "ord_data_type": 6,
        "abscissa_spacing": 1 if even else 0,
        "abscissa_spec_data_type": 18, "abscissa_axis_lab": "Frequency", "abscissa_axis_units_lab": "Hz",
        "ordinate_spec_data_type": U.QUANTITY_TO_UFF_CODE[q],
        "ordinate_axis_lab": q.value.capitalize(),
        "ordinate_axis_units_lab": U.response_label(q, out.is_rotation),
        "orddenom_spec_data_type": 13,
        "orddenom_axis_lab": "Moment" if inp.is_rotation else "Force",
        "orddenom_axis_units_lab": U.excitation_label(inp.is_rotation),
        "z_axis_spec_data_type": 0,
        "data": np.ascontiguousarray(frf.values[:, o, i]),
        "x": x,
    }


def _coherence_dataset(frf: FRF, coh: np.ndarray, o: int, i: int, even: bool, binary: bool) -> dict:
    """A function-type-6 record (ordinary coherence, real double, dimensionless) for entry (o, i)."""
    ds = _dataset(frf, o, i, even, binary, f"jointdb coherence({frf.outputs[o]},{frf.inputs[i]})")
    ds.update({
        "func_type": 6, "ord_data_type": 4,
        "ordinate_spec_data_type": 0, "ordinate_axis_lab": "Coherence", "ordinate_axis_units_lab": "NONE",
        "orddenom_spec_data_type": 0, "orddenom_axis_lab": "NONE", "orddenom_axis_units_lab": "NONE",
        "data": np.ascontiguousarray(coh[:, o, i], dtype=np.float64),
    })
    return ds


def _as_coherence(coherence: "FRF | np.ndarray", frf: FRF) -> np.ndarray:
    """Coherence as a real ``(n_freq, n_out, n_in)`` array on the FRF's grid and DOFs, checked to lie in 0..1."""
    shape = frf.values.shape
    if isinstance(coherence, FRF):
        if (coherence.outputs != frf.outputs or coherence.inputs != frf.inputs
                or coherence.freq.shape != frf.freq.shape or not np.array_equal(coherence.freq, frf.freq)):
            raise InputError("coherence: its frequency lines and DOFs must be the FRF's "
                             f"({frf.n_freq} lines, outputs {' '.join(map(str, frf.outputs))}, "
                             f"inputs {' '.join(map(str, frf.inputs))})")
        values = coherence.values
        if np.any(values.imag != 0):
            raise InputError("coherence: values must be real (ordinary coherence 0..1)")
        coh = np.asarray(values.real, dtype=np.float64)
    else:
        coh = np.asarray(coherence)
        if np.iscomplexobj(coh):
            raise InputError("coherence: values must be real (ordinary coherence 0..1)")
        coh = coh.astype(np.float64)
        if coh.shape == (shape[0],):
            coh = np.broadcast_to(coh[:, None, None], shape)
        if coh.shape != shape:
            raise InputError(f"coherence: shape {coh.shape} does not match the FRF's {shape} (or ({shape[0]},))")
    if not np.all(np.isfinite(coh)) or np.any(coh < 0) or np.any(coh > 1):
        raise InputError("coherence: values must be finite and within 0..1")
    return coh


def _write_58b(fh, ds: dict) -> None:
    """One binary 58b record, in the layout pyuff reads and writes, little-endian IEEE float64.

    Written here rather than by pyuff because pyuff's 58b writer states half the
    byte count for complex data, truncates the file in "overwrite" mode and
    leaves a file handle open.
    """
    even = bool(ds["abscissa_spacing"])
    x = np.asarray(ds["x"], dtype=np.float64)
    if ds["ord_data_type"] == 6:  # complex double: (re, im) per line
        y = np.asarray(ds["data"], dtype=np.complex128)
        columns = [y.real, y.imag]
    else:  # 4, real double (coherence)
        y = np.asarray(ds["data"], dtype=np.float64)
        columns = [y]
    n = y.size
    if not even:
        columns = [x[:n], *columns]
    block = np.stack(columns, axis=1)
    payload = block.astype("<f8").tobytes()
    lines = [
        "%6i\n%6i" % (-1, 58),
        "b%6i%6i%12i%12i%6i%6i%12i%12i\n" % (1, 2, 11, len(payload), 0, 0, 0, 0),
        *("%-80s\n" % ds[f"id{k}"] for k in range(1, 6)),
        "%5i%10i%5i%10i %10s%10i%4i %10s%10i%4i\n" % (
            ds["func_type"], ds["func_id"], ds["ver_num"], ds["load_case_id"], ds["rsp_ent_name"],
            ds["rsp_node"], ds["rsp_dir"], ds["ref_ent_name"], ds["ref_node"], ds["ref_dir"]),
        "%10i%10i%10i%13.5e%13.5e%13.5e\n" % (
            ds["ord_data_type"], n, int(even), x[0] if even else 0.0, (x[1] - x[0]) if even else 0.0, 0.0),
    ]
    for axis in ("abscissa", "ordinate", "orddenom", "z_axis"):
        lines.append("%10i%5i%5i%5i %-20s %-20s\n" % (
            ds[f"{axis}_spec_data_type"], 0, 0, 0, ds.get(f"{axis}_axis_lab", "NONE"),
            ds.get(f"{axis}_axis_units_lab", "NONE")))
    fh.write("".join(lines).encode("ascii", errors="replace"))
    fh.write(payload)
    fh.write(b"%6i\n" % -1)


def write_uff58(
    path: str | os.PathLike,
    frf: FRF,
    binary: bool = False,
    *,
    abscissa: str = "auto",
    round_freq: bool = False,
    description: str | None = None,
    units_dataset: bool = True,
    coherence: "FRF | np.ndarray | None" = None,
) -> None:
    """Write every entry of an FRF as one dataset-58 record (function type 4).

    With ``coherence``, one coherence record (function type 6, real double,
    dimensionless, same abscissa and DOF pair) per entry follows the FRF
    records; :func:`jointdb.io.read_coherence_uff58` reads them back.

    Records run over outputs (outer) and inputs (inner), directions positive,
    complex double precision, data-type codes 8/11/12 (receptance / mobility /
    accelerance) over 13 (excitation force), frequency (18) in Hz, SI unit
    labels (``m/s^2`` over ``N``; ``rad``, ``N*m`` for rotations). A dataset
    164 (SI units) precedes them unless ``units_dataset=False``. The file is
    written atomically (temporary file, fsync, rename).

    Parameters
    ----------
    path
        Target file; replaced if it exists.
    frf
        The FRF to write (any quantity; written as it is).
    binary
        Write binary 58b (bit-exact) instead of ASCII 58.
    abscissa
        ``"auto"`` (even when exact, else uneven), ``"even"`` or ``"uneven"``.
    round_freq
        Accept rounding of frequencies to 6 significant digits in ASCII.
    description
        ID line 1 of every FRF record (default names quantity and DOF pair).
    units_dataset
        Write a dataset 164 (SI units) before the records.
    coherence
        Ordinary coherence 0..1 of each entry: a real ``(n_freq, n_out, n_in)``
        array, a ``(n_freq,)`` array shared by all entries, or an
        :class:`~jointdb.frf.FRF` with the same lines and DOFs and real values.

    Raises
    ------
    InputError
        If the grid cannot be written as asked (see the module notes), the
        coherence does not match the FRF or leaves 0..1, or the target
        directory does not exist.
    """
    import pyuff  # lazy

    if not isinstance(frf, FRF):
        raise InputError(f"write_uff58 needs an FRF, got {type(frf).__name__}")
    if abscissa not in ("auto", "even", "uneven"):
        raise InputError(f"abscissa must be 'auto', 'even' or 'uneven', got {abscissa!r}")
    even = _choose_spacing(frf.freq, binary, abscissa, round_freq)
    pairs = [(o, i) for o in range(len(frf.outputs)) for i in range(len(frf.inputs))]
    sets = [_dataset(frf, o, i, even, binary, description) for o, i in pairs]
    if coherence is not None:
        coh = _as_coherence(coherence, frf)
        sets += [_coherence_dataset(frf, coh, o, i, even, binary) for o, i in pairs]
    with atomic_path(path) as tmp:
        uff = pyuff.UFF(str(tmp))
        if units_dataset:
            uff.write_sets({"type": 164, "units_code": 1, "units_description": "SI - Meter (newton)",
                            "temp_mode": 2, "length": 1.0, "force": 1.0, "temp": 1.0, "temp_offset": 273.15},
                           mode="overwrite")
        else:
            tmp.write_bytes(b"")
        if binary:
            with open(tmp, "ab") as fh:
                for ds in sets:
                    _write_58b(fh, ds)
        else:
            uff.write_sets(sets, mode="add")
