"""`jointdb lobes --method sd` solves the speeds in chunks (for the progress bar): same result as one call."""

import numpy as np

from jointdb.usecases._lobes import sd_lobes_in_chunks as _sd_lobes_with_progress
from jointdb.modal import ModalModel
from jointdb.stability import MillingCut, milling_lobes_sd


def test_chunked_sd_lobes_equal_one_call():
    mx = ModalModel([452.77], [0.1237], np.array([9.203e-5 - 1.862e-4j]).reshape(1, 1, 1), ("1x",), ("1x",))
    my = ModalModel([516.17], [0.0243], np.array([-2.393e-6 - 1.722e-4j]).reshape(1, 1, 1), ("1y",), ("1y",))
    model = ModalModel.block_diagonal([mx, my])
    cut = MillingCut(2, 6e8, 2e8, 0.1, True)
    speeds = np.linspace(5000, 25000, 7)
    whole = milling_lobes_sd(model, cut, speeds, n_intervals=12)
    parts = _sd_lobes_with_progress(model, cut, speeds, 12, n_chunks=3)
    for attr in ("spindle_speed_rpm", "depth_m", "chatter_freq_hz", "lobe", "kind"):
        assert np.array_equal(getattr(parts, attr), getattr(whole, attr)), attr
    assert parts.method == whole.method and parts.info == whole.info


def test_turning_ignores_rotations_and_refuses_a_rotation_only_frf(tmp_path):
    """A rotation (rad/(N·m)) must not be summed into the oriented displacement FRF (m/N)."""
    import pytest
    from typer.testing import CliRunner

    from jointdb.cli import app
    from jointdb.errors import InputError
    from jointdb.frf import FRF
    from jointdb.io import write_frf_hdf5
    from jointdb.stability import turning_lobes

    f = np.linspace(100.0, 3000.0, 300)
    w, wn, z = 2 * np.pi * f, 2 * np.pi * 1500.0, 0.02
    hx = 1.0 / (1e7 * (1 - (w / wn) ** 2 + 2j * z * w / wn))
    values = np.zeros((f.size, 2, 2), complex)
    values[:, 0, 0], values[:, 1, 1] = hx, hx * 1e3  # 1ry/1ry: large, other units
    write_frf_hdf5(tmp_path / "tip.h5", FRF(f, values, ["1x", "1ry"], ["1x", "1ry"]))
    write_frf_hdf5(tmp_path / "rot.h5", FRF(f, values[:, 1:, 1:], ["1ry"], ["1ry"]))
    r = CliRunner().invoke(app, ["lobes", str(tmp_path / "tip.h5"), "--op", "turning", "--kf", "1e9",
                                 "--n-speeds", "5", "--json"])
    assert r.exit_code == 0, r.output
    import json

    got = json.loads(r.stdout)["info"]["absolute_limit_m"]
    want = turning_lobes(FRF(f, values[:, :1, :1], ["1x"], ["1x"]), 1e9).info["absolute_limit_m"]
    assert got == pytest.approx(want, rel=1e-12)
    r = CliRunner().invoke(app, ["lobes", str(tmp_path / "rot.h5"), "--op", "turning", "--kf", "1e9"])
    assert isinstance(r.exception, InputError) and "translational" in str(r.exception)
