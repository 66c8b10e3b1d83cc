"""Coherence records (UFF58 function type 6): written with the FRF, read back aligned with it."""

import numpy as np
import pytest

from jointdb.errors import InputError
from jointdb.frf import FRF
from jointdb.io import import_uff58, read_coherence_uff58, read_frf_uff58, read_uff58, write_uff58

from jointdb_io_helpers import assert_identical, make_frf, one_line_error, raw58, write_raw


def _coh(frf, seed=1, digits12=False):
    c = np.random.default_rng(seed).uniform(0.0, 1.0, size=frf.values.shape)
    if digits12:
        c = np.vectorize(lambda v: float("%.11e" % v))(c)
    return c


@pytest.mark.parametrize("binary", [False, True])
@pytest.mark.parametrize("even", [True, False])
def test_coherence_round_trip(tmp_path, binary, even):
    freq = np.arange(1, 41) * 2.5 if even else np.r_[1.0, 2.0, 4.0, 8.0, 16.0, 32.0]
    frf = make_frf(freq, digits12=not binary)
    coh = _coh(frf, digits12=not binary)
    path = tmp_path / "c.uff"
    write_uff58(path, frf, binary=binary, coherence=coh)
    back = read_frf_uff58(path)  # coherence records are not FRFs: the matrix is unchanged
    assert_identical(back, frf)
    got = read_coherence_uff58(path)
    assert got.shape == frf.values.shape
    assert np.array_equal(got, coh)  # binary bit-exact; ASCII exact for 12-digit values
    recs = [r for r in read_uff58(path) if r.function_type == 6]
    assert len(recs) == frf.values.shape[1] * frf.values.shape[2]
    assert all(r.function_name == "coherence" for r in recs)
    skipped = import_uff58(path).skipped
    assert len(skipped) == len(recs) and all("coherence" in s for s in skipped)


def test_coherence_as_frf_or_shared_vector(tmp_path):
    frf = make_frf(np.arange(1, 11) * 10.0, digits12=True)
    vec = np.linspace(0.5, 1.0, frf.n_freq)
    write_uff58(tmp_path / "v.uff", frf, binary=True, coherence=vec)
    got = read_coherence_uff58(tmp_path / "v.uff")
    assert np.array_equal(got, np.broadcast_to(vec[:, None, None], frf.values.shape))
    as_frf = FRF(frf.freq, got.astype(complex), frf.outputs, frf.inputs, frf.quantity)
    write_uff58(tmp_path / "f.uff", frf, binary=True, coherence=as_frf)
    assert np.array_equal(read_coherence_uff58(tmp_path / "f.uff"), got)


def test_no_coherence_records_gives_none(tmp_path):
    frf = make_frf(np.arange(1, 11) * 10.0, digits12=True)
    write_uff58(tmp_path / "n.uff", frf)
    assert read_coherence_uff58(tmp_path / "n.uff") is None


@pytest.mark.parametrize("bad, frag", [
    (lambda f: _coh(f) * 2, "0..1"),
    (lambda f: np.where(np.arange(f.n_freq)[:, None, None] == 3, np.nan, _coh(f)), "0..1"),
    (lambda f: _coh(f)[:, :1, :], "shape"),
    (lambda f: _coh(f) + 0j, "real"),
    (lambda f: FRF(f.freq[:-1], _coh(f)[:-1] + 0j, f.outputs, f.inputs, f.quantity), "lines and DOFs"),
])
def test_bad_coherence_is_refused_and_nothing_written(tmp_path, bad, frag):
    frf = make_frf(np.arange(1, 11) * 10.0, digits12=True)
    path = tmp_path / "x.uff"
    with pytest.raises(InputError) as exc:
        write_uff58(path, frf, coherence=bad(frf))
    one_line_error(exc, frag)
    assert not path.exists()


def test_negative_direction_coherence_keeps_its_sign_and_missing_pair_is_named(tmp_path):
    x = np.arange(1.0, 11.0)
    h = np.ones(10) * (1 + 1j)
    c = np.linspace(0.1, 0.9, 10)
    path = write_raw(tmp_path / "neg.uff", [
        raw58(1, -1, 2, 1, x, h),
        raw58(1, -1, 2, 1, x, c, func_type=6, num=0, den=0),
    ])
    assert np.allclose(read_frf_uff58(path).values[:, 0, 0], -h)
    assert np.allclose(read_coherence_uff58(path)[:, 0, 0], c)  # not negated

    path2 = write_raw(tmp_path / "miss.uff", [
        raw58(1, 1, 2, 1, x, h), raw58(3, 1, 2, 1, x, h),
        raw58(1, 1, 2, 1, x, c, func_type=6, num=0, den=0),
    ])
    with pytest.raises(InputError) as exc:
        read_coherence_uff58(path2)
    one_line_error(exc, "missing", "3x/2x")


def test_diagnose_reader_takes_the_written_coherence(tmp_path):
    """The `jointdb diagnose` CLI reads coherence records into Measurement.coherence."""
    from jointdb.usecases._diagnose import read_recording as _read_recording

    frf = make_frf(np.arange(1, 21) * 50.0, digits12=True)
    coh = _coh(frf)
    path = tmp_path / "rec.uff"
    write_uff58(path, frf, binary=True, coherence=coh)
    m = _read_recording(path)
    assert np.array_equal(m.coherence, coh)
