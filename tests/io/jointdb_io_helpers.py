"""Helpers for the io tests: raw UFF58 datasets written with pyuff directly (independent of
jointdb's writer), test FRFs and comparison helpers."""

import re
import warnings
from pathlib import Path

import numpy as np

from jointdb.frf import FRF

DATA = Path(__file__).resolve().parents[1] / "data"
REAL_UFF = DATA / "measured-accelerance-3refs.uff"


def raw58(rsp_node=1, rsp_dir=1, ref_node=1, ref_dir=1, x=None, data=None, *, func_type=4, num=12, den=13,
          abscissa=18, even=True, binary=False, labels=("NONE", "NONE", "NONE")):
    """A dataset-58 dict for pyuff.UFF.write_sets."""
    x = np.arange(10.0) if x is None else np.asarray(x, dtype=float)
    if data is None:
        rng = np.random.default_rng(rsp_node * 100 + ref_node * 10 + abs(rsp_dir))
        data = rng.normal(size=x.size) + 1j * rng.normal(size=x.size)
    return {
        "type": 58, "binary": int(binary), "id1": "raw", "func_type": func_type,
        "rsp_node": rsp_node, "rsp_dir": rsp_dir, "ref_node": ref_node, "ref_dir": ref_dir,
        "ord_data_type": 6 if np.iscomplexobj(data) else 4, "abscissa_spacing": int(even),
        "abscissa_spec_data_type": abscissa, "ordinate_spec_data_type": num, "orddenom_spec_data_type": den,
        "abscissa_axis_units_lab": labels[0], "ordinate_axis_units_lab": labels[1],
        "orddenom_axis_units_lab": labels[2], "data": np.asarray(data), "x": x,
    }


def write_raw(path, datasets):
    import pyuff

    path = Path(path)
    if path.exists():
        path.unlink()
    uff = pyuff.UFF(str(path))
    with warnings.catch_warnings():
        # pyuff's 58b writer leaves a file handle to the garbage collector
        warnings.simplefilter("ignore", ResourceWarning)
        uff.write_sets(list(datasets), mode="add")  # pyuff: binary + "overwrite" truncates the header
    return path


# ASCII UFF58 keeps 12 significant digits of double values (E20.12): the
# largest relative change of an arbitrary float64 is half a unit in the 12th digit.
ASCII_VALUE_RTOL = 5e-12


def round12(a):
    """Values with at most 12 significant digits (exactly representable in ASCII UFF58)."""
    f = np.vectorize(lambda v: float("%.11e" % v))
    return f(a.real) + 1j * f(a.imag)


def make_frf(freq, outputs=("1x", "2y"), inputs=("1x", "3z", "4rx"), quantity="accelerance", seed=0, digits12=False):
    rng = np.random.default_rng(seed)
    shape = (len(freq), len(outputs), len(inputs))
    v = rng.normal(size=shape) * 10.0 ** rng.integers(-6, 3, size=shape) + 1j * rng.normal(size=shape)
    if digits12:
        v = round12(v)
    return FRF(freq, v, outputs, inputs, quantity)


def assert_identical(a: FRF, b: FRF):
    assert a.outputs == b.outputs and a.inputs == b.inputs and a.quantity == b.quantity
    assert np.array_equal(a.freq, b.freq), np.max(np.abs(a.freq - b.freq))
    assert np.array_equal(a.values, b.values), np.max(np.abs(a.values - b.values))


def one_line_error(excinfo, *fragments):
    msg = str(excinfo.value)
    assert "\n" not in msg, msg
    for frag in fragments:
        assert re.search(frag, msg, re.I), f"{frag!r} not in {msg!r}"
