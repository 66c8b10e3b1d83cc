"""`jointdb lobes --method sd` solves the speeds in chunks (for the progress bar): same result as one call."""

import numpy as np

from jointdb.cli._stability import _sd_lobes_with_progress
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
