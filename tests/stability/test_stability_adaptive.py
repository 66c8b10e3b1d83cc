"""Adaptive spindle speeds (refine_lobes): the plain computation's values at every shared speed,
more speeds where the envelope turns; folds are not drawn as depths."""

from __future__ import annotations

import numpy as np
import pytest

from jointdb.frf import FRF
from jointdb.modal import ModalModel
from jointdb.stability import (
    LobeResult,
    MillingCut,
    milling_lobes_sd,
    milling_lobes_zoa,
    plottable_depth,
    refine_lobes,
    turning_lobes,
)


def _tip():
    f = np.linspace(200.0, 3000.0, 1400)
    w = 2 * np.pi * f
    values = np.zeros((f.size, 2, 2), complex)
    for i, (fn, z, k) in enumerate(((922.0, 0.011, 1.3e6), (1110.0, 0.02, 2.0e6))):
        wn = 2 * np.pi * fn
        values[:, i, i] = 1.0 / (k * (1 - (w / wn) ** 2 + 2j * z * w / wn))
    return FRF(f, values, ["1x", "1y"], ["1x", "1y"])


COLS = ("spindle_speed_rpm", "depth_m", "chatter_freq_hz", "lobe", "kind")


def _rows_at(res: LobeResult, speeds) -> dict:
    idx = np.searchsorted(res.spindle_speed_rpm, speeds)
    assert np.array_equal(res.spindle_speed_rpm[idx], speeds)
    return {c: getattr(res, c)[idx] for c in COLS}


@pytest.mark.parametrize("kind", ["zoa", "turning"])
def test_refined_equals_plain_at_shared_speeds(kind):
    tip, cut = _tip(), MillingCut(2, 6e8, 2e8, 0.5, True)
    if kind == "zoa":
        def compute(s):
            return milling_lobes_zoa(tip, cut, spindle_speed_rpm=s)
    else:
        def compute(s):
            return turning_lobes(tip, 1e9, spindle_speed_rpm=s)
    base = np.linspace(3000, 30000, 120)
    plain = compute(base)
    refined = refine_lobes(compute, base, rounds=3)
    added = refined.info["refined_speeds"]
    assert added > 20 and refined.spindle_speed_rpm.size == base.size + added
    assert np.all(np.diff(refined.spindle_speed_rpm) > 0)
    at_base = _rows_at(refined, base)
    for c in COLS:  # exactly the plain computation's numbers (each speed is computed on its own)
        assert np.array_equal(at_base[c], getattr(plain, c), equal_nan=c in ("depth_m", "chatter_freq_hz")), c
    # ... and every added speed equals a plain computation on the refined grid
    again = compute(refined.spindle_speed_rpm)
    for c in COLS:
        assert np.array_equal(getattr(again, c), getattr(refined, c), equal_nan=c in ("depth_m", "chatter_freq_hz"))
    # the refinement finds the floor at least as low and the best pocket at least as high
    assert np.nanmin(plottable_depth(refined)) <= np.nanmin(plottable_depth(plain))
    assert np.nanmax(plottable_depth(refined)) >= np.nanmax(plottable_depth(plain))


def test_refined_sd_equals_plain_sd_at_shared_speeds():
    mx = ModalModel([452.77], [0.1237], np.array([9.203e-5 - 1.862e-4j]).reshape(1, 1, 1), ("1x",), ("1x",))
    my = ModalModel([516.17], [0.0243], np.array([-2.393e-6 - 1.722e-4j]).reshape(1, 1, 1), ("1y",), ("1y",))
    model = ModalModel.block_diagonal([mx, my])
    cut = MillingCut(2, 6e8, 2e8, 0.1, True)
    base = np.linspace(5000, 25000, 9)

    def compute(s):
        return milling_lobes_sd(model, cut, s, n_intervals=12)

    plain = compute(base)
    refined = refine_lobes(compute, base, rounds=1)
    assert refined.info["refined_speeds"] > 0
    at_base = _rows_at(refined, base)
    for c in COLS:
        assert np.array_equal(at_base[c], getattr(plain, c), equal_nan=c in ("depth_m", "chatter_freq_hz")), c
    assert refined.info["evaluations"] == plain.info["evaluations"] + compute(
        np.setdiff1d(refined.spindle_speed_rpm, base)).info["evaluations"]


def test_refine_rounds_zero_is_the_plain_computation():
    tip, cut = _tip(), MillingCut(2, 6e8, 2e8, 0.5, True)
    base = np.linspace(3000, 30000, 50)
    r = refine_lobes(lambda s: milling_lobes_zoa(tip, cut, spindle_speed_rpm=s), base, rounds=0)
    assert r.info["refined_speeds"] == 0 and np.array_equal(r.spindle_speed_rpm, base)


def test_folds_are_not_plottable_depths_nor_set_the_plot_scale():
    """SD on the README's demo tip gave a fold (real multiplier +1) of 423 mm at 5000 rpm beside
    real limits of 35-54 mm; the plot must not draw it. Here the same shape of result."""
    from jointdb.plots import lobes_figure

    speeds = np.array([5000.0, 5066.9, 5133.8, 5200.7])
    depth = np.array([0.423, 0.0347, 0.0410, 0.0539])
    res = LobeResult("milling-sd", speeds, depth, [2333.3, 3049.0, 3069.0, 3111.5], [14, 18, 17, 17],
                     ["fold", "hopf", "hopf", "hopf"])
    d = plottable_depth(res)
    assert np.isnan(d[0]) and np.array_equal(d[1:], depth[1:])
    fig = lobes_figure(res)
    ax = fig.axes[0]
    assert ax.get_ylim()[1] == pytest.approx(1.1 * 53.9)  # mm: the real limits set the scale, not the fold
    assert any("1 fold point" in t.get_text() for t in ax.get_legend().get_texts())
    import matplotlib.pyplot as plt

    plt.close(fig)


def test_a_real_sd_fold_is_left_out_of_the_plot():
    """The case that produced the 423 mm spike: the README's SD example (2 teeth, K_t 6e8, K_r 2e8 N/m²,
    a/D 0.1, down-milling) on the demo's tool tip, fitted with 3 modes per direction (x = y)."""
    from jointdb.plots import lobes_figure

    res = [1.6970204276e-05 - 1.9466645361e-04j, -3.6518113400e-05 - 5.9013790542e-04j,
           8.3752179325e-05 - 6.6576823504e-04j]
    freq, zeta = [1391.0850032, 2347.85903458, 3085.95476988], [0.05186123, 0.02544383, 0.02673512]
    mx = ModalModel(freq, zeta, np.array(res).reshape(3, 1, 1), ("1x",), ("1x",))
    my = ModalModel(freq, zeta, np.array(res).reshape(3, 1, 1), ("1y",), ("1y",))
    cut = MillingCut(2, 6e8, 2e8, 0.1, True)
    r = milling_lobes_sd(ModalModel.block_diagonal([mx, my]), cut, [5000.0, 5066.889632107023, 5133.779264214047])
    assert list(r.kind) == ["fold", "hopf", "hopf"]
    assert r.depth_m[0] > 0.3 and r.depth_m[1:].max() < 0.06  # the spike, beside real limits of 35-41 mm
    fig = lobes_figure(r)
    top = fig.axes[0].get_ylim()[1]
    assert top == pytest.approx(1.1 * 1e3 * r.depth_m[1:].max())  # mm: the fold does not set the scale
    line = next(ln for ln in fig.axes[0].get_lines() if ln.get_label() == "milling-sd")
    assert np.isnan(line.get_ydata()[0])  # not drawn as a depth
    import matplotlib.pyplot as plt

    plt.close(fig)
