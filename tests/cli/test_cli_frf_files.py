"""One suffix table for FRF files (app.read_frf_file / write_frf_file), used by frf, lobes, modal-fit, predict."""

import numpy as np
import pytest

from jointdb.usecases import read_frf_file, write_frf_file
from jointdb.errors import InputError, NotFoundError
from jointdb.frf import FRF


def _frf():
    f = np.arange(1, 11) * 10.0
    v = (1.0 / (1 + 1j * f / 50.0)).reshape(-1, 1, 1) * 1e-6
    return FRF(f, v, ["1x"], ["1x"], "receptance")


@pytest.mark.parametrize("name", ["a.uff", "a.unv", "a.h5", "a.hdf", "a.csv"])
def test_every_suffix_round_trips(tmp_path, name):
    frf = _frf()
    write_frf_file(tmp_path / name, frf, binary=True)
    assert read_frf_file(tmp_path / name).allclose(frf, rtol=1e-12)


def test_bad_suffix_missing_file_and_missing_directory(tmp_path):
    with pytest.raises(InputError, match="unknown FRF file type '.txt'"):
        read_frf_file(tmp_path / "a.txt")
    with pytest.raises(NotFoundError, match="does not exist"):
        read_frf_file(tmp_path / "a.uff")
    with pytest.raises(InputError, match="--out .*directory .* does not exist"):
        write_frf_file(tmp_path / "nodir" / "a.uff", _frf())
    assert list(tmp_path.iterdir()) == []
