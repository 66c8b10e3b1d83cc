"""UFF58 import/export: round trips, the real export, signs, units, grouping, bad files."""

import re
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from jointdb.errors import InputError, NotFoundError
from jointdb.frf import FRF, Dof, Quantity
from jointdb.io import (
    frf_from_records,
    import_uff58,
    read_frf_uff58,
    read_uff58,
    read_uff58_records,
    write_uff58,
)
from jointdb_io_helpers import REAL_UFF, raw58, write_raw

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


# ------------------------------------------------------------------ quantity and units
def test_quantity_conversion_on_read(tmp_path):
    frf = make_frf(np.arange(1.0, 31.0), quantity="accelerance", digits12=True)
    write_uff58(tmp_path / "q.uff", frf)
    rec = read_frf_uff58(tmp_path / "q.uff", quantity="receptance")
    assert rec.quantity is Quantity.RECEPTANCE
    assert np.allclose(rec.values, frf.values / (-(frf.omega**2))[:, None, None], rtol=1e-15, atol=0)
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
    assert np.allclose(h.entry("1x", "1x"), d * 9.80665 / 4.4482216152605, rtol=1e-15)
    assert np.allclose(h.entry("1x", "2x"), d * 1e-3 / 1e3, rtol=1e-15)
    assert np.allclose(h.entry("1x", "3x"), d * 9.80665, rtol=1e-15)
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
    assert np.allclose(h.values[:, 0, 0], (np.pi / 180) / 1e-3, rtol=1e-15)


def test_frequency_in_rad_per_s_is_converted(tmp_path):
    w = 2 * np.pi * np.arange(1.0, 6.0)
    path = write_raw(tmp_path / "w.uff", [raw58(1, 1, 1, 1, np.round(w, 4), even=False, binary=True,
                                                 labels=("rad/s", "NONE", "NONE"))])
    h = read_frf_uff58(path)
    assert np.allclose(h.freq, np.round(w, 4) / (2 * np.pi), rtol=1e-15)


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
    assert np.allclose(imp.frf.entry("1x", "1x"), d / 1000.0, rtol=1e-15)      # mm/N -> m/N
    assert np.allclose(imp.frf.entry("1x", "2rx"), d, rtol=1e-15)              # mm/(N mm) -> m/(N m)
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
    assert np.allclose(h.entry("1x", "1x"), d / (-(2 * np.pi * x) ** 2), rtol=1e-15)
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
        if calls["n"] == 3:
            raise OSError("disk full (simulated)")
        return real(self, *a, **k)

    monkeypatch.setattr(pyuff.UFF, "write_sets", failing)
    with pytest.raises(OSError):
        write_uff58(target, frf)
    assert list(tmp_path.iterdir()) == []
    # an existing file is left as it was
    monkeypatch.setattr(pyuff.UFF, "write_sets", real)
    write_uff58(target, frf)
    before = target.read_bytes()
    calls["n"] = 0
    monkeypatch.setattr(pyuff.UFF, "write_sets", failing)
    with pytest.raises(OSError):
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
