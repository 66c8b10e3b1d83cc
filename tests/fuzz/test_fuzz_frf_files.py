"""Fuzz corpus: malformed UFF58 (ASCII and 58b), HDF5 exchange and CSV FRF files through the CLI.

Each case is a deterministic edit of a valid seed file (or a file built from
scratch with h5py), read by ``jointdb lobes`` / ``jointdb modal-fit`` with an
output path requested; see :mod:`fuzz_helpers` for what is asserted.
"""

from __future__ import annotations

import numpy as np
import pytest
from fuzz_helpers import INPUT, INTEGRITY, NOT_FOUND, Case, check_case, seed_bytes

LOBES = ["--kt", "6e8", "--kr", "2e8", "--plot", "lobes.png"]


def _uff_lines() -> list[str]:
    return seed_bytes("uff").decode().split("\n")


def uff_edit(line_no: int | None = None, new: str | None = None, *, find: str | None = None,
             replace: str | None = None) -> bytes:
    """The ASCII seed with line ``line_no`` (0-based) replaced, or ``find`` replaced by ``replace`` once."""
    if find is not None:
        text = seed_bytes("uff").decode()
        assert find in text, find
        return text.replace(find, replace, 1).encode()
    lines = _uff_lines()
    lines[line_no] = new
    return "\n".join(lines).encode()


# Line numbers of the ASCII seed (dataset 164 first, then one dataset 58).
HEADER6 = 13  # record 6: function type, response/reference node and direction
HEADER7 = 14  # record 7: ordinate type, number of points, spacing, min, step
HEADER8 = 15  # record 8: abscissa data type and unit label
FIRST_VALUES = 19


def _rec7(n="16", start="1.00000e+01", step="5.00000e+00", ord_type="6", even="1") -> str:
    return f"{ord_type:>10}{n:>10}{even:>10}  {start:>11}  {step:>11}  0.00000e+00"


def _rec6(func="4", rnode="1", rdir="1", fnode="1", fdir="1") -> str:
    return f"{func:>5}         0    0         0       NONE{rnode:>10}{rdir:>4}       NONE{fnode:>10}{fdir:>4}"


def _uff_cases() -> list[Case]:
    seed = seed_bytes("uff")
    text = seed.decode()
    rng = np.random.default_rng(58)
    c = []

    def add(cid, content, codes=(INPUT,), match="x.uff"):
        c.append(Case(f"uff-{cid}", ["lobes", "x.uff", *LOBES], {"x.uff": content}, codes, match))

    add("empty", b"")
    add("only-delimiter", b"    -1\n")
    add("two-delimiters", b"    -1\n    -1\n")
    for frac in (0.1, 0.5, 0.9, 0.99):
        add(f"truncated-{frac}", seed[: int(len(seed) * frac)])
    lines = _uff_lines()
    add("values-line-dropped", "\n".join(lines[:FIRST_VALUES] + lines[FIRST_VALUES + 1:]).encode())
    add("count-huge", uff_edit(HEADER7, _rec7(n="999999999")))
    add("count-negative", uff_edit(HEADER7, _rec7(n="-5")))
    add("count-zero", uff_edit(HEADER7, _rec7(n="0")))
    add("count-text", uff_edit(HEADER7, _rec7(n="abc")))
    add("step-nan", uff_edit(HEADER7, _rec7(step="nan")))
    add("step-zero", uff_edit(HEADER7, _rec7(step="0.00000e+00")))
    add("step-negative", uff_edit(HEADER7, _rec7(step="-5.0000e+00")))
    add("start-inf", uff_edit(HEADER7, _rec7(start="inf")))
    add("start-negative", uff_edit(HEADER7, _rec7(start="-1.0000e+02")))
    add("ordinate-type-7", uff_edit(HEADER7, _rec7(ord_type="7")))
    add("uneven-flag-without-abscissa", uff_edit(HEADER7, _rec7(even="0")))
    add("direction-9", uff_edit(HEADER6, _rec6(rdir="9")))
    add("direction-text", uff_edit(HEADER6, _rec6(rdir="x")))
    add("node-negative", uff_edit(HEADER6, _rec6(fnode="-3")))
    add("function-type-text", uff_edit(HEADER6, _rec6(func="abc")))
    add("value-overflow", uff_edit(find="3.45584192065e-07", replace="1.00000000e+999"))
    add("value-nan", uff_edit(find="3.45584192065e-07", replace="              nan"))
    add("value-garbage", uff_edit(find="3.45584192065e-07", replace="3.455841920#5e-07"))
    add("abscissa-time", uff_edit(HEADER8, "        17    0    0    0 Time                 s                   "))
    add("unit-furlong", uff_edit(find="Receptance           m     ", replace="Receptance           furlong"))
    add("no-dataset-58", text.replace("    58    ", "    59    ").encode())
    add("only-164", b"\n".join(seed.split(b"\n")[:6]) + b"\n")
    add("units-164-zero", uff_edit(3, "   0.0000000000000000D+00   1.0000000000000000D+00   1.0000000000000000D+00"))
    add("units-164-text", uff_edit(3, "   one                      1.0000000000000000D+00   1.0000000000000000D+00"))
    add("random-bytes", rng.integers(0, 256, 4096, dtype=np.uint8).tobytes())
    add("random-bytes-with-delimiters", b"    -1\n    58\n" + rng.integers(0, 256, 2048, dtype=np.uint8).tobytes()
        + b"\n    -1\n")
    add("utf16", text.encode("utf-16"))
    add("nul-bytes", seed.replace(b"3.45584192065e-07", b"3.4558\x00192065e-07", 1))
    add("readme-text", b"This is not a universal file.\nJust some words.\n")
    add("duplicate-record", seed + b"\n".join(seed.split(b"\n")[6:]))
    add("id-lines-missing", "\n".join(lines[:8] + lines[13:]).encode())
    add("crlf-truncated", text.replace("\n", "\r\n").encode()[:900])
    # binary 58b
    b = seed_bytes("uffb")
    addb = lambda cid, content, codes=(INPUT,): c.append(  # noqa: E731
        Case(f"uff58b-{cid}", ["lobes", "x.uff", *LOBES], {"x.uff": content}, codes, "x.uff"))
    addb("truncated-data", b[: len(b) - 100])
    addb("truncated-header", b[:400])
    # the seed's binary block is its last 256 + 7 bytes: 16 complex doubles, then "    -1\n"
    addb("data-odd-length", b[:-263] + b[-260:])
    addb("data-one-double", b[:-263] + b[-263:-255] + b[-7:])
    header6 = b.split(b"\n")
    header6[13] = rng.integers(33, 127, 80, dtype=np.uint8).tobytes()
    addb("garbage-in-header", b"\n".join(header6))
    addb("nan-values", b[:-263] + np.full(32, np.nan).tobytes() + b[-7:], (INPUT,))
    # a directory where a file is expected is "not found" (no such file)
    c.append(Case("uff-is-a-directory", ["lobes", "x.uff", *LOBES], {"x.uff/keep": b""}, (NOT_FOUND, INPUT)))
    c.append(Case("uff-missing", ["lobes", "nothere.uff", *LOBES], {}, (NOT_FOUND,), "nothere.uff"))
    c.append(Case("uff-modal-fit-truncated", ["modal-fit", "x.uff", "--plot", "figs"], {"x.uff": seed[:700]},
                  (INPUT,), "x.uff"))
    return c


def _h5(build):
    """A file writer for :class:`Case` that builds an HDF5 file with h5py from ``build(f)``."""
    def write(path):
        import h5py

        with h5py.File(path, "w") as f:
            build(f)
    return write


def _valid_h5(f, *, freq=None, values=None, outputs=("1x",), inputs=("1x",), skip=(), attrs=None):
    import h5py

    n = 8 if freq is None else (1 if np.ndim(freq) == 0 else len(freq))
    a = {"format": "jointdb-frf", "format_version": 1, "quantity": "receptance", "metadata": "{}"}
    a.update(attrs or {})
    for k, v in a.items():
        if k not in skip:
            f.attrs[k] = v
    data = {
        "freq": np.arange(1.0, n + 1.0) if freq is None else freq,
        "values": np.ones((n, len(outputs), len(inputs), 2)) if values is None else values,
        "outputs": np.array(outputs, dtype=object), "inputs": np.array(inputs, dtype=object),
    }
    for k, v in data.items():
        if k in skip:
            continue
        if isinstance(v, np.ndarray) and v.dtype == object:
            f.create_dataset(k, data=v, dtype=h5py.string_dtype())
        else:
            f.create_dataset(k, data=v)


def _h5_cases() -> list[Case]:
    seed = seed_bytes("h5")
    c = []

    def add(cid, content, codes=(INPUT,)):
        c.append(Case(f"h5-{cid}", ["lobes", "x.h5", *LOBES], {"x.h5": content}, codes, "x.h5"))

    add("empty", b"")
    add("text", b"freq,values\n1,2\n")
    add("truncated-half", seed[: len(seed) // 2])
    add("truncated-end", seed[:-64])
    flipped = bytearray(seed)
    for k in range(len(seed) // 3, 2 * len(seed) // 3):
        flipped[k] ^= 0xFF
    add("flipped-bytes", bytes(flipped), (INPUT, INTEGRITY))
    add("no-format", _h5(lambda f: _valid_h5(f, skip=("format",))))
    add("other-format", _h5(lambda f: _valid_h5(f, attrs={"format": "other"})))
    add("version-99", _h5(lambda f: _valid_h5(f, attrs={"format_version": 99})))
    add("version-text", _h5(lambda f: _valid_h5(f, attrs={"format_version": "one"})))
    add("version-array", _h5(lambda f: _valid_h5(f, attrs={"format_version": np.array([1, 2])})))
    add("version-float-nan", _h5(lambda f: _valid_h5(f, attrs={"format_version": np.nan})))
    add("format-bytes-array", _h5(lambda f: _valid_h5(f, attrs={"format": np.array([b"jointdb-frf", b"x"])})))
    add("quantity-banana", _h5(lambda f: _valid_h5(f, attrs={"quantity": "banana"})))
    add("quantity-missing", _h5(lambda f: _valid_h5(f, skip=("quantity",))))
    add("quantity-number", _h5(lambda f: _valid_h5(f, attrs={"quantity": 3})))
    add("metadata-bad-json", _h5(lambda f: _valid_h5(f, attrs={"metadata": "{oops"})))
    add("freq-missing", _h5(lambda f: _valid_h5(f, skip=("freq",))))
    add("freq-nan", _h5(lambda f: _valid_h5(f, freq=np.array([1.0, np.nan, 3.0]))))
    add("freq-inf", _h5(lambda f: _valid_h5(f, freq=np.array([1.0, 2.0, np.inf]))))
    add("freq-decreasing", _h5(lambda f: _valid_h5(f, freq=np.array([3.0, 2.0, 1.0]))))
    add("freq-repeated", _h5(lambda f: _valid_h5(f, freq=np.array([1.0, 1.0, 2.0]))))
    add("freq-empty", _h5(lambda f: _valid_h5(f, freq=np.zeros(0), values=np.zeros((0, 1, 1, 2)))))
    add("freq-2d", _h5(lambda f: _valid_h5(f, freq=np.ones((3, 2)), values=np.ones((3, 1, 1, 2)))))
    add("freq-strings", _h5(lambda f: _valid_h5(f, freq=np.array([b"a", b"b"]), values=np.ones((2, 1, 1, 2)))))
    add("freq-scalar", _h5(lambda f: _valid_h5(f, freq=np.float64(3.0), values=np.ones((1, 1, 1, 2)))))
    add("freq-is-group", _h5(lambda f: (_valid_h5(f, skip=("freq",)), f.create_group("freq"))))
    add("values-shape", _h5(lambda f: _valid_h5(f, values=np.ones((8, 2, 1, 2)))))
    add("values-last-axis-3", _h5(lambda f: _valid_h5(f, values=np.ones((8, 1, 1, 3)))))
    add("values-strings", _h5(lambda f: _valid_h5(f, values=np.array([b"x"] * 8).reshape(8, 1, 1))))
    add("values-nan", _h5(lambda f: _valid_h5(f, values=np.full((8, 1, 1, 2), np.nan))))
    add("values-missing", _h5(lambda f: _valid_h5(f, skip=("values",))))
    add("outputs-bad-label", _h5(lambda f: _valid_h5(f, outputs=("1q",))))
    add("outputs-numbers", _h5(lambda f: (_valid_h5(f, skip=("outputs",)), f.create_dataset("outputs", data=[7]))))
    add("outputs-empty", _h5(lambda f: _valid_h5(f, outputs=(), values=np.ones((8, 0, 1, 2)))))

    def huge(f):
        _valid_h5(f, skip=("freq", "values"))
        f.create_dataset("freq", shape=(2**40,), dtype="f8", chunks=(1024,))
        f.create_dataset("values", shape=(2**40, 1, 1, 2), dtype="f8", chunks=(1024, 1, 1, 2))
    add("declared-huge", _h5(huge))
    c.append(Case("h5-missing", ["lobes", "nothere.h5", *LOBES], {}, (NOT_FOUND,), "nothere.h5"))
    c.append(Case("h5-couple-joint-garbage", ["couple", "campaign.json", "--joint", "j.h5", "--out", "a.h5"],
                  {"__campaign__": True, "j.h5": b"\x89HDF\r\n\x1a\nbroken"}, (INPUT,), "j.h5"))
    return c


def _csv_cases() -> list[Case]:
    seed = seed_bytes("csv").decode()
    lines = seed.splitlines()
    c = []

    def add(cid, content):
        c.append(Case(f"csv-{cid}", ["lobes", "x.csv", *LOBES], {"x.csv": content}, (INPUT,), "x.csv"))

    add("empty", "")
    add("header-only", lines[0] + "\n")
    add("not-a-number", "\n".join(lines[:3] + ["20.0,abc,1e-7"] + lines[4:]))
    add("freq-nan", "\n".join(lines[:2] + ["nan,1e-7,1e-7"] + lines[3:]))
    add("freq-decreasing", "\n".join([lines[0]] + lines[1:][::-1]))
    add("value-inf", "\n".join(lines[:2] + ["15.0,inf,1e-7"] + lines[3:]))
    add("ragged", "\n".join(lines[:3] + ["20.0,1e-7"] + lines[4:]))
    add("bad-header", "frequency,Re a/b,Im a/b\n1,2,3\n")
    add("bad-dof", seed.replace("1x/1x", "1q/1x"))
    add("binary", np.random.default_rng(7).integers(0, 256, 512, dtype=np.uint8).tobytes())
    add("nul", seed.replace("10.0", "1\0.0", 1))
    add("huge-field", lines[0] + "\n" + "1" * 200_000 + ",1,1\n")
    add("latin1", (lines[0] + "\n10.0,1e-7,1e-7 \xb5m\n").encode("latin-1"))
    return c


CASES = _uff_cases() + _h5_cases() + _csv_cases()


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_malformed_frf_file_gives_one_line_and_writes_nothing(case, tmp_path, monkeypatch, capsys):
    check_case(case, tmp_path, monkeypatch, capsys)
