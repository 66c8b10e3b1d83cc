"""Zero-order lobes of many tips at once equal the one-tip function to the last digit."""

from pathlib import Path

import numpy as np

from jointdb.io import read_frf_uff58
from jointdb.modal import ModalModel
from jointdb.stability import MillingCut, milling_lobes_zoa
from jointdb.stability._batch import zoa_envelope_batch

TIP = read_frf_uff58(Path(__file__).parent / "data" / "demo-tip.uff")


def tips():
    """The demo tip and variants: scaled, shifted in frequency, one plane only, a two-mode model."""
    f = TIP.freq
    out = [TIP.values, TIP.values * 1.7, TIP.values[:, ::-1, ::-1].copy()]
    x_only = TIP.values.copy()
    x_only[:, 1, 1] = 0
    out.append(x_only)
    m = ModalModel.block_diagonal([ModalModel.from_modal_parameters([900.0, 2100.0], [0.03, 0.02], [2e7, 6e7], "1x"),
                                   ModalModel.from_modal_parameters([1000.0], [0.04], [3e7], "1y")])
    out.append(m.synthesize(f).values)
    diag = np.zeros((len(out), f.size, 2, 2), dtype=complex)
    for i, v in enumerate(out):
        diag[i, :, 0, 0], diag[i, :, 1, 1] = v[:, 0, 0], v[:, 1, 1]
    return diag


def test_batch_equals_one_tip_function_to_the_last_digit():
    phi = tips()
    speeds = np.linspace(3000, 30000, 300)
    for cut in (MillingCut(4, 7.96e8, 1.69e8, 0.5, True), MillingCut(2, 6e8, 2e8, 0.2, False),
                MillingCut(3, 2e9, 6e8, 1.0, True)):
        depth, fc, lobe = zoa_envelope_batch(TIP.freq, phi, cut, speeds)
        for i in range(phi.shape[0]):
            ref = milling_lobes_zoa(TIP.replace(values=phi[i]), cut, spindle_speed_rpm=speeds)
            np.testing.assert_array_equal(depth[i], ref.depth_m)
            np.testing.assert_array_equal(fc[i], ref.chatter_freq_hz)
            np.testing.assert_array_equal(lobe[i], ref.lobe)
