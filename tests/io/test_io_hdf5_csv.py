"""HDF5 exchange file and CSV: exact round trips, documented layout, atomic writes, bad files."""

import json
import re

import h5py
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from jointdb.errors import InputError, IntegrityError, NotFoundError
from jointdb.frf import FRF, Dof, Quantity
from jointdb.io import (
    HDF5_FORMAT,
    HDF5_FORMAT_VERSION,
    read_frf_csv,
    read_frf_hdf5,
    read_frf_hdf5_attrs,
    read_frf_hdf5_full,
    read_frf_uff58,
    unit_label,
    write_frf_csv,
    write_frf_hdf5,
)
from jointdb_io_helpers import REAL_UFF


def make_frf(n_freq=50, outputs=("1x", "2ry"), inputs=("1x", "3rz", "4y"), quantity="mobility", seed=0):
    rng = np.random.default_rng(seed)
    shape = (n_freq, len(outputs), len(inputs))
    freq = np.cumsum(rng.uniform(0.1, 10.0, n_freq))
    values = rng.normal(size=shape) * 10.0 ** rng.integers(-9, 3, size=shape) + 1j * rng.normal(size=shape)
    return FRF(freq, values, outputs, inputs, quantity)


def assert_identical(a, b):
    assert a.outputs == b.outputs and a.inputs == b.inputs and a.quantity is b.quantity
    assert np.array_equal(a.freq, b.freq) and np.array_equal(a.values, b.values)


def one_line(excinfo, *fragments):
    msg = str(excinfo.value)
    assert "\n" not in msg
    for frag in fragments:
        assert re.search(frag, msg, re.I), f"{frag!r} not in {msg!r}"


# ------------------------------------------------------------------ HDF5
@pytest.mark.parametrize("quantity", list(Quantity))
def test_hdf5_round_trip_is_bit_exact(tmp_path, quantity):
    frf = make_frf(quantity=quantity)
    write_frf_hdf5(tmp_path / "f.h5", frf)
    assert_identical(read_frf_hdf5(tmp_path / "f.h5"), frf)


def test_hdf5_real_export_round_trip(tmp_path):
    frf = read_frf_uff58(REAL_UFF)
    write_frf_hdf5(tmp_path / "r.h5", frf, attrs={"source": REAL_UFF.name})
    back, meta = read_frf_hdf5_full(tmp_path / "r.h5")
    assert_identical(back, frf)
    assert meta == {"source": REAL_UFF.name}


def test_hdf5_attrs_round_trip(tmp_path):
    attrs = {"joint": "HSK63", "preload_n": 25000.0, "torque_nm": np.float64(80.0), "n": np.int64(3),
             "geometry": {"d": 0.063}, "tags": ["a", "b"], "grid": np.array([1.0, 2.0])}
    write_frf_hdf5(tmp_path / "a.h5", make_frf(), attrs=attrs)
    got = read_frf_hdf5_attrs(tmp_path / "a.h5")
    assert got == {"joint": "HSK63", "preload_n": 25000.0, "torque_nm": 80.0, "n": 3, "geometry": {"d": 0.063},
                   "tags": ["a", "b"], "grid": [1.0, 2.0]}
    write_frf_hdf5(tmp_path / "b.h5", make_frf())
    assert read_frf_hdf5_attrs(tmp_path / "b.h5") == {}


def test_hdf5_layout_is_as_documented(tmp_path):
    frf = make_frf(n_freq=5000, quantity="accelerance")
    write_frf_hdf5(tmp_path / "l.h5", frf)
    with h5py.File(tmp_path / "l.h5", "r") as f:
        assert f.attrs["format"] == HDF5_FORMAT == "jointdb-frf"
        assert int(f.attrs["format_version"]) == HDF5_FORMAT_VERSION == 1
        assert f.attrs["quantity"] == "accelerance"
        assert f.attrs["frequency_unit"] == "Hz"
        assert "real part" in f.attrs["complex_convention"] and "imaginary" in f.attrs["complex_convention"]
        assert "+i omega t" in f.attrs["time_convention"]
        assert f.attrs["software"].startswith("jointdb ")
        json.loads(f.attrs["metadata"])
        v = f["values"]
        assert v.shape == (5000, 2, 3, 2) and v.dtype == np.float64
        assert v.chunks[1:] == (2, 3, 2) and v.chunks[0] < 5000  # chunked along frequency only
        assert v.shuffle and v.fletcher32 and v.compression == "gzip"
        assert f["freq"].fletcher32 and f["freq"].compression == "gzip" and f["freq"].attrs["unit"] == "Hz"
        assert np.array_equal(v[..., 0], frf.values.real) and np.array_equal(v[..., 1], frf.values.imag)
        assert [s.decode() for s in f["outputs"][()]] == ["1x", "2ry"]
        assert [s.decode() for s in f["inputs"][()]] == ["1x", "3rz", "4y"]
        units = f["units"][()].astype(str)
        assert units[0, 0] == "m/s^2/N" and units[1, 1] == "rad/s^2/(N*m)" and units[0, 1] == "m/s^2/(N*m)"


def test_hdf5_reads_a_complex_compound_values_dataset(tmp_path):
    frf = make_frf(n_freq=7)
    p = tmp_path / "c.h5"
    with h5py.File(p, "w") as f:
        f.attrs["format"] = "jointdb-frf"
        f.attrs["format_version"] = 1
        f.attrs["quantity"] = "mobility"
        f["freq"] = frf.freq
        f["values"] = frf.values
        f["outputs"] = [str(d).encode() for d in frf.outputs]
        f["inputs"] = [str(d).encode() for d in frf.inputs]
    assert_identical(read_frf_hdf5(p), frf)


def test_failed_hdf5_write_leaves_nothing_behind(tmp_path, monkeypatch):
    target = tmp_path / "t.h5"
    real = h5py.Group.create_dataset

    def failing(self, name, *a, **k):
        if name == "inputs":
            raise OSError("disk full (simulated)")
        return real(self, name, *a, **k)

    monkeypatch.setattr(h5py.Group, "create_dataset", failing)
    with pytest.raises(InputError, match="cannot write .*disk full"):  # one line for the user
        write_frf_hdf5(target, make_frf())
    assert list(tmp_path.iterdir()) == []
    monkeypatch.setattr(h5py.Group, "create_dataset", real)
    first = make_frf(seed=1)
    write_frf_hdf5(target, first)
    before = target.read_bytes()
    monkeypatch.setattr(h5py.Group, "create_dataset", failing)
    with pytest.raises(InputError, match="cannot write"):
        write_frf_hdf5(target, make_frf(seed=2))
    assert target.read_bytes() == before and [p.name for p in tmp_path.iterdir()] == ["t.h5"]
    monkeypatch.setattr(h5py.Group, "create_dataset", real)
    assert_identical(read_frf_hdf5(target), first)


def test_hdf5_bad_attrs_write_nothing(tmp_path):
    with pytest.raises(InputError) as e:
        write_frf_hdf5(tmp_path / "x.h5", make_frf(), attrs={"f": object()})
    one_line(e, "JSON")
    with pytest.raises(InputError):
        write_frf_hdf5(tmp_path / "x.h5", make_frf(), attrs={"nan": float("nan")})
    with pytest.raises(InputError):
        write_frf_hdf5(tmp_path / "x.h5", "not an frf")
    assert list(tmp_path.iterdir()) == []


def test_hdf5_bad_files(tmp_path):
    with pytest.raises(NotFoundError):
        read_frf_hdf5(tmp_path / "absent.h5")
    (tmp_path / "text.h5").write_text("not hdf5")
    with pytest.raises(InputError) as e:
        read_frf_hdf5(tmp_path / "text.h5")
    one_line(e, "not a readable HDF5 file")
    with h5py.File(tmp_path / "other.h5", "w") as f:
        f["x"] = [1, 2]
    with pytest.raises(InputError) as e:
        read_frf_hdf5(tmp_path / "other.h5")
    one_line(e, "not a jointdb FRF file")
    write_frf_hdf5(tmp_path / "new.h5", make_frf())
    with h5py.File(tmp_path / "new.h5", "a") as f:
        f.attrs["format_version"] = 2
    with pytest.raises(InputError) as e:
        read_frf_hdf5(tmp_path / "new.h5")
    one_line(e, "version 2", "upgrade")
    write_frf_hdf5(tmp_path / "miss.h5", make_frf())
    with h5py.File(tmp_path / "miss.h5", "a") as f:
        del f["inputs"]
    with pytest.raises(InputError) as e:
        read_frf_hdf5(tmp_path / "miss.h5")
    one_line(e, "missing dataset 'inputs'")
    write_frf_hdf5(tmp_path / "lab.h5", make_frf())
    with h5py.File(tmp_path / "lab.h5", "a") as f:
        del f["outputs"]
        f["outputs"] = [b"1x", b"2q"]
    with pytest.raises(InputError) as e:
        read_frf_hdf5(tmp_path / "lab.h5")
    one_line(e, "outputs", "2q")


def test_hdf5_corrupt_chunk_is_an_integrity_error(tmp_path):
    p = tmp_path / "bad.h5"
    write_frf_hdf5(p, make_frf(n_freq=3000))
    with h5py.File(p, "r") as f:
        info = f["values"].id.get_chunk_info(0)
    raw = bytearray(p.read_bytes())
    mid = info.byte_offset + info.size // 2
    raw[mid] ^= 0xFF
    p.write_bytes(bytes(raw))
    with pytest.raises(IntegrityError) as e:
        read_frf_hdf5(p)
    one_line(e, "values", "corrupt")


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(n_out=st.integers(1, 4), n_in=st.integers(1, 4), n_freq=st.integers(1, 300), seed=st.integers(0, 2**31),
       quantity=st.sampled_from(list(Quantity)))
def test_property_hdf5_and_csv_round_trips(tmp_path, n_out, n_in, n_freq, seed, quantity):
    rng = np.random.default_rng(seed)
    dirs = ["x", "y", "z", "rx", "ry", "rz"]
    outs = tuple(Dof(k, dirs[rng.integers(6)]) for k in range(1, n_out + 1))
    ins = tuple(Dof(k, dirs[rng.integers(6)]) for k in range(20, 20 + n_in))
    freq = np.cumsum(rng.exponential(3.0, n_freq) + 1e-3)
    vals = rng.standard_cauchy((n_freq, n_out, n_in)) + 1j * rng.normal(size=(n_freq, n_out, n_in))
    frf = FRF(freq, vals, outs, ins, quantity)
    write_frf_hdf5(tmp_path / f"{seed}.h5", frf)
    assert_identical(read_frf_hdf5(tmp_path / f"{seed}.h5"), frf)
    write_frf_csv(tmp_path / f"{seed}.csv", frf)
    assert_identical(read_frf_csv(tmp_path / f"{seed}.csv"), frf)


# ------------------------------------------------------------------ CSV
def test_csv_header_names_dofs_quantity_and_units(tmp_path):
    frf = make_frf(n_freq=4, outputs=("1x",), inputs=("2x", "3rz"), quantity="receptance")
    write_frf_csv(tmp_path / "f.csv", frf)
    lines = (tmp_path / "f.csv").read_text().splitlines()
    assert lines[0] == ("freq [Hz],Re 1x/2x receptance [m/N],Im 1x/2x receptance [m/N],"
                        "Re 1x/3rz receptance [m/(N*m)],Im 1x/3rz receptance [m/(N*m)]")
    assert len(lines) == 5
    row = [float(x) for x in lines[1].split(",")]
    assert row[0] == frf.freq[0] and complex(row[3], row[4]) == frf.values[0, 0, 1]
    assert_identical(read_frf_csv(tmp_path / "f.csv"), frf)


def test_csv_real_export_round_trip(tmp_path):
    frf = read_frf_uff58(REAL_UFF)
    write_frf_csv(tmp_path / "r.csv", frf)
    assert_identical(read_frf_csv(tmp_path / "r.csv"), frf)


@pytest.mark.parametrize("header, fragment", [
    ("time,Re 1x/1x mobility,Im 1x/1x mobility", "first column"),
    ("freq [Hz],Re 1x/1x mobility", "column pairs"),
    ("freq [Hz],Re 1x/1x mobility [m/s/N],Re 1x/1x mobility [m/s/N]", "not 'Im"),
    ("freq [Hz],Re 1x/1x mobility,Im 1x/2x mobility", "same entry"),
    ("freq [Hz],Re 1x/1x mobility,Im 1x/1x mobility,Re 1x/2x receptance,Im 1x/2x receptance", "mix quantities"),
    ("freq [Hz],Re 1x/1x mobility,Im 1x/1x mobility,Re 2x/2x mobility,Im 2x/2x mobility", "missing 1x/2x"),
    ("freq [Hz],Re 1q/1x mobility,Im 1q/1x mobility", "1q"),
])
def test_csv_bad_headers(tmp_path, header, fragment):
    n = header.count(",") + 1
    p = tmp_path / "b.csv"
    p.write_text(header + "\n" + ",".join(["1.0"] * n) + "\n")
    with pytest.raises(InputError) as e:
        read_frf_csv(p)
    one_line(e, fragment)


def test_csv_bad_rows(tmp_path):
    head = "freq [Hz],Re 1x/1x mobility,Im 1x/1x mobility\n"
    p = tmp_path / "r.csv"
    p.write_text(head + "1,2,3\n2,3\n")
    with pytest.raises(InputError) as e:
        read_frf_csv(p)
    one_line(e, "line 3 has 2 fields")
    p.write_text(head + "1,2,3\n2,abc,3\n")
    with pytest.raises(InputError) as e:
        read_frf_csv(p)
    one_line(e, "line 3", "not a number")
    p.write_text(head + "2,2,3\n1,3,3\n")
    with pytest.raises(InputError) as e:
        read_frf_csv(p)
    one_line(e, "strictly increasing")
    p.write_text(head)
    with pytest.raises(InputError) as e:
        read_frf_csv(p)
    one_line(e, "no data rows")
    with pytest.raises(NotFoundError):
        read_frf_csv(tmp_path / "absent.csv")


def test_failed_csv_write_leaves_previous_file(tmp_path, monkeypatch):
    import csv

    target = tmp_path / "t.csv"
    write_frf_csv(target, make_frf(seed=1))
    before = target.read_bytes()

    class Boom:
        def __init__(self, *a, **k):
            pass

        def writerow(self, row):
            pass

        def writerows(self, rows):
            raise OSError("disk full (simulated)")

    monkeypatch.setattr(csv, "writer", Boom)
    with pytest.raises(InputError, match="cannot write"):
        write_frf_csv(target, make_frf(seed=2))
    assert target.read_bytes() == before and [p.name for p in tmp_path.iterdir()] == ["t.csv"]


def test_unit_label():
    assert unit_label("receptance", Dof(1, "x"), Dof(2, "y")) == "m/N"
    assert unit_label("mobility", Dof(1, "rx"), Dof(2, "y")) == "rad/s/N"
    assert unit_label("accelerance", Dof(1, "z"), Dof(2, "ry")) == "m/s^2/(N*m)"
