"""Reading UFF dataset 58 (function at nodal DOF) records with pyuff.

Every record is validated and brought to SI with positive direction labels;
what was changed is listed in :attr:`UffRecord.conversions`. Grouping records
into one :class:`~jointdb.frf.FRF` lives in :mod:`jointdb.io._uff58_group`.
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from jointdb.errors import InputError, NotFoundError
from jointdb.frf import DIRECTIONS, Dof, Quantity
from jointdb.io import _units as U

#: UFF58 function types (record 6, field 1).
FUNCTION_TYPES: dict[int, str] = {
    0: "general or unknown", 1: "time response", 2: "auto spectrum", 3: "cross spectrum",
    4: "frequency response function", 5: "transmissibility", 6: "coherence", 7: "auto correlation",
    8: "cross correlation", 9: "power spectral density", 10: "energy spectral density",
    11: "probability density function", 12: "spectrum", 13: "cumulative frequency distribution",
    14: "peaks valley", 15: "stress/cycles", 16: "strain/cycles", 17: "orbit",
    18: "mode indicator function", 19: "force pattern", 20: "partial power", 21: "partial coherence",
    22: "eigenvalue", 23: "eigenvector", 24: "shock response spectrum", 25: "finite impulse response filter",
    26: "multiple coherence", 27: "order function",
}

_TAG = b"    -1"


@dataclass(frozen=True, eq=False)
class UffRecord:
    """One dataset-58 record, in SI with positive direction labels.

    Attributes
    ----------
    index
        1-based position of the dataset among all datasets of the file.
    function_type
        UFF58 function type code (4 = FRF); see :data:`FUNCTION_TYPES`.
    response, reference
        DOFs with positive direction, or ``None`` for a scalar point (code 0).
    response_sign, reference_sign
        Signs of the direction codes in the file (+1/−1). ``values`` have been
        multiplied by ``response_sign * reference_sign``.
    freq
        Abscissa in Hz, shape ``(n,)``.
    values
        Complex ordinate, shape ``(n,)``, SI units of ``quantity``.
    quantity
        Receptance / mobility / accelerance from the ordinate data-type codes
        (8 / 11 / 12 over 13), or ``None`` when the codes do not say.
    data_types
        Specific data-type codes (abscissa, ordinate numerator, ordinate denominator).
    unit_labels
        Axis unit labels as found (abscissa, numerator, denominator).
    binary, even, double_precision, complex_data
        Storage form in the file (58b, even abscissa, 8-byte values, complex ordinate).
    ids
        ID lines 1–5.
    conversions
        Human-readable notes of every change made on import (sign flips, unit scaling).
    """

    index: int
    function_type: int
    response: Dof | None
    reference: Dof | None
    response_sign: int
    reference_sign: int
    freq: np.ndarray
    values: np.ndarray
    quantity: Quantity | None
    data_types: tuple[int, int, int]
    unit_labels: tuple[str, str, str]
    binary: bool
    even: bool
    double_precision: bool
    complex_data: bool
    ids: tuple[str, ...]
    conversions: tuple[str, ...]

    @property
    def function_name(self) -> str:
        return FUNCTION_TYPES.get(self.function_type, f"type {self.function_type}")

    @property
    def label(self) -> str:
        """``"response/reference"``, e.g. ``"1x/3x"``."""
        return f"{self.response if self.response else 'scalar'}/{self.reference if self.reference else 'scalar'}"

    @property
    def is_frf(self) -> bool:
        """Function type 4, or type 0 whose codes say response over force."""
        return self.function_type == 4 or (self.function_type == 0 and self.quantity is not None)


#: Name used in jointdb's contract documents.
UffFrfRecord = UffRecord


def _line_of(data: bytes, offset: int) -> int:
    return data.count(b"\n", 0, offset) + 1


def _scan_blocks(path: Path, data: bytes) -> None:
    """Check the '    -1' delimiters pair up (the same rule pyuff uses to find them)."""
    tags = []
    ind = -1
    n = len(data)
    while True:
        ind = data.find(_TAG, ind + 1)
        if ind == -1:
            break
        end = ind + 6
        if end == n or data[end] in (10, 13) or (ind + 80 < n and data[end:ind + 80] == b" " * 74):
            tags.append(ind)
    if not tags:
        raise InputError(f"{path}: not a universal file (no '    -1' dataset delimiters found)")
    if len(tags) % 2:
        raise InputError(
            f"{path}: truncated or corrupt: the dataset starting at line {_line_of(data, tags[-1])} "
            "has no closing '    -1' line"
        )


def _direction(node: object, code: object, which: str, where: str) -> tuple[Dof | None, int]:
    try:
        node_i, code_i = int(node), int(code)  # type: ignore[call-overload]
    except (TypeError, ValueError):
        raise InputError(f"{where}: {which} node/direction {node!r}/{code!r} are not integers") from None
    if code_i == 0:
        return None, 1
    if abs(code_i) > len(DIRECTIONS):
        raise InputError(
            f"{where}: unknown {which} direction code {code_i} (expected ±1..±6 for x y z rx ry rz, 0 for scalar)"
        )
    if node_i < 0:
        raise InputError(f"{where}: negative {which} node number {node_i}")
    return Dof.from_uff(node_i, code_i)


@dataclass(frozen=True)
class _UnitSystem:
    """Dataset 164 factors: value_SI = value_file / factor."""

    code: int
    length: float
    force: float


def _arrays(d: dict, where: str):
    """The abscissa, the ordinate and the ordinate data type of a record, checked."""
    x = np.asarray(d.get("x"), dtype=np.float64)
    y = np.asarray(d.get("data"))
    num_pts = int(d.get("num_pts", -1))
    if y.ndim != 1 or x.shape != y.shape:
        raise InputError(f"{where}: abscissa and ordinate have different lengths ({x.shape} vs {y.shape})")
    if num_pts != y.size:
        raise InputError(
            f"{where}: header says {num_pts} values but {y.size} were found (file truncated or corrupt)"
        )
    if y.size == 0:
        raise InputError(f"{where}: the record holds no values")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        raise InputError(f"{where}: abscissa or values contain NaN or inf")
    ord_type = int(d.get("ord_data_type", 0))
    if ord_type not in (2, 4, 5, 6):
        raise InputError(f"{where}: unknown ordinate data type {ord_type} (expected 2, 4, 5 or 6)")
    return x, y, ord_type


def _quantity(types: tuple, func_type: int, where: str, notes: list[str]) -> Quantity | None:
    """The FRF quantity the data-type codes say (None: not an FRF, or not known), noting assumptions."""
    num, den = types[1], types[2]
    quantity = U.UFF_CODE_TO_QUANTITY.get(num)
    if num == 13 and den in (8, 11, 12):
        if func_type in (0, 4):
            raise InputError(
                f"{where}: force over {U.UFF_DATA_TYPES[den]} (dynamic stiffness / impedance / apparent mass) "
                "is not supported; export the FRF (response over force) instead"
            )
    if quantity is not None and den not in (13, 9, 0):
        if func_type in (0, 4):
            raise InputError(
                f"{where}: ordinate denominator is {U.UFF_DATA_TYPES.get(den, den)} (code {den}); "
                "an FRF needs an excitation force (code 13)"
            )
        quantity = None
    if quantity is not None and den == 9:
        notes.append("denominator 'reaction force' (code 9) treated as the excitation force")
    if quantity is not None and den == 0 and func_type == 4:
        notes.append("denominator data type unknown (code 0); assumed excitation force")
    if func_type == 0 and quantity is not None and den == 0:
        quantity = None  # a general function with no denominator is not an FRF
    return quantity


def _record_from_dict(d: dict, index: int, path: Path, units: _UnitSystem | None, assume_si: bool) -> UffRecord:
    where = f"{path}: dataset #{index}"
    func_type = int(d.get("func_type", 0))
    response, rsign = _direction(d.get("rsp_node"), d.get("rsp_dir"), "response", where)
    reference, fsign = _direction(d.get("ref_node"), d.get("ref_dir"), "reference", where)
    where = f"{where} ({response or 'scalar'}/{reference or 'scalar'})"
    x, y, ord_type = _arrays(d, where)
    types = (int(d.get("abscissa_spec_data_type", 0)), int(d.get("ordinate_spec_data_type", 0)),
             int(d.get("orddenom_spec_data_type", 0)))
    labels = (str(d.get("abscissa_axis_units_lab", "") or ""), str(d.get("ordinate_axis_units_lab", "") or ""),
              str(d.get("orddenom_axis_units_lab", "") or ""))
    notes: list[str] = []
    values = y.astype(np.complex128)
    if ord_type in (2, 4) and func_type in (0, 4):
        notes.append("real-valued ordinate read as complex with zero imaginary part")
    sign = rsign * fsign
    if sign < 0:
        values = -values
    if rsign < 0 or fsign < 0:
        flipped = [f"response {response} (code {d.get('rsp_dir')})"] if rsign < 0 else []
        flipped += [f"reference {reference} (code {d.get('ref_dir')})"] if fsign < 0 else []
        notes.append(
            "negative direction " + " and ".join(flipped) + " relabelled positive"
            + ("; values negated" if sign < 0 else "; signs cancel, values unchanged")
        )
    quantity = _quantity(types, func_type, where, notes)
    # abscissa
    freq = x
    if types[0] not in (18, 0) and func_type in (0, 4):
        raise InputError(
            f"{where}: abscissa is {U.UFF_DATA_TYPES.get(types[0], types[0])} (code {types[0]}), "
            "not frequency (code 18)"
        )
    if types[0] == 0 and func_type == 4:
        notes.append("abscissa data type unknown (code 0); read as frequency")
    if func_type in (0, 4, 6):
        _check_abscissa(x, where)
    if func_type in (0, 4):
        if not assume_si:
            f_factor = U.frequency_factor(labels[0], where)
            if f_factor != 1.0:
                freq = x * f_factor
                notes.append(f"abscissa unit {labels[0]!r} converted to Hz (x{f_factor:.12g})")
        factor = 1.0
        if quantity is not None and response is not None and reference is not None:
            factor = _ordinate_factor(labels, quantity, response, reference, units, assume_si, where, notes)
        if factor != 1.0:
            values = values * factor
    return UffRecord(
        index=index,
        function_type=func_type,
        response=response,
        reference=reference,
        response_sign=rsign,
        reference_sign=fsign,
        freq=freq,
        values=values,
        quantity=quantity,
        data_types=types,
        unit_labels=labels,
        binary=bool(d.get("binary", 0)),
        even=int(d.get("abscissa_spacing", 0)) == 1,
        double_precision=ord_type in (4, 6),
        complex_data=ord_type in (5, 6),
        ids=tuple(str(d.get(f"id{k}", "")) for k in range(1, 6)),
        conversions=tuple(notes),
    )


def _check_abscissa(x: np.ndarray, where: str) -> None:
    """Frequencies >= 0 and strictly increasing (naming the first offending value)."""
    if x[0] < 0:
        raise InputError(f"{where}: frequencies must be >= 0 Hz, the first is {x[0]:g}")
    bad = np.flatnonzero(np.diff(x) <= 0)
    if bad.size:
        k = int(bad[0]) + 1
        raise InputError(f"{where}: frequencies must be strictly increasing; value {k + 1} ({x[k]:g}) does not "
                         f"exceed value {k} ({x[k - 1]:g})")


def _ordinate_factor(labels, quantity, response, reference, units, assume_si, where, notes) -> float:
    if assume_si:
        if not (U.is_none_label(labels[1]) and U.is_none_label(labels[2])):
            notes.append(f"unit labels {labels[1]!r}/{labels[2]!r} ignored (assume_si)")
        return 1.0
    num_label, den_label = labels[1], labels[2]
    if not U.is_none_label(num_label) and U.is_none_label(den_label):
        split = U.split_frf_label(num_label)
        if split is not None:
            num_label, den_label = split
    factor = 1.0
    if U.is_none_label(num_label) and U.is_none_label(den_label):
        if units is not None and units.code != 1 and (units.length != 1.0 or units.force != 1.0):
            num = 1.0 if response.is_rotation else 1.0 / units.length
            den = 1.0 / units.force * (1.0 / units.length if reference.is_rotation else 1.0)
            factor = num / den
            notes.append(
                f"units from dataset 164 (code {units.code}, length factor {units.length:g}, force factor "
                f"{units.force:g}): values x{factor:.12g} to SI"
            )
        return factor
    if not U.is_none_label(num_label):
        f = U.response_factor(num_label, quantity, response, where)
        if f != 1.0:
            notes.append(f"response unit {num_label!r} converted to SI (x{f:.12g})")
        factor *= f
    if not U.is_none_label(den_label):
        f = U.excitation_factor(den_label, reference, where)
        if f != 1.0:
            notes.append(f"excitation unit {den_label!r} converted to SI (/{f:.12g})")
        factor /= f
    return factor


def read_uff58(path: str | os.PathLike, *, assume_si: bool = False) -> list[UffRecord]:
    """Read every dataset-58 record of a universal file (ASCII 58 or binary 58b).

    Parameters
    ----------
    path
        The ``.uff`` / ``.unv`` file.
    assume_si
        Ignore unit labels and dataset 164 and take the values as SI (noted
        in each record's ``conversions``). By default unit labels are honoured
        and an unknown label is an error.

    Returns
    -------
    list[UffRecord]
        In file order, signs normalised to positive directions, units SI.

    Raises
    ------
    NotFoundError
        If the file does not exist.
    InputError
        If the file is not a universal file, is truncated, holds no dataset
        58, or a record is malformed (unknown direction code, count mismatch,
        NaN, unknown unit label, non-frequency abscissa for an FRF).
    """
    import pyuff  # lazy: keep `import jointdb.io` light

    p = Path(path)
    if not p.is_file():
        raise NotFoundError(f"UFF file {p} does not exist")
    data = p.read_bytes()
    _scan_blocks(p, data)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # numpy warnings on garbage; refused below with one line
            uff = pyuff.UFF(str(p))
            types = [int(t) for t in uff.get_set_types()]
    except Exception as exc:  # pyuff raises bare Exception for every failure
        raise InputError(f"{p}: cannot be read as a universal file ({exc})") from None
    if 58 not in types:
        found = ", ".join(str(t) for t in sorted(set(types))) or "none"
        raise InputError(f"{p}: holds no dataset 58 (function at nodal DOF); datasets found: {found}")
    units: _UnitSystem | None = None
    records = []
    for i, t in enumerate(types):
        if t not in (58, 164):
            continue
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # e.g. NaN arithmetic on a damaged 58b block: refused below
                d = uff.read_sets(i)
        except Exception as exc:  # pyuff raises bare Exception for every failure
            raise InputError(f"{p}: dataset #{i + 1} ({t}) is malformed and cannot be parsed ({exc})") from None
        if t == 164:
            try:
                units = _UnitSystem(int(d["units_code"]), float(d["length"]), float(d["force"]))
            except (KeyError, TypeError, ValueError):
                raise InputError(f"{p}: dataset #{i + 1} (164, units) is malformed") from None
            if units.length <= 0 or units.force <= 0:
                raise InputError(f"{p}: dataset #{i + 1} (164, units) has non-positive conversion factors")
            continue
        records.append(_record_from_dict(d, i + 1, p, units, assume_si))
    return records
