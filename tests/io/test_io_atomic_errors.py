"""Writers turn a refused write (read-only directory, disk full) into one InputError line, leaving nothing."""

import errno

import numpy as np
import pytest

from jointdb.errors import InputError
from jointdb.frf import FRF
from jointdb.io import _atomic, write_frf_csv, write_uff58


def _frf():
    return FRF(np.arange(1.0, 5.0), np.ones((4, 1, 1)) * (1 + 1j), ["1x"], ["1x"])


def test_read_only_directory_is_one_line_input_error(tmp_path, monkeypatch):
    def refuse(*a, **k):
        raise PermissionError(errno.EACCES, "Permission denied")

    monkeypatch.setattr(_atomic.tempfile, "mkstemp", refuse)
    with pytest.raises(InputError, match=r"cannot write .*a\.uff: Permission denied"):
        write_uff58(tmp_path / "a.uff", _frf())
    assert list(tmp_path.iterdir()) == []


def test_disk_full_during_the_write_leaves_nothing(tmp_path, monkeypatch):
    real_open = open

    def full_open(path, mode="r", *a, **k):
        fh = real_open(path, mode, *a, **k)
        if "w" in mode:
            def write(*_a, **_k):
                raise OSError(errno.ENOSPC, "No space left on device")
            fh.write = write
        return fh

    monkeypatch.setattr("builtins.open", full_open)
    with pytest.raises(InputError, match="No space left"):
        write_frf_csv(tmp_path / "a.csv", _frf())
    monkeypatch.undo()
    assert list(tmp_path.iterdir()) == []
