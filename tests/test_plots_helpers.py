"""Plot details of issue 14: phase lines break at wraps, k(ω) scaled by percentiles (spikes clipped to
the edge), the tip-vs-rigid legend names the joint versions and weights. (The checks on the main job's
outputs — tip plot, refined lobes, ``joints show`` prints k, c — are in test_journey.py, on its one run.)"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from jointdb.plots import phase_deg, robust_limits


def test_phase_breaks_at_wraps():
    f = np.linspace(0, 100, 1001)
    h = np.exp(-1j * 2 * np.pi * f / 25)  # a delay: the phase wraps four times
    ff, p = phase_deg(f, h)
    assert np.isnan(p).sum() == 4 and ff.size == f.size + 4
    finite = ~np.isnan(p)
    runs = np.split(p, np.flatnonzero(~finite))
    assert all(np.all(np.abs(np.diff(r[~np.isnan(r)])) < 10) for r in runs)  # no vertical bar inside a run
    assert np.array_equal(p[finite], np.degrees(np.angle(h)))  # the values themselves are unchanged


def test_robust_limits_ignore_single_spikes():
    y = np.full(500, 3.0e7) + np.linspace(-1e6, 1e6, 500)
    y[250] = 5e9  # one noisy line, 170x the level
    lo, hi = robust_limits(y)
    assert hi < 3.3e7 and lo > 2.7e7


def test_kc_plot_keeps_the_scale_of_the_bulk(tmp_path):
    from jointdb.frf import FRF
    from jointdb.plots import save_kc_plot

    f = np.linspace(50, 5000, 200)
    z = 3e7 + 1j * 2 * np.pi * f * 200.0
    z[100] = 1e10  # a spike in k(ω)
    frf = FRF(f, (1 / z)[:, None, None], ["3x"], ["3x"])
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    captured = {}
    real_close = plt.close

    def keep(fig=None):
        captured["fig"] = fig

    plt.close = keep
    try:
        save_kc_plot(tmp_path / "kc.png", frf)
    finally:
        plt.close = real_close
    ax_k = captured["fig"].axes[0]
    assert ax_k.get_ylim()[1] < 4e7  # the spike is drawn at the edge, not setting the scale
    assert any("off scale" in t.get_text() for t in ax_k.get_legend().get_texts())
    real_close(captured["fig"])


def test_tip_legend_names_versions_and_weights():
    from jointdb.plots import joints_legend

    res = {
        "tool-holder": SimpleNamespace(kind="interpolated", name="th-a", version=1,
                                       description="INTERPOLATED tool-holder joint from th-a v1 (w=0.550), "
                                                   "th-b v2 (w=0.450)"),
        "holder-spindle": SimpleNamespace(kind="query", name="hs-1", version=3, description=""),
        "spindle": SimpleNamespace(kind="rigid", name=None, version=None, description="rigid"),
    }
    text = joints_legend(res)
    assert text == "tool-holder: interpolated th-a v1 (w=0.550), th-b v2 (w=0.450); holder-spindle: hs-1 v3"
