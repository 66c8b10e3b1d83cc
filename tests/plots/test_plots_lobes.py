"""Lobe figures a planner reads at a glance (issue 22, item 5): the envelope only, drawn as the lobes
really run between the FRF lines, the depth axis capped at the flute length or a stated multiple of
the floor, the cutting parameters and joints under the title, the band visible, the stable shading
without gaps. Each test reads the matplotlib figure object."""

from __future__ import annotations

import numpy as np
import pytest

from jointdb import FRF
from jointdb.stability import LobeResult, MillingCut, envelope, milling_lobes_zoa
from jointdb.stability._band import LobeBand

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg", force=True)
import matplotlib.pyplot as plt  # noqa: E402

from jointdb.plots import lobes_figure  # noqa: E402
from jointdb.plots._axes import percent  # noqa: E402
from jointdb.plots._envelope import FLOOR_MULTIPLE, shade_depth  # noqa: E402

CUT = MillingCut(4, 7.96e8, 0.212 * 7.96e8, 0.5, True)
SPEEDS = np.linspace(3000.0, 30000.0, 400)


def two_plane_tip(df: float) -> FRF:
    """Tool tip with two modes per plane (x and y slightly apart) on lines ``df`` Hz apart."""
    f = np.arange(500.0, 5000.0 + df / 2, df)
    w = 2 * np.pi * f
    g = np.zeros((f.size, 2, 2), complex)
    for fn, k, zeta, d in [(1150, 3e7, 0.04, 0), (2900, 2.2e7, 0.03, 0), (1180, 3.3e7, 0.04, 1),
                           (2950, 2.4e7, 0.03, 1)]:
        m = k / (2 * np.pi * fn) ** 2
        g[:, d, d] += 1 / (k - m * w**2 + 2j * zeta * np.sqrt(k * m) * w)
    return FRF(f, g, ["1x", "1y"], ["1x", "1y"])


@pytest.fixture(scope="module")
def coarse_and_truth():
    coarse = milling_lobes_zoa(two_plane_tip(20.0), CUT, spindle_speed_rpm=SPEEDS)
    truth = milling_lobes_zoa(two_plane_tip(0.05), CUT, spindle_speed_rpm=SPEEDS)
    return coarse, truth


def envelope_line(fig, label):
    return next(ln for ln in fig.axes[0].get_lines() if ln.get_label() == label)


def all_text(fig) -> str:
    ax = fig.axes[0]
    return "\n".join([ax.get_title(), *(t.get_text() for t in ax.texts),
                      *(t.get_text() for t in ax.get_legend().get_texts())])


def test_the_drawn_envelope_follows_the_lobes_between_the_frf_lines(coarse_and_truth):
    """On 20 Hz lines the lobe k = 0 of a mode spans a few lines over thousands of rpm. The drawn line
    must follow the envelope of the same tip on 0.05 Hz lines (within 1 %; measured 0.24 %), where
    the computed speeds joined by straight segments miss it by more than 5 % (measured 10 %)."""
    coarse, truth = coarse_and_truth
    fig = lobes_figure(coarse)
    line = envelope_line(fig, "milling-zoa")
    x, y = np.asarray(line.get_xdata(), float), np.asarray(line.get_ydata(), float) / 1e3   # mm -> m
    exact, _, _ = envelope(truth.lobes, x)
    ok = np.isfinite(exact) & np.isfinite(y)
    assert ok.mean() > 0.99
    assert np.max(np.abs(y[ok] / exact[ok] - 1)) < 0.01
    straight = np.interp(x, coarse.spindle_speed_rpm, coarse.depth_m)
    assert np.max(np.abs(straight[ok] / exact[ok] - 1)) > 0.05
    # no segment longer than 1/1000 of the speed range: nothing is drawn as a straight segment
    assert np.max(np.diff(x)) <= (x[-1] - x[0]) / 1000
    plt.close(fig)


def test_only_the_envelope_is_drawn_unless_lobes_are_asked_for(coarse_and_truth):
    coarse, _ = coarse_and_truth
    fig = lobes_figure(coarse)
    drawn = [ln for ln in fig.axes[0].get_lines() if len(ln.get_xdata())]
    assert [ln.get_label() for ln in drawn] == ["milling-zoa"]
    plt.close(fig)
    fig = lobes_figure(coarse, show_lobes=True)
    assert len([ln for ln in fig.axes[0].get_lines() if len(ln.get_xdata())]) == 1 + len(coarse.lobes)
    plt.close(fig)


def pockets(depth_floor: float, depth_peak: float) -> LobeResult:
    """A result with a floor and one pocket, on speeds 5000-6000 rpm (depths in m)."""
    s = np.linspace(5000, 6000, 101)
    d = depth_floor + (depth_peak - depth_floor) * np.exp(-(((s - 5500) / 60) ** 2))
    return LobeResult("milling-sd", s, d, np.full(s.size, 3000.0), np.full(s.size, 10), np.full(s.size, "hopf"),
                      info={"n_teeth": 2, "kt": 6e8, "kr": 2e8, "radial_immersion": 0.1, "down_milling": True})


def test_depth_axis_stops_at_the_flute_length():
    """Pockets to 54 mm for a tool with 30 mm of flutes: the axis ends just above 30 mm, the flute
    length is drawn and named, the pocket above it is marked with its depth."""
    fig = lobes_figure(pockets(0.011, 0.0547), flute_length_m=0.030)
    ax = fig.axes[0]
    assert ax.get_ylim()[1] == pytest.approx(1.08 * 30.0)
    flute = envelope_line(fig, "flute length 30 mm")
    assert np.allclose(flute.get_ydata(), 30.0)
    text = all_text(fig)
    assert "depth axis capped at the flute length" in text
    assert "highest pocket 54.7 mm at 5500 rpm" in text
    plt.close(fig)


def test_depth_axis_without_flute_length_stops_at_a_stated_multiple_of_the_floor():
    fig = lobes_figure(pockets(0.010, 0.080))       # a pocket 8x the floor
    assert fig.axes[0].get_ylim()[1] == pytest.approx(FLOOR_MULTIPLE * 10.0)
    assert f"capped at {FLOOR_MULTIPLE:g} × the floor" in all_text(fig)
    plt.close(fig)
    fig = lobes_figure(pockets(0.010, 0.020))       # 2x: nothing to cap
    assert fig.axes[0].get_ylim()[1] == pytest.approx(1.1 * 20.0)
    assert "capped" not in all_text(fig)
    plt.close(fig)


def test_title_names_the_cutting_parameters_and_the_joints(coarse_and_truth):
    coarse, _ = coarse_and_truth
    joints = "tool-holder: th-er32-carbide-120nm v1 (nearest); holder-spindle: hs-hsk-a63-18kn v1 (nearest)"
    fig = lobes_figure(coarse, title="Stability lobes: demo stack", joints=joints)
    text = all_text(fig).replace("\n", " ")
    for part in ("Stability lobes: demo stack", "milling ZOA", "4 teeth", "K_t 796 N/mm²", "K_r 168.8 N/mm²",
                 "a_e/D 0.5", "down-milling", "th-er32-carbide-120nm v1", "hs-hsk-a63-18kn v1"):
        assert part in text, part
    plt.close(fig)


def sd_with_gaps() -> LobeResult:
    """SD-like rows with fold points and a speed without a limit in the middle (the 5-6.5 krpm case)."""
    s = np.linspace(5000, 7000, 41)
    d = 0.03 + 0.01 * np.sin(s / 150)
    kind = np.full(s.size, "hopf")
    kind[[8, 9, 20, 30]] = "fold"
    d[25] = np.nan
    kind[25] = ""
    return LobeResult("milling-sd", s, d, np.full(s.size, 2900.0), np.full(s.size, 12), kind,
                      info={"n_teeth": 2, "kt": 6e8, "kr": 2e8, "radial_immersion": 0.1, "down_milling": True})


def test_stable_shading_has_no_gaps_where_the_line_breaks():
    res = sd_with_gaps()
    fig = lobes_figure(res)
    ax = fig.axes[0]
    line = envelope_line(fig, "milling-sd")
    assert np.isnan(line.get_ydata()).sum() == 5          # folds and the missing limit: not drawn
    shade = next(c for c in ax.collections if c.get_label() == "stable")
    paths = shade.get_paths()
    assert len(paths) == 1                                   # one region, not one per run of the line
    v = paths[0].vertices
    assert np.all(np.isfinite(v))
    top = v[v[:, 1] > 0]
    assert top[:, 0].min() == pytest.approx(5000) and top[:, 0].max() == pytest.approx(7000)
    # over a gap the shade reaches the lower of the two neighbouring limits (conservative)
    d_mm = res.depth_m * 1e3
    at = lambda i: top[np.isclose(top[:, 0], res.spindle_speed_rpm[i]), 1].max()  # noqa: E731
    assert at(8) == pytest.approx(min(d_mm[7], d_mm[10]))
    assert at(25) == pytest.approx(min(d_mm[24], d_mm[26]))
    plt.close(fig)


def test_shade_depth_fills_gaps_and_unlimited_speeds():
    d = np.array([1.0, np.nan, 3.0, np.inf, 2.0, np.nan, np.nan])
    assert shade_depth(d, top=9.0).tolist() == [1.0, 1.0, 3.0, 9.0, 2.0, 2.0, 2.0]


def lobe_band(res: LobeResult, relative: float) -> LobeBand:
    d = np.where(np.isfinite(res.depth_m), res.depth_m, np.nan)
    crit = res.min_depth_m
    return LobeBand(res.spindle_speed_rpm, np.stack([d * (1 - relative), d, d * (1 + relative)]),
                    np.array([crit * (1 - relative), crit, crit * (1 + relative)]), 100)


@pytest.mark.parametrize("relative, annotated", [(0.0005, True), (0.05, False)])
def test_band_is_shaded_and_annotated_when_narrower_than_the_line(coarse_and_truth, relative, annotated):
    coarse, _ = coarse_and_truth
    fig = lobes_figure(coarse, band=lobe_band(coarse, relative))
    ax = fig.axes[0]
    band = next(c for c in ax.collections if c.get_label().startswith("5–95 % band"))
    assert f"±{percent(relative)})" in band.get_label() and percent(relative) in ("0.05%", "5.0%")
    notes = [t.get_text() for t in ax.texts if "narrower than the line" in t.get_text()]
    assert bool(notes) is annotated
    plt.close(fig)
