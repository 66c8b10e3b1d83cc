"""UFF58 import/export: the real export, exact round trips (ASCII/binary, even/uneven), signs."""

import re

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from jointdb.errors import InputError
from jointdb.frf import FRF, Dof, Quantity
from jointdb.io import (
    import_uff58,
    read_frf_uff58,
    read_uff58,
    read_uff58_records,
    write_uff58,
)
from jointdb_io_helpers import (
    ASCII_VALUE_RTOL,
    REAL_UFF,
    assert_identical,
    make_frf,
    one_line_error,
    raw58,
    round12,
    write_raw,
)

# ------------------------------------------------------------------ the real export
def test_real_export_reads_with_correct_dofs_and_quantity():
    frf = read_frf_uff58(REAL_UFF)
    assert frf.outputs == (Dof(1, "x"),)
    assert frf.inputs == (Dof(1, "x"), Dof(2, "x"), Dof(3, "x"))
    assert frf.quantity is Quantity.ACCELERANCE
    assert frf.n_freq == 1001 and frf.freq[0] == 0.0 and frf.freq[-1] == 1000.0
    assert np.array_equal(frf.freq, np.arange(1001.0))


def test_real_export_values_match_the_text_of_the_file():
    # Parse the first data lines of each record straight from the text (independent of pyuff).
    lines = REAL_UFF.read_text().splitlines()
    starts = [k for k, ln in enumerate(lines) if ln.strip() == "58"]
    frf = read_frf_uff58(REAL_UFF)
    for j, s in enumerate(starts):
        nums = [float(x) for x in lines[s + 12].split()]  # first line of data: Re0 Im0 Re1 Im1
        assert frf.values[0, 0, j] == complex(nums[0], nums[1])
        assert frf.values[1, 0, j] == complex(nums[2], nums[3])
        last = [float(x) for x in lines[s + 12 + 500].split()]  # 1001 values: line 501 holds value 1000 only
        assert frf.values[1000, 0, j] == complex(last[0], last[1])


def test_real_export_records_and_import_notes():
    recs = read_uff58(REAL_UFF)
    assert read_uff58_records is read_uff58
    assert [r.index for r in recs] == [1, 2, 3]
    assert all(r.function_type == 4 and r.even and not r.binary and r.complex_data for r in recs)
    assert all(r.data_types == (18, 12, 13) for r in recs)
    imp = import_uff58(REAL_UFF)
    assert imp.conversions == () and imp.skipped == ()


@pytest.mark.parametrize("binary", [False, True])
def test_real_export_round_trips_exactly(tmp_path, binary):
    frf = read_frf_uff58(REAL_UFF)
    out = tmp_path / "rt.uff"
    write_uff58(out, frf, binary=binary)
    back = read_frf_uff58(out)
    assert_identical(back, frf)
    assert all(r.binary == binary and r.even for r in read_uff58(out))


# ------------------------------------------------------------------ round trips
@pytest.mark.parametrize("quantity", ["receptance", "mobility", "accelerance"])
def test_ascii_even_round_trip_exact_for_12_digit_values(tmp_path, quantity):
    frf = make_frf(10.0 + 0.5 * np.arange(37), quantity=quantity, digits12=True)
    write_uff58(tmp_path / "a.uff", frf)
    back = read_frf_uff58(tmp_path / "a.uff")
    assert_identical(back, frf)
    assert all(r.even and not r.binary for r in read_uff58(tmp_path / "a.uff"))


def test_ascii_round_trip_of_arbitrary_values_within_12_digits_and_idempotent(tmp_path):
    frf = make_frf(np.arange(1.0, 65.0), seed=3)
    write_uff58(tmp_path / "a.uff", frf)
    back = read_frf_uff58(tmp_path / "a.uff")
    err = np.abs(back.values - frf.values) / np.maximum(np.abs(frf.values), 1e-300)
    assert err.max() <= ASCII_VALUE_RTOL
    assert err.max() > 0  # arbitrary float64 really are rounded: the tolerance is needed
    write_uff58(tmp_path / "b.uff", back)
    assert (tmp_path / "a.uff").read_bytes() == (tmp_path / "b.uff").read_bytes()
    assert_identical(read_frf_uff58(tmp_path / "b.uff"), back)


def test_binary_even_round_trip_bit_exact_for_arbitrary_values(tmp_path):
    frf = make_frf(0.25 * np.arange(200), seed=5)
    write_uff58(tmp_path / "b.uff", frf, binary=True)
    assert_identical(read_frf_uff58(tmp_path / "b.uff"), frf)
    recs = read_uff58(tmp_path / "b.uff")
    assert all(r.binary and r.even and r.double_precision for r in recs)


def test_ascii_uneven_round_trip_exact(tmp_path):
    freq = np.array([float("%.5e" % f) for f in np.geomspace(3.0, 2000.0, 50)])
    frf = make_frf(freq, digits12=True, seed=7)
    write_uff58(tmp_path / "u.uff", frf)
    assert not any(r.even for r in read_uff58(tmp_path / "u.uff"))
    assert_identical(read_frf_uff58(tmp_path / "u.uff"), frf)


def test_binary_uneven_round_trip_bit_exact_for_arbitrary_grid(tmp_path):
    rng = np.random.default_rng(11)
    freq = np.sort(rng.uniform(1.0, 3000.0, 80))
    frf = make_frf(freq, seed=8)
    write_uff58(tmp_path / "u.uff", frf, binary=True)
    assert not any(r.even for r in read_uff58(tmp_path / "u.uff"))
    assert_identical(read_frf_uff58(tmp_path / "u.uff"), frf)


def test_forced_uneven_and_even(tmp_path):
    frf = make_frf(np.arange(5.0, 25.0), digits12=True)
    write_uff58(tmp_path / "u.uff", frf, abscissa="uneven")
    assert not read_uff58(tmp_path / "u.uff")[0].even
    assert_identical(read_frf_uff58(tmp_path / "u.uff"), frf)
    uneven = make_frf(np.array([1.0, 2.0, 4.0]))
    with pytest.raises(InputError) as e:
        write_uff58(tmp_path / "e.uff", uneven, abscissa="even")
    one_line_error(e, "not evenly spaced")
    with pytest.raises(InputError):
        write_uff58(tmp_path / "e.uff", uneven, abscissa="sideways")


def test_ascii_refuses_to_round_frequencies_unless_asked(tmp_path):
    freq = np.linspace(1.0, 2000.0, 301)  # increment 6.663333... has more than 6 significant digits
    frf = make_frf(freq, digits12=True)
    with pytest.raises(InputError) as e:
        write_uff58(tmp_path / "a.uff", frf)
    one_line_error(e, "6 significant digits", "binary=True")
    assert not (tmp_path / "a.uff").exists()
    write_uff58(tmp_path / "a.uff", frf, round_freq=True)
    back = read_frf_uff58(tmp_path / "a.uff")
    assert np.max(np.abs(back.freq - freq) / freq) <= 5e-6
    write_uff58(tmp_path / "b.uff", frf, binary=True)  # binary keeps them exactly
    assert_identical(read_frf_uff58(tmp_path / "b.uff"), frf)


def test_linspace_grid_written_even_comes_back_within_1e_12(tmp_path):
    freq = np.linspace(0.0, 100.0, 1001)  # 0.1 Hz: not every line is bit-identical to 0 + k*0.1
    frf = make_frf(freq, ("1x",), ("1x",), digits12=True)
    write_uff58(tmp_path / "a.uff", frf)
    back = read_frf_uff58(tmp_path / "a.uff")
    assert read_uff58(tmp_path / "a.uff")[0].even
    assert np.max(np.abs(back.freq - freq)) <= 1e-12 * 100.0
    assert np.array_equal(back.values, frf.values)


def test_single_line_frf(tmp_path):
    frf = make_frf(np.array([125.0]), ("2z",), ("2z",), digits12=True)
    for binary in (False, True):
        write_uff58(tmp_path / "s.uff", frf, binary=binary)
        assert_identical(read_frf_uff58(tmp_path / "s.uff"), frf)


def test_rotational_dofs_get_rotational_unit_labels(tmp_path):
    frf = make_frf(np.arange(1.0, 11.0), ("1ry", "2x"), ("1rz", "3y"), quantity="receptance", digits12=True)
    write_uff58(tmp_path / "r.uff", frf)
    recs = read_uff58(tmp_path / "r.uff")
    labels = {r.label: r.unit_labels for r in recs}
    assert labels["1ry/1rz"] == ("Hz", "rad", "N*m")
    assert labels["2x/3y"] == ("Hz", "m", "N")
    assert_identical(read_frf_uff58(tmp_path / "r.uff"), frf)


def test_written_file_is_read_by_plain_pyuff_with_the_standard_codes(tmp_path):
    import pyuff

    frf = make_frf(np.arange(1.0, 11.0), ("7y",), ("3z",), quantity="mobility", digits12=True)
    write_uff58(tmp_path / "p.uff", frf, binary=True)
    uff = pyuff.UFF(str(tmp_path / "p.uff"))
    assert list(uff.get_set_types()) == [164, 58]
    d = uff.read_sets(1)
    assert (d["func_type"], d["rsp_node"], d["rsp_dir"], d["ref_node"], d["ref_dir"]) == (4, 7, 2, 3, 3)
    assert (d["ordinate_spec_data_type"], d["orddenom_spec_data_type"], d["abscissa_spec_data_type"]) == (11, 13, 18)
    assert np.array_equal(d["data"], frf.values[:, 0, 0])


def test_binary_header_states_the_true_byte_count(tmp_path):
    frf = make_frf(np.arange(1.0, 11.0), ("1x",), ("1x", "2x"))
    for abscissa, per_line in (("even", 2), ("uneven", 3)):
        write_uff58(tmp_path / "b.uff", frf, binary=True, abscissa=abscissa)
        raw = (tmp_path / "b.uff").read_bytes()
        heads = [m.start() for m in re.finditer(rb"    58b", raw)]
        assert len(heads) == 2
        for h in heads:
            line = raw[h:raw.index(b"\n", h)].decode()
            # 58b header: byte ordering, fp format, n ascii lines, n bytes (6, 6, 12, 12 wide)
            n_bytes = int(line[7 + 6 + 6 + 12: 7 + 6 + 6 + 12 + 12])
            assert n_bytes == 8 * per_line * frf.n_freq


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    n_out=st.integers(1, 3), n_in=st.integers(1, 3), n_freq=st.integers(2, 40),
    quantity=st.sampled_from(["receptance", "mobility", "accelerance"]), seed=st.integers(0, 2**31),
    binary=st.booleans(),
)
def test_property_round_trip(tmp_path, n_out, n_in, n_freq, quantity, seed, binary):
    rng = np.random.default_rng(seed)
    outs = tuple(Dof(int(k), str(rng.choice(["x", "y", "z", "rx", "ry", "rz"]))) for k in range(1, n_out + 1))
    ins = tuple(Dof(int(k), str(rng.choice(["x", "y", "z", "rx", "ry", "rz"]))) for k in range(10, 10 + n_in))
    freq = np.cumsum(rng.integers(1, 50, n_freq)) * 0.125  # ASCII-representable uneven or even grid
    v = rng.normal(size=(n_freq, n_out, n_in)) + 1j * rng.normal(size=(n_freq, n_out, n_in))
    frf = FRF(freq, v if binary else round12(v), outs, ins, quantity)
    path = tmp_path / f"p{seed}.uff"
    write_uff58(path, frf, binary=binary)
    assert_identical(read_frf_uff58(path), frf)


# ------------------------------------------------------------------ signs
@pytest.mark.parametrize("binary", [False, True])
def test_negative_directions_are_normalised(tmp_path, binary):
    x = np.arange(1.0, 21.0)
    rng = np.random.default_rng(4)
    d = [round12(rng.normal(size=20) + 1j * rng.normal(size=20)) for _ in range(4)]
    path = write_raw(tmp_path / "neg.uff", [
        raw58(1, -2, 5, 1, x, d[0], binary=binary),   # response -Y
        raw58(1, -2, 6, -3, x, d[1], binary=binary),  # both negative: signs cancel
        raw58(2, 1, 5, -1, x, d[2], binary=binary),   # reference -X
        raw58(2, 1, 6, -3, x, d[3], binary=binary),
    ])
    imp = import_uff58(path)
    frf = imp.frf
    assert frf.outputs == (Dof(1, "y"), Dof(2, "x"))
    assert frf.inputs == (Dof(5, "x"), Dof(6, "z"))
    assert np.array_equal(frf.entry("1y", "5x"), -d[0])
    assert np.array_equal(frf.entry("1y", "6z"), d[1])
    assert np.array_equal(frf.entry("2x", "5x"), -d[2])
    assert np.array_equal(frf.entry("2x", "6z"), -d[3])
    rec = read_uff58(path)[0]
    assert (rec.response_sign, rec.reference_sign) == (-1, 1)
    assert any("negative direction" in c and "negated" in c for c in imp.conversions)
    assert any("signs cancel" in c for c in imp.conversions)
    # written back with positive directions, read again: identical
    write_uff58(tmp_path / "pos.uff", frf, binary=binary)
    assert all(r.response_sign == 1 and r.reference_sign == 1 for r in read_uff58(tmp_path / "pos.uff"))
    assert_identical(read_frf_uff58(tmp_path / "pos.uff"), frf)


