"""Unit labels of FRFs: SI labels for export, and parsing of file labels to SI factors.

Only what FRF exchange needs: response units (length or angle, divided by
seconds^p), excitation units (force or moment) and the abscissa (frequency).
Every parser returns the factor that turns a file value into SI
(``value_SI = factor * value_file``) and raises :class:`InputError` for a label
it does not know or that contradicts the DOF or the data-type code.
"""

from __future__ import annotations

import math

from jointdb.errors import InputError
from jointdb.frf import Dof, Quantity

#: UFF58 "specific data type" codes (records 8-10) used for FRFs.
UFF_DATA_TYPES: dict[int, str] = {
    0: "unknown",
    1: "general",
    2: "stress",
    3: "strain",
    5: "temperature",
    6: "heat flux",
    8: "displacement",
    9: "reaction force",
    11: "velocity",
    12: "acceleration",
    13: "excitation force",
    15: "pressure",
    16: "mass",
    17: "time",
    18: "frequency",
    19: "rpm",
    20: "order",
}

#: Response data-type code (ordinate numerator) for each quantity, and back.
QUANTITY_TO_UFF_CODE: dict[Quantity, int] = {
    Quantity.RECEPTANCE: 8,
    Quantity.MOBILITY: 11,
    Quantity.ACCELERANCE: 12,
}
UFF_CODE_TO_QUANTITY: dict[int, Quantity] = {v: k for k, v in QUANTITY_TO_UFF_CODE.items()}

_NONE_LABELS = {"", "none", "null"}

_LENGTH = {"m": 1.0, "mm": 1e-3, "cm": 1e-2, "um": 1e-6, "micron": 1e-6, "nm": 1e-9, "in": 0.0254,
           "inch": 0.0254, "ft": 0.3048}
_ANGLE = {"rad": 1.0, "mrad": 1e-3, "deg": math.pi / 180.0, "degree": math.pi / 180.0, "°": math.pi / 180.0}
_G0 = 9.80665
_LBF = 4.4482216152605
_FORCE = {"n": 1.0, "newton": 1.0, "kn": 1e3, "mn": 1e-3, "lbf": _LBF, "lb": _LBF, "kgf": _G0}
_MOMENT = {"nm": 1.0, "nmm": 1e-3, "knm": 1e3, "lbfin": _LBF * 0.0254, "inlbf": _LBF * 0.0254,
           "lbin": _LBF * 0.0254, "inlb": _LBF * 0.0254, "lbfft": _LBF * 0.3048, "ftlbf": _LBF * 0.3048}
# time suffixes -> power of 1/s, longest first
_TIME_SUFFIXES = (("/sec^2", 2), ("/sec2", 2), ("/s^2", 2), ("/s2", 2), ("/s/s", 2), ("/sec", 1), ("/s", 1))
_FREQ = {"hz": 1.0, "1/s": 1.0, "khz": 1e3, "rad/s": 1.0 / (2.0 * math.pi), "cpm": 1.0 / 60.0}


_FREQ_NAMES = ("Hz", "1/s", "kHz", "rad/s", "cpm")


def known_response_units() -> str:
    """The response unit labels the parsers accept, as one line for error messages."""
    return (f"lengths {', '.join(_LENGTH)}; angles {', '.join(_ANGLE)}; each optionally followed by /s or /s^2 "
            "(velocity, acceleration); g for an acceleration")


def known_excitation_units() -> str:
    """The excitation unit labels the parsers accept, as one line for error messages."""
    return f"forces {', '.join(('N', 'kN', 'mN', 'lbf', 'lb', 'kgf'))}; moments {', '.join(('N*m', 'N*mm', 'kN*m', 'lbf*in', 'lbf*ft'))}"


def is_none_label(label: str | None) -> bool:
    """True for an absent unit label (``None``, empty, ``"NONE"``)."""
    return label is None or str(label).strip().lower() in _NONE_LABELS


def _norm(label: str) -> str:
    s = str(label).strip().lower()
    for a, b in (("µ", "u"), ("μ", "u"), ("²", "^2"), ("**", "^"), ("[", ""), ("]", ""), (" ", "")):
        s = s.replace(a, b)
    return s


def response_label(quantity: Quantity | str, rotational: bool) -> str:
    """SI unit of the response: ``m``, ``m/s``, ``m/s^2`` (``rad...`` for rotations)."""
    base = "rad" if rotational else "m"
    return base + ("", "/s", "/s^2")[Quantity.parse(quantity).power]


def excitation_label(rotational: bool) -> str:
    """SI unit of the excitation: ``N`` or ``N*m``."""
    return "N*m" if rotational else "N"


def unit_label(quantity: Quantity | str, output: Dof, input: Dof) -> str:  # noqa: A002
    """SI unit of one FRF entry, e.g. ``"m/s^2/N"`` or ``"rad/(N*m)"``.

    Parameters
    ----------
    quantity
        Receptance, mobility or accelerance.
    output, input
        The response and excitation DOFs (a rotation gives rad, a moment N*m).

    Returns
    -------
    str

    Examples
    --------
    >>> from jointdb import Dof
    >>> from jointdb.io import unit_label
    >>> unit_label("accelerance", Dof(1, "x"), Dof(1, "x")), unit_label("receptance", Dof(1, "ry"), Dof(1, "ry"))
    ('m/s^2/N', 'rad/(N*m)')
    """
    num = response_label(quantity, output.is_rotation)
    den = excitation_label(input.is_rotation)
    return f"{num}/({den})" if input.is_rotation else f"{num}/{den}"


def response_factor(label: str, quantity: Quantity, dof: Dof, where: str) -> float:
    """Factor to SI for a response unit label (``value_SI = factor * value``).

    Raises
    ------
    InputError
        Unknown label, a rotational unit on a translation (or vice versa), or a
        time derivative that contradicts ``quantity``.
    """
    s = _norm(label)
    if s in ("g", "gn", "g's", "gs"):
        if dof.is_rotation or quantity is not Quantity.ACCELERANCE:
            raise InputError(f"{where}: response unit {label!r} (g) does not fit a {quantity.value} on DOF {dof}")
        return _G0
    power = 0
    for suffix, p in _TIME_SUFFIXES:
        if s.endswith(suffix):
            s, power = s[: -len(suffix)], p
            break
    factor = _unit_factor(
        s, (_LENGTH, _ANGLE), dof,
        lambda: f"{where}: unknown response unit label {label!r}; known: {known_response_units()}",
        lambda kind: f"{where}: response unit {label!r} is {kind} but DOF {dof} is not",
        ("translational", "rotational"),
    )
    if power != quantity.power:
        named = ("displacement", "velocity", "acceleration")[power]
        raise InputError(
            f"{where}: response unit {label!r} is a {named} but the data-type code says {quantity.value}"
        )
    return factor


def excitation_factor(label: str, dof: Dof, where: str) -> float:
    """Factor to SI for an excitation unit label (force for translations, moment for rotations).

    Raises
    ------
    InputError
        Unknown label, or a force on a rotational DOF (moment on a translation).
    """
    s = _norm(label)
    for ch in ("*", ".", "-", "·", "(", ")"):
        s = s.replace(ch, "")
    return _unit_factor(
        s, (_FORCE, _MOMENT), dof,
        lambda: f"{where}: unknown excitation unit label {label!r}; known: {known_excitation_units()}",
        lambda kind: f"{where}: excitation unit {label!r} is {kind}, which does not fit DOF {dof}",
        ("a force", "a moment"),
    )


def _unit_factor(unit: str, tables: tuple, dof: Dof, unknown, mismatch, kinds: tuple) -> float:
    """The factor to SI of a normalised unit label, looked up in ``tables`` = ``(translational,
    rotational)`` and checked against ``dof``'s kind. InputError with ``unknown()`` when the label is in
    neither table, with ``mismatch(kind)`` (``kind`` from ``kinds``, in the same order) when it does not
    fit the DOF."""
    for rotational, table in enumerate(tables):
        if unit in table:
            if bool(rotational) != dof.is_rotation:
                raise InputError(mismatch(kinds[rotational]))
            return table[unit]
    raise InputError(unknown())


def split_frf_label(label: str) -> tuple[str, str] | None:
    """Split a combined label such as ``"m/s^2/N"`` or ``"g/(N*m)"`` into (response, excitation).

    Returns ``None`` when the label has no recognisable excitation part.
    """
    text = str(label).strip()
    if "/" not in text:
        return None
    head, tail = text.rsplit("/", 1)
    probe = _norm(tail)
    for ch in ("*", ".", "-", "·", "(", ")"):
        probe = probe.replace(ch, "")
    if probe in _FORCE or probe in _MOMENT:
        head = head.strip()
        if head.startswith("(") and head.endswith(")"):
            head = head[1:-1]
        return head, tail.strip()
    return None


def frequency_factor(label: str, where: str) -> float:
    """Factor from an abscissa unit label to Hz.

    Raises
    ------
    InputError
        If the label is not a frequency unit.
    """
    if is_none_label(label):
        return 1.0
    s = _norm(label)
    if s not in _FREQ:
        raise InputError(f"{where}: abscissa unit {label!r} is not a frequency unit; known: {', '.join(_FREQ_NAMES)}")
    return _FREQ[s]
