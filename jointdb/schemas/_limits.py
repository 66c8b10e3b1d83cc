"""Resource limits on what users hand to jointdb (model, stack and campaign files, CLI options).

A beam model file is a few kilobytes describing a few dozen segments; the
limits below are far above anything a real machine-tool model reaches but
stop a mistyped or hostile file before it allocates gigabytes, overflows a
float or exhausts the interpreter's recursion. Each message names the field,
the value and the limit, e.g.
``max_element_length: 1e-09 m would need 140000000 elements; the limit is 3000 (raise max_element_length)``.

Limits (SI units)
-----------------
- JSON description files: at most :data:`MAX_JSON_BYTES` bytes and
  :data:`MAX_JSON_DEPTH` levels of nesting (checked before parsing); every
  number finite and at most ``1e300`` in magnitude.
- Beam models: at most :data:`MAX_SEGMENTS` segments, :data:`MAX_ITEMS` points,
  clamps, supports, point masses and damping entries each, and
  :data:`MAX_ELEMENTS` finite elements after meshing (the matrices are
  dense: 3000 planar or 1000 frame3d elements are about 6000 DOFs, 290 MB per
  matrix). Lengths and diameters lie in ``[1e-6, 100]`` m, positions within
  ``±1000`` m, Young's moduli in ``[1e5, 1e13]`` Pa, densities in
  ``[1, 1e5]`` kg/m³.
- Frequency grids built from options or files: at most :data:`MAX_FREQ_LINES`
  lines.
- Stored catalogue records (checked before the write transaction, by
  :func:`check_stored_json` and :func:`check_text`; bundle imports and the HTTP
  API go through the same checks): free-form JSON fields (``conditions.extra``,
  provenance parameters) at most :data:`MAX_FIELD_DEPTH` levels deep,
  :data:`MAX_FIELD_BYTES` bytes encoded and :data:`MAX_FIELD_ENTRIES` keys and
  entries; keys of at most :data:`MAX_KEY_CHARS` and texts of at most
  :data:`MAX_TEXT_CHARS` characters; no NUL or other control characters (tab
  and line breaks only inside free text); numbers finite. A row that breaks
  these limits anyway (an older version, a damaged file) is reported as
  damaged when read, never served.

Plain standard library: the numerical core's file loaders may use it.
"""

from __future__ import annotations

import json
import math
import re
from typing import Any

from jointdb.errors import InputError

#: Largest JSON description file read [bytes].
MAX_JSON_BYTES = 16 * 1024 * 1024
#: Deepest nesting of objects/lists in a JSON description file.
MAX_JSON_DEPTH = 64
#: Largest magnitude of any number in a JSON description file.
MAX_JSON_NUMBER = 1e300
#: Most segments in one beam model.
MAX_SEGMENTS = 1000
#: Most entries in each list of a beam model (points, clamps, supports, point masses, damping).
MAX_ITEMS = 1000
#: Most finite elements of one beam model after meshing, by model kind (dense matrices).
MAX_ELEMENTS = {"planar": 3000, "frame3d": 1000}
#: Most frequency lines of a grid built from options or files.
MAX_FREQ_LINES = 200_000
#: Physical ranges (inclusive) of model quantities: (low, high, unit).
LENGTH_RANGE = (1e-6, 100.0, "m")
POSITION_LIMIT = 1000.0  # |position| in m
MODULUS_RANGE = (1e5, 1e13, "Pa")
DENSITY_RANGE = (1.0, 1e5, "kg/m³")
#: Largest magnitude of any other model number (stiffness, damping, mass, inertia, ...).
MAX_MODEL_NUMBER = 1e20


_JSON_STRING = re.compile(r'"(?:[^"\\\n]|\\.)*"')
_JSON_BRACKET = re.compile(r"[\[\]{}]")


def _fail(field: str, reason: str) -> InputError:
    return InputError(f"{field}: {reason}")


# ------------------------------------------------------------------ JSON text
def check_json_text(text: str, where: str) -> None:
    """Refuse a JSON text that is too large or nested too deeply, before parsing it.

    The nesting depth is counted over brackets outside strings, so a
    100 000-deep document is refused in one linear pass instead of
    exhausting the parser's recursion.

    Parameters
    ----------
    text
        The file's content.
    where
        The file, for messages (e.g. ``"model file m.json"``).

    Raises
    ------
    InputError
        Naming the file, the line and the limit.
    """
    if len(text) > MAX_JSON_BYTES:
        raise InputError(f"{where}: {len(text)} characters; the limit is {MAX_JSON_BYTES} "
                         "(a description file is a few kilobytes)")
    stripped = _JSON_STRING.sub('""', text)
    depth = 0
    for m in _JSON_BRACKET.finditer(stripped):
        depth += 1 if m.group() in "[{" else -1
        if depth > MAX_JSON_DEPTH:
            line = stripped.count("\n", 0, m.start()) + 1
            raise InputError(f"{where}: nested more than {MAX_JSON_DEPTH} levels deep (line {line}); "
                             f"the limit is {MAX_JSON_DEPTH}")


def check_json_numbers(value: Any, field: str = "") -> None:
    """Refuse NaN, ±Infinity and numbers beyond ``±1e300`` anywhere in a parsed JSON document.

    Python's ``json`` accepts ``NaN`` and ``Infinity`` and reads ``1e400`` as
    ``inf``; later arithmetic would then overflow or silently propagate NaN.
    Call only on documents checked by :func:`check_json_text` (bounded depth).

    Raises
    ------
    InputError
        ``segments[0].length: must be finite and of magnitude <= 1e+300, got inf``.
    """
    stack = [(field, value)]
    while stack:
        where, v = stack.pop()
        if isinstance(v, bool) or v is None or isinstance(v, str):
            continue
        if isinstance(v, (int, float)):
            _stored_number(v, where or "value")
        elif isinstance(v, dict):
            stack.extend((f"{where}.{k}" if where else str(k), item) for k, item in v.items())
        elif isinstance(v, list):
            stack.extend((f"{where}[{i}]", item) for i, item in enumerate(v))


# ------------------------------------------------------------------ counts and ranges
def check_count(n: int, field: str, limit: int, what: str = "entries") -> None:
    """Refuse more than ``limit`` items, naming the field and the limit."""
    if n > limit:
        raise _fail(field, f"{n} {what}; the limit is {limit}")


def _real(v: Any) -> float | None:
    """``v`` as a float when it is a plain finite number, else ``None`` (left to the field's own check)."""
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return None
    try:
        f = float(v)
    except OverflowError:
        return math.inf
    return f


def check_range(v: Any, field: str, low: float, high: float, unit: str) -> None:
    """Refuse a number outside ``[low, high]`` (non-numbers and values <= 0 are left to the field's own check)."""
    f = _real(v)
    if f is None or not (f > 0 or math.isinf(f)):
        return
    if not math.isfinite(f) or f > high:
        raise _fail(field, f"{v!r} {unit} is above the limit of {high:g} {unit}")
    if f < low:
        raise _fail(field, f"{v!r} {unit} is below the limit of {low:g} {unit}")


def check_magnitude(v: Any, field: str, limit: float, unit: str = "") -> None:
    """Refuse a number of magnitude above ``limit`` (non-numbers are left to the field's own check)."""
    f = _real(v)
    if f is not None and (not math.isfinite(f) or abs(f) > limit):
        u = f" {unit}" if unit else ""
        raise _fail(field, f"{v!r}{u} exceeds the limit of ±{limit:g}{u}")


def element_count(lengths: list[float], max_element_length: float) -> int:
    """Number of elements the mesher makes at least: Σ ceil(length / max_element_length)."""
    total = 0.0
    for length in lengths:
        total += max(1.0, math.ceil(length / max_element_length - 1e-9))
    return int(min(total, 1e18))


def check_elements(lengths: list[float], max_element_length: float, kind: str,
                   field: str = "max_element_length") -> None:
    """Refuse a mesh of more than :data:`MAX_ELEMENTS` elements for the model kind.

    Raises
    ------
    InputError
        ``max_element_length: 1e-09 m would need 140000000 elements; the limit is 3000 for a planar
        model (raise max_element_length)``.
    """
    limit = MAX_ELEMENTS.get(kind, min(MAX_ELEMENTS.values()))
    n = element_count(lengths, max_element_length)
    if n > limit:
        total = sum(lengths)
        if field == "max_element_length":
            raise _fail(field, f"{max_element_length:g} m would need {n} elements over {total:g} m of beam; the "
                               f"limit is {limit} for a {kind} model (raise max_element_length)")
        raise _fail(field, f"{total:g} m of beam would need {n} elements of {max_element_length:g} m; the limit is "
                           f"{limit} for a {kind} model")


# ------------------------------------------------------------------ model files
_MODEL_LISTS = ("points", "clamps", "supports", "point_masses", "damping", "joints", "insertions")
_POSITIONS = ("position", "start", "end")
_DIAMETERS = ("outer_diameter", "inner_diameter")


def check_model_limits(data: Any) -> None:
    """Resource limits on a parsed beam model description, before anything is built.

    Checks only what is well-typed (a wrong type is reported by the model
    reader with its own message): numbers finite and not absurd, counts of
    segments and other entries, physical ranges of lengths, diameters,
    positions, moduli and densities, and the number of elements after
    meshing. Limits are listed in the module docstring.

    Raises
    ------
    InputError
        Naming the field and the limit, e.g.
        ``segments: 100000 segments; the limit is 1000``.
    """
    if not isinstance(data, dict):
        return
    check_json_numbers(data)
    segments = data.get("segments")
    lengths: list[float] = []
    if isinstance(segments, list):
        check_count(len(segments), "segments", MAX_SEGMENTS, "segments")
        for i, s in enumerate(segments):
            if not isinstance(s, dict):
                continue
            p = f"segments[{i}]"
            for key in ("length", "outer_diameter", "inner_diameter"):
                check_range(s.get(key), f"{p}.{key}", *LENGTH_RANGE)
            _check_material(s.get("material"), f"{p}.material")
            f = _real(s.get("length"))
            if f is not None and f > 0:
                lengths.append(f)
    materials = data.get("materials")
    if isinstance(materials, dict):
        check_count(len(materials), "materials", MAX_ITEMS, "materials")
        for key, spec in materials.items():
            _check_material(spec, f"materials.{key}")
    for key in _MODEL_LISTS:
        items = data.get(key)
        if isinstance(items, list):
            check_count(len(items), key, MAX_ITEMS)
            for i, item in enumerate(items):
                if isinstance(item, dict):
                    _check_item(item, f"{key}[{i}]")
                    if key == "insertions":  # a concentric part: meshed over [start, end] as well
                        a, b = _real(item.get("start")), _real(item.get("end"))
                        if a is not None and b is not None and b > a:
                            lengths.append(b - a)
    mel_f = _real(data.get("max_element_length", 0.005))
    kind = data.get("kind", "planar")
    if lengths and mel_f is not None and mel_f > 0 and isinstance(kind, str):
        check_elements(lengths, mel_f, kind if kind in MAX_ELEMENTS else "frame3d")


def _check_material(spec: Any, field: str) -> None:
    if not isinstance(spec, dict):
        return
    check_range(spec.get("E"), f"{field}.E", *MODULUS_RANGE)
    check_range(spec.get("rho"), f"{field}.rho", *DENSITY_RANGE)


def _check_item(item: dict, field: str) -> None:
    for key, v in item.items():
        if key in _POSITIONS:
            check_magnitude(v, f"{field}.{key}", POSITION_LIMIT, "m")
        elif key in _DIAMETERS:
            check_range(v, f"{field}.{key}", *LENGTH_RANGE)
        elif key == "material":
            _check_material(v, f"{field}.material")
        elif isinstance(v, dict):
            for k2, v2 in v.items():
                check_magnitude(v2, f"{field}.{key}.{k2}", MAX_MODEL_NUMBER)
        elif isinstance(v, list):
            check_count(len(v), f"{field}.{key}", MAX_ITEMS)
            for i, v2 in enumerate(v):
                check_magnitude(v2, f"{field}.{key}[{i}]", MAX_MODEL_NUMBER)
        else:
            check_magnitude(v, f"{field}.{key}", MAX_MODEL_NUMBER)


# ------------------------------------------------------------------ frequency grids
def check_lines(n: float, field: str) -> None:
    """Refuse a frequency grid of more than :data:`MAX_FREQ_LINES` lines (``n`` may be a float estimate)."""
    if not math.isfinite(n) or n > MAX_FREQ_LINES:
        shown = f"{n:.3g}" if math.isfinite(n) else "infinitely many"
        raise _fail(field, f"gives {shown} frequency lines; the limit is {MAX_FREQ_LINES} (use a coarser step)")


# ------------------------------------------------------------------ stored records
#: Deepest nesting of a free-form JSON field stored in the catalogue (conditions.extra,
#: provenance parameters, ...): the same as for description files.
MAX_FIELD_DEPTH = MAX_JSON_DEPTH
#: Largest encoded size of one free-form JSON field of a stored record [bytes].
MAX_FIELD_BYTES = 2 * 1024 * 1024
#: Most keys and list entries, counted over all levels, of one stored JSON field.
MAX_FIELD_ENTRIES = 100_000
#: Longest key of a stored JSON object [characters].
MAX_KEY_CHARS = 1000
#: Longest string inside a stored JSON field, and longest free text (a deprecation reason) [characters].
MAX_TEXT_CHARS = 10_000
#: Most interface materials, geometry numbers, input files and quality metrics of one version.
MAX_MATERIALS = 20
MAX_GEOMETRY_KEYS = 100
MAX_INPUT_FILES = 1000
MAX_QUALITY_METRICS = 100

#: Control characters a stored string may never hold (NUL included): everything of Unicode
#: category Cc except tab, line feed and carriage return, plus lone surrogates (not UTF-8).
_CONTROL = re.compile(r"[\x00-\x08\x0b\x0c\x0e-\x1f\x7f-\x9f\ud800-\udfff]")
#: In names, keys and labels not even tab and line breaks are allowed.
_CONTROL_STRICT = re.compile(r"[\x00-\x1f\x7f-\x9f\ud800-\udfff]")


def control_character(text: str, strict: bool = True) -> str | None:
    """The first control character in ``text`` as ``U+XXXX`` (None when there is none).

    ``strict``: also tab, line feed and carriage return (names, keys, labels, query texts).
    """
    m = (_CONTROL_STRICT if strict else _CONTROL).search(text)
    return None if m is None else f"U+{ord(m.group()):04X}"


def check_text(value: Any, field: str, limit: int = MAX_TEXT_CHARS, strict: bool = False) -> str:
    """Refuse a stored text that is not a string, too long, or holds control characters.

    Raises
    ------
    InputError
        ``reason: holds the control character U+0000; the limit allows none``.
    """
    if not isinstance(value, str):
        raise _fail(field, f"must be text, got {type(value).__name__}")
    if len(value) > limit:
        raise _fail(field, f"{len(value)} characters; the limit is {limit}")
    bad = control_character(value, strict)
    if bad:
        raise _fail(field, f"holds the control character {bad}; control characters are not allowed")
    return value


def _stored_number(v: Any, where: str) -> None:
    try:
        ok = math.isfinite(v) and abs(v) <= MAX_JSON_NUMBER
    except OverflowError:  # an int too large for a float
        ok = False
    if not ok:
        shown = repr(v) if isinstance(v, float) else f"an integer of {len(str(abs(v)))} digits"
        raise _fail(where, f"must be finite and of magnitude <= {MAX_JSON_NUMBER:g}, got {shown}")


def check_stored_json(value: Any, field: str, max_bytes: int = MAX_FIELD_BYTES, texts: bool = True) -> None:
    """Refuse a value that the catalogue could store but not read back safely, before any write.

    Walks the value without recursion: plain JSON types only (objects with text keys, lists,
    text, finite numbers, booleans, null), at most :data:`MAX_FIELD_DEPTH` levels of nesting,
    :data:`MAX_FIELD_ENTRIES` keys and entries, keys of at most :data:`MAX_KEY_CHARS` and
    strings of at most :data:`MAX_TEXT_CHARS` characters, no control characters (none at all
    in keys; tab and line breaks allowed in strings), and at most ``max_bytes`` encoded.
    ``texts=False`` (reading back what is stored) skips the length and character checks of
    keys and strings.

    Raises
    ------
    InputError
        Naming the field (with the path inside it) and the limit, e.g.
        ``conditions.extra.a.a...: nested more than 64 levels deep; the limit is 64``.
    """
    stack = [(field, value, 0)]
    entries = 0
    while stack:
        where, v, depth = stack.pop()
        if v is None or isinstance(v, bool):
            continue
        if isinstance(v, str):
            if texts:
                check_text(v, where)
        elif isinstance(v, (int, float)):
            _stored_number(v, where)
        elif isinstance(v, (dict, list, tuple)):
            if depth >= MAX_FIELD_DEPTH:
                raise _fail(field, f"nested more than {MAX_FIELD_DEPTH} levels deep; the limit is {MAX_FIELD_DEPTH}")
            entries += len(v)
            if entries > MAX_FIELD_ENTRIES:
                raise _fail(field, f"more than {MAX_FIELD_ENTRIES} keys and entries; the limit is {MAX_FIELD_ENTRIES}")
            if isinstance(v, dict):
                for k, item in v.items():
                    if not isinstance(k, str):
                        raise _fail(where, f"key {str(k)[:40]!r} must be text, got {type(k).__name__}")
                    if texts:
                        check_text(k, f"{where} key {k[:40]!r}", MAX_KEY_CHARS, strict=True)
                    stack.append((f"{where}.{k[:40]}", item, depth + 1))
            else:
                stack.extend((f"{where}[{i}]", item, depth + 1) for i, item in enumerate(v))
        else:
            raise _fail(where, f"must be JSON (object, list, text, number, true/false or null), "
                               f"got {type(v).__name__}")
    size = len(json.dumps(value, ensure_ascii=False, allow_nan=False).encode("utf-8", "surrogatepass"))
    if size > max_bytes:
        raise _fail(field, f"{size} bytes encoded; the limit is {max_bytes}")
