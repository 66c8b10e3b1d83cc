"""UFF58 import: quantity and units, grouping into a matrix, bad files, atomic writes."""

import subprocess
import sys

import numpy as np
import pytest

from jointdb.errors import InputError, NotFoundError
from jointdb.frf import Dof, Quantity
from jointdb.io import (
    frf_from_records,
    import_uff58,
    read_frf_uff58,
    read_uff58,
    write_uff58,
)
from jointdb_io_helpers import (
    REAL_UFF,
    make_frf,
    one_line_error,
    raw58,
    round12,
    write_raw,
)


#: A unit conversion is a few multiplications/divisions (each ≤ ½ ulp) done by the reader and again
#: by the test in another order: agreement to a few eps, with no absolute floor (values are ~1e-6).
CONVERSION_RTOL = 8 * np.finfo(float).eps

# ------------------------------------------------------------------ quantity and units
def test_quantity_conversion_on_read(tmp_path):
    frf = make_frf(np.arange(1.0, 31.0), quantity="accelerance", digits12=True)
    write_uff58(tmp_path / "q.uff", frf)
    rec = read_frf_uff58(tmp_path / "q.uff", quantity="receptance")
    assert rec.quantity is Quantity.RECEPTANCE
    assert np.allclose(rec.values, frf.values / (-(frf.omega**2))[:, None, None], rtol=CONVERSION_RTOL, atol=0)
    with pytest.raises(InputError) as e:
        read_frf_uff58(REAL_UFF, quantity="receptance")  # starts at 0 Hz
    one_line_error(e, "0 Hz")
    mob = read_frf_uff58(REAL_UFF, quantity="accelerance")
    assert mob.quantity is Quantity.ACCELERANCE


def test_unit_labels_are_converted_to_si_and_noted(tmp_path):
    x = np.arange(1.0, 11.0)
    d = round12(np.linspace(1, 2, 10) + 1j)
    path = write_raw(tmp_path / "u.uff", [
        raw58(1, 1, 1, 1, x, d, labels=("Hz", "g", "lbf")),
        raw58(1, 1, 2, 1, x, d, labels=("Hz", "mm/s^2", "kN")),
        raw58(1, 1, 3, 1, x, d, labels=("NONE", "g/N", "NONE")),
    ])
    imp = import_uff58(path)
    h = imp.frf
    assert np.allclose(h.entry("1x", "1x"), d * 9.80665 / 4.4482216152605, rtol=CONVERSION_RTOL, atol=0)
    assert np.allclose(h.entry("1x", "2x"), d * 1e-3 / 1e3, rtol=CONVERSION_RTOL, atol=0)
    assert np.allclose(h.entry("1x", "3x"), d * 9.80665, rtol=CONVERSION_RTOL, atol=0)
    assert sum("converted to SI" in c for c in imp.conversions) == 5
    si = read_frf_uff58(path, assume_si=True)
    assert np.array_equal(si.entry("1x", "1x"), d)


def test_mobility_units_and_rotations(tmp_path):
    x = np.arange(1.0, 6.0)
    d = np.ones(5) + 0j
    path = write_raw(tmp_path / "m.uff", [
        raw58(1, 5, 1, 4, x, d, num=11, labels=("Hz", "deg/s", "N*mm")),
    ])
    h = read_frf_uff58(path)
    assert h.quantity is Quantity.MOBILITY and h.outputs == (Dof(1, "ry"),) and h.inputs == (Dof(1, "rx"),)
    assert np.allclose(h.values[:, 0, 0], (np.pi / 180) / 1e-3, rtol=CONVERSION_RTOL, atol=0)


def test_frequency_in_rad_per_s_is_converted(tmp_path):
    w = 2 * np.pi * np.arange(1.0, 6.0)
    path = write_raw(tmp_path / "w.uff", [raw58(1, 1, 1, 1, np.round(w, 4), even=False, binary=True,
                                                 labels=("rad/s", "NONE", "NONE"))])
    h = read_frf_uff58(path)
    assert np.allclose(h.freq, np.round(w, 4) / (2 * np.pi), rtol=CONVERSION_RTOL, atol=0)


def test_units_dataset_164_is_applied(tmp_path):
    import pyuff

    x = np.arange(1.0, 6.0)
    d = np.full(5, 2.0 + 1.0j)
    path = tmp_path / "mm.uff"
    uff = pyuff.UFF(str(path))
    # mm / N system: value_SI = value / length_factor for a length
    uff.write_sets([{"type": 164, "units_code": 6, "units_description": "mm (newton)", "temp_mode": 2,
                     "length": 1000.0, "force": 1.0, "temp": 1.0, "temp_offset": 273.15},
                    raw58(1, 1, 1, 1, x, d, num=8), raw58(1, 1, 2, 4, x, d, num=8)], mode="overwrite")
    imp = import_uff58(path)
    assert np.allclose(imp.frf.entry("1x", "1x"), d / 1000.0, rtol=CONVERSION_RTOL, atol=0)      # mm/N -> m/N
    assert np.allclose(imp.frf.entry("1x", "2rx"), d, rtol=CONVERSION_RTOL, atol=0)              # mm/(N mm) -> m/(N m)
    assert any("dataset 164" in c for c in imp.conversions)


@pytest.mark.parametrize("labels, fragment", [
    (("NONE", "furlongs", "NONE"), "unknown response unit"),
    (("NONE", "m/s", "NONE"), "velocity.*accelerance"),
    (("NONE", "rad/s^2", "NONE"), "rotational"),
    (("NONE", "NONE", "N*m"), "moment"),
    (("NONE", "NONE", "stone"), "unknown excitation unit"),
    (("seconds", "NONE", "NONE"), "not a frequency unit"),
])
def test_bad_or_contradicting_unit_labels(tmp_path, labels, fragment):
    path = write_raw(tmp_path / "b.uff", [raw58(labels=labels)])
    with pytest.raises(InputError) as e:
        read_frf_uff58(path)
    one_line_error(e, fragment, "dataset #1")


def test_unknown_quantity_codes_need_file_quantity(tmp_path):
    path = write_raw(tmp_path / "g.uff", [raw58(num=0, den=0)])
    with pytest.raises(InputError) as e:
        read_frf_uff58(path)
    one_line_error(e, "file_quantity")
    h = read_frf_uff58(path, file_quantity="mobility")
    assert h.quantity is Quantity.MOBILITY
    with pytest.raises(InputError):
        read_frf_uff58(REAL_UFF, file_quantity="mobility")  # contradicts the codes


def test_mixed_quantities_need_a_target(tmp_path):
    x = np.arange(1.0, 6.0)
    d = np.full(5, 1.0 + 0j)
    path = write_raw(tmp_path / "mix.uff", [raw58(1, 1, 1, 1, x, d, num=12), raw58(1, 1, 2, 1, x, d, num=8)])
    with pytest.raises(InputError) as e:
        read_frf_uff58(path)
    one_line_error(e, "mix quantities")
    h = read_frf_uff58(path, quantity="receptance")
    assert np.allclose(h.entry("1x", "1x"), d / (-(2 * np.pi * x) ** 2), rtol=CONVERSION_RTOL, atol=0)
    assert np.array_equal(h.entry("1x", "2x"), d)


def test_dynamic_stiffness_is_refused(tmp_path):
    path = write_raw(tmp_path / "k.uff", [raw58(num=13, den=8)])
    with pytest.raises(InputError) as e:
        read_frf_uff58(path)
    one_line_error(e, "dynamic stiffness")


# ------------------------------------------------------------------ grouping
def test_missing_pairs_are_named_and_reciprocity_can_fill(tmp_path):
    x = np.arange(1.0, 6.0)
    path = write_raw(tmp_path / "tri.uff", [raw58(1, 1, 1, 1, x), raw58(1, 1, 2, 1, x), raw58(2, 1, 2, 1, x)])
    with pytest.raises(InputError) as e:
        read_frf_uff58(path)
    one_line_error(e, "missing 1 pair", "2x/1x")
    imp = import_uff58(path, fill="reciprocity")
    h = imp.frf
    assert np.array_equal(h.entry("2x", "1x"), h.entry("1x", "2x"))
    assert any("reciprocity" in c for c in imp.conversions)
    path2 = write_raw(tmp_path / "gap.uff", [raw58(1, 1, 1, 1, x), raw58(2, 1, 3, 1, x)])
    with pytest.raises(InputError) as e:
        read_frf_uff58(path2, fill="reciprocity")
    one_line_error(e, "missing 2 pair", "1x/3x", "2x/1x")


def test_scalar_dof_and_general_function_type(tmp_path):
    path = write_raw(tmp_path / "sc.uff", [raw58(1, 0, 1, 1)])
    with pytest.raises(InputError) as e:
        read_frf_uff58(path)
    one_line_error(e, "scalar DOF", "dataset #1")
    path = write_raw(tmp_path / "gen.uff", [raw58(1, 1, 1, 1, func_type=0)])
    imp = import_uff58(path)
    assert imp.frf.quantity is Quantity.ACCELERANCE
    assert any("function type 0" in c for c in imp.conversions)


def test_duplicate_pairs_are_refused(tmp_path):
    path = write_raw(tmp_path / "dup.uff", [raw58(1, 1, 1, 1), raw58(1, 1, 1, 1)])
    with pytest.raises(InputError) as e:
        read_frf_uff58(path)
    one_line_error(e, "1x/1x appears twice", "#1", "#2")


def test_non_frf_records_are_skipped_with_a_note(tmp_path):
    x = np.arange(1.0, 6.0)
    path = write_raw(tmp_path / "coh.uff", [raw58(1, 1, 1, 1, x), raw58(1, 1, 1, 1, x, np.ones(5), func_type=6,
                                                                         num=0, den=0)])
    imp = import_uff58(path)
    assert imp.frf.shape == (5, 1, 1)
    assert len(imp.skipped) == 1 and "coherence" in imp.skipped[0]
    only = write_raw(tmp_path / "only.uff", [raw58(1, 1, 1, 1, x, np.ones(5), func_type=6, num=0, den=0)])
    with pytest.raises(InputError) as e:
        read_frf_uff58(only)
    one_line_error(e, "no FRF records", "coherence")


def test_frf_from_records_orders_by_first_appearance(tmp_path):
    x = np.arange(1.0, 6.0)
    path = write_raw(tmp_path / "o.uff", [raw58(3, 2, 9, 1, x), raw58(3, 2, 4, 1, x), raw58(1, 3, 9, 1, x),
                                          raw58(1, 3, 4, 1, x)])
    h = frf_from_records(read_uff58(path)).frf
    assert h.outputs == (Dof(3, "y"), Dof(1, "z")) and h.inputs == (Dof(9, "x"), Dof(4, "x"))


# ------------------------------------------------------------------ bad files
def test_truncated_file(tmp_path):
    raw = REAL_UFF.read_bytes()
    cut = tmp_path / "cut.uff"
    cut.write_bytes(raw[: int(len(raw) * 0.6)])
    with pytest.raises(InputError) as e:
        read_frf_uff58(cut)
    one_line_error(e, "truncated", "line")


def test_data_lines_missing_inside_a_record(tmp_path):
    lines = REAL_UFF.read_bytes().splitlines(keepends=True)
    del lines[600:640]  # inside record 2, closing -1 lines kept
    bad = tmp_path / "short.uff"
    bad.write_bytes(b"".join(lines))
    with pytest.raises(InputError) as e:
        read_frf_uff58(bad)
    one_line_error(e, "dataset #2", "header says 1001 values")


def test_not_dataset_58(tmp_path):
    import pyuff

    path = tmp_path / "nodes.uff"
    pyuff.UFF(str(path)).write_sets({"type": 15, "node_nums": [1, 2], "def_cs": [0, 0], "disp_cs": [0, 0],
                                     "color": [1, 1], "x": [0.0, 1.0], "y": [0.0, 0.0], "z": [0.0, 0.0]},
                                    mode="overwrite")
    with pytest.raises(InputError) as e:
        read_frf_uff58(path)
    one_line_error(e, "no dataset 58", "15")


def test_not_a_universal_file(tmp_path):
    path = tmp_path / "junk.uff"
    path.write_text("hello\nworld\n")
    with pytest.raises(InputError) as e:
        read_frf_uff58(path)
    one_line_error(e, "not a universal file")
    with pytest.raises(NotFoundError):
        read_frf_uff58(tmp_path / "absent.uff")


@pytest.mark.parametrize("old, new, fragment", [
    (b"TestCase         1   1   TestCase         1   1", b"TestCase         1   7   TestCase         1   1",
     "unknown response direction code 7"),
    (b"TestCase         1   1   TestCase         1   1", b"TestCase         1   1   TestCase         1  -9",
     "unknown reference direction code -9"),
])
def test_unknown_direction_codes(tmp_path, old, new, fragment):
    raw = REAL_UFF.read_bytes()
    assert old in raw
    bad = tmp_path / "dir.uff"
    bad.write_bytes(raw.replace(old, new, 1))
    with pytest.raises(InputError) as e:
        read_frf_uff58(bad)
    one_line_error(e, fragment, "dataset #1")


def test_garbled_header_is_an_input_error(tmp_path):
    raw = REAL_UFF.read_bytes()
    bad = tmp_path / "garbled.uff"
    bad.write_bytes(raw.replace(b"         6      1001         1", b"         6      10x1         1", 1))
    with pytest.raises(InputError) as e:
        read_frf_uff58(bad)
    one_line_error(e, "dataset #1", "malformed")


def test_inconsistent_grids(tmp_path):
    path = write_raw(tmp_path / "grids.uff", [raw58(1, 1, 1, 1, np.arange(10.0)),
                                              raw58(1, 1, 2, 1, np.arange(20.0))])
    with pytest.raises(InputError) as e:
        read_frf_uff58(path)
    one_line_error(e, "inconsistent frequency grids", "20 lines", "10 lines")


def test_non_frequency_abscissa(tmp_path):
    path = write_raw(tmp_path / "time.uff", [raw58(abscissa=17)])
    with pytest.raises(InputError) as e:
        read_frf_uff58(path)
    one_line_error(e, "not frequency")


# ------------------------------------------------------------------ atomic writes
def test_failed_uff_write_leaves_nothing_behind(tmp_path, monkeypatch):
    import pyuff

    frf = make_frf(np.arange(1.0, 11.0), digits12=True)
    target = tmp_path / "t.uff"
    calls = {"n": 0}
    real = pyuff.UFF.write_sets

    def failing(self, *a, **k):
        calls["n"] += 1
        if calls["n"] == 2:  # 1: the units dataset 164, 2: the FRF records
            raise OSError("disk full (simulated)")
        return real(self, *a, **k)

    monkeypatch.setattr(pyuff.UFF, "write_sets", failing)
    with pytest.raises(InputError, match="cannot write"):
        write_uff58(target, frf)
    assert list(tmp_path.iterdir()) == []
    # an existing file is left as it was
    monkeypatch.setattr(pyuff.UFF, "write_sets", real)
    write_uff58(target, frf)
    before = target.read_bytes()
    calls["n"] = 0
    monkeypatch.setattr(pyuff.UFF, "write_sets", failing)
    with pytest.raises(InputError, match="cannot write"):
        write_uff58(target, make_frf(np.arange(1.0, 11.0), seed=9, digits12=True))
    assert target.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["t.uff"]


def test_write_into_missing_directory(tmp_path):
    with pytest.raises(InputError) as e:
        write_uff58(tmp_path / "nope" / "x.uff", make_frf(np.arange(1.0, 4.0)))
    one_line_error(e, "does not exist")


def test_import_jointdb_io_is_lazy():
    code = "import sys, jointdb.io; print(','.join(m for m in ('h5py', 'pyuff') if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == ""


def test_single_precision_and_real_records_from_other_writers(tmp_path):
    import pyuff

    x = np.arange(1.0, 11.0)
    rng = np.random.default_rng(12)
    d = rng.normal(size=10) + 1j * rng.normal(size=10)
    single = raw58(1, 1, 1, 1, x, d)
    single["ord_data_type"] = 5
    real = raw58(1, 1, 2, 1, x, d.real)
    path = tmp_path / "sp.uff"
    pyuff.UFF(str(path)).write_sets([single, real], mode="add", force_double=False)
    recs = read_uff58(path)
    assert not recs[0].double_precision and recs[0].complex_data
    assert not recs[1].complex_data
    imp = import_uff58(path)
    assert np.allclose(imp.frf.entry("1x", "1x"), d, rtol=5e-6, atol=0)  # E13.5: 6 significant digits
    assert np.allclose(imp.frf.entry("1x", "2x"), d.real, rtol=5e-6, atol=0)
    assert any("real-valued ordinate" in c for c in imp.conversions)


def test_failed_binary_uff_write_leaves_nothing_behind(tmp_path, monkeypatch):
    import jointdb.io._uff58_write as W

    real = W._write_58b
    calls = {"n": 0}

    def failing(fh, ds):
        calls["n"] += 1
        if calls["n"] == 4:
            raise OSError("disk full (simulated)")
        real(fh, ds)

    target = tmp_path / "b.uff"
    write_uff58(target, make_frf(np.arange(1.0, 11.0)), binary=True)
    before = target.read_bytes()
    monkeypatch.setattr(W, "_write_58b", failing)
    with pytest.raises(InputError, match="cannot write"):
        write_uff58(target, make_frf(np.arange(1.0, 11.0), seed=4), binary=True)
    assert target.read_bytes() == before and [p.name for p in tmp_path.iterdir()] == ["b.uff"]
