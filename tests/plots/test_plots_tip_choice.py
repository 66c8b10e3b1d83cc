"""Tool-tip, joint-choice and assembly-fit figures for a planner (issue 22, item 5): one unit per
figure, the rigid comparison in a panel of its own with the reason, the joint choice on one scale
with values and the request, the phase without wrap artefacts. Each test reads the figure object."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from jointdb import FRF
from jointdb.stack._band import TipBand

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg", force=True)
import matplotlib.pyplot as plt  # noqa: E402

from jointdb.plots import (  # noqa: E402
    comparison_figure,
    joint_choice_figure,
    phase_unwrapped,
    tip_comparison_figure,
)

F = np.linspace(50.0, 5000.0, 991)


def modes(*spec) -> np.ndarray:
    """Receptance [m/N] of a sum of single-DOF modes ``(f_n [Hz], k [N/m], ζ)`` on :data:`F`."""
    w = 2 * np.pi * F
    h = np.zeros(F.size, complex)
    for fn, k, zeta in spec:
        m = k / (2 * np.pi * fn) ** 2
        h += 1 / (k - m * w**2 + 2j * zeta * np.sqrt(k * m) * w)
    return h


def tip_frf(h_x, h_y=None) -> FRF:
    v = np.zeros((F.size, 2, 2), complex)
    v[:, 0, 0], v[:, 1, 1] = h_x, h_x if h_y is None else h_y
    return FRF(F, v, ["1x", "1y"], ["1x", "1y"])


@pytest.fixture(scope="module")
def prediction():
    # with joints: compliant and well damped; rigid: stiffer, only material damping (peak ~ 6x higher)
    tip = tip_frf(modes((1200, 8e7, 0.05), (2900, 2.2e7, 0.03)))
    rigid = tip_frf(modes((1400, 1e8, 0.01), (3750, 4e7, 0.003)))
    return SimpleNamespace(tip=tip, rigid=rigid)


def tip_band(pred, relative: float) -> TipBand:
    mag = np.abs(pred.tip.entry("1x", "1x"))
    peak = mag.max()
    return TipBand(F, {"x": np.stack([mag * (1 - relative), mag, mag * (1 + relative)])},
                   {"x": np.array([peak * (1 - relative), peak, peak * (1 + relative)])},
                   {"x": np.array([2900.0, 2900.0, 2900.0])}, 200, ("tool-holder",), {})


def labelled(ax) -> list[str]:
    return [ln.get_label() for ln in ax.get_lines() if len(ln.get_xdata())]


def test_tip_figure_is_in_micrometres_per_newton_throughout(prediction):
    fig = tip_comparison_figure(prediction, label="with catalogued joints")
    ylabels = [ax.get_ylabel() for ax in fig.axes]
    assert len(ylabels) == 3 and all("[µm/N]" in y for y in ylabels), ylabels
    peak_um = np.abs(prediction.tip.entry("1x", "1x")).max() * 1e6
    line = next(ln for ln in fig.axes[0].get_lines() if ln.get_label() == "with catalogued joints")
    assert np.max(line.get_ydata()) == pytest.approx(peak_um)    # values in µm/N, not m/N
    plt.close(fig)


def test_rigid_joints_only_in_their_own_panel_with_the_reason(prediction):
    fig = tip_comparison_figure(prediction, label="with catalogued joints")
    ax_m, ax_c, ax_r = fig.axes
    assert "rigid joints" not in labelled(ax_m) and len(ax_c.get_lines()) == 2 + 1   # Re, Im, the zero line
    assert labelled(ax_r) == ["with catalogued joints", "rigid joints"]
    rigid_peak = np.abs(prediction.rigid.entry("1x", "1x")).max() * 1e6
    tip_peak = np.abs(prediction.tip.entry("1x", "1x")).max() * 1e6
    assert ax_m.get_ylim()[1] < 1.2 * tip_peak < rigid_peak          # the prediction keeps its scale
    reason = ax_r.get_title().replace("\n", " ")
    assert f"peak {rigid_peak / tip_peak:.1f}× higher" in reason
    assert "at 3750 Hz instead of 2900 Hz" in reason and "no joint damping" in reason
    plt.close(fig)


def test_tip_figure_draws_y_when_it_differs(prediction):
    pred = SimpleNamespace(tip=tip_frf(modes((2900, 2.2e7, 0.03)), modes((2850, 2e7, 0.03))),
                           rigid=prediction.rigid)
    fig = tip_comparison_figure(pred)
    assert len(fig.axes) == 6 and "|H_yy| [µm/N]" in [ax.get_ylabel() for ax in fig.axes]
    plt.close(fig)


@pytest.mark.parametrize("relative, annotated", [(0.0007, True), (0.044, False)])
def test_tip_band_is_shaded_and_annotated_when_thinner_than_the_line(prediction, relative, annotated):
    fig = tip_comparison_figure(prediction, band=tip_band(prediction, relative))
    ax = fig.axes[0]
    band = next(c for c in ax.collections if c.get_label().startswith("5–95 % band"))
    assert "µm/N" in band.get_label()
    assert any("narrower than the line" in t.get_text() for t in ax.texts) is annotated
    plt.close(fig)


def resolution(interface, candidates, used, method="nearest", per_condition=None, outside=()):
    """A stand-in for :class:`jointdb.usecases.JointResolution` with the fields the figure reads."""
    name, version = (used[0][0], used[0][1]) if len(used) == 1 else (None, None)
    return SimpleNamespace(interface=interface, kind="query", name=name, version=version,
                           candidates=tuple(candidates), neighbours=tuple(used), method=method,
                           per_condition=per_condition or {}, extrapolating=bool(outside),
                           outside_range=tuple(outside))


def test_joint_choice_one_scale_values_on_bars_request_shown():
    res = {
        "tool-holder": resolution("tool-holder", [("th-a", 1, 0.166), ("th-b", 1, 0.203), ("th-c", 2, 0.687)],
                                  [("th-a", 1, 1.0, 0.166)], per_condition={"torque_nm": 0.166, "materials": 0.0}),
        "holder-spindle": resolution("holder-spindle", [("hs-a", 1, 0.096), ("hs-b", 1, 0.166)],
                                     [("hs-a", 1, 0.634, 0.096), ("hs-b", 1, 0.366, 0.166)],
                                     method="simplex interpolation", outside=("preload_n",)),
        "spindle": SimpleNamespace(interface="spindle", kind="rigid", candidates=()),
    }
    conditions = {"tool-holder": {"materials": ["tungsten-carbide", "steel"], "torque_nm": 100.0,
                                  "geometry": {"shank_diameter_m": 0.012}},
                  "holder-spindle": {"preload_n": 20000.0}}
    fig = joint_choice_figure(res, conditions=conditions)
    ax_th, ax_hs = fig.axes
    assert ax_th.get_xlim() == ax_hs.get_xlim()                     # one x-scale
    values = [t.get_text() for t in ax_th.texts]
    assert sorted(values) == ["0.166", "0.203", "0.687"]
    th_title = ax_th.get_title().replace("\n", " ")
    assert "torque 100 N·m" in th_title and "shank diameter 12 mm" in th_title
    assert "tungsten-carbide/steel" in th_title and "torque 0.166" in th_title
    hs_title = ax_hs.get_title().replace("\n", " ")
    assert "simplex interpolation" in hs_title and "OUTSIDE the catalogue in preload_n" in hs_title
    assert "preload 20 kN" in hs_title
    names = [t.get_text() for t in ax_hs.get_yticklabels()]
    assert "hs-a@1  (w=0.63)" in names and "hs-b@1  (w=0.37)" in names
    colours = {tuple(p.get_facecolor()) for p in ax_hs.patches}
    assert len(colours) == 1                                         # both interpolated joints in colour
    assert len({tuple(p.get_facecolor()) for p in ax_th.patches}) == 2
    plt.close(fig)


def test_phase_unwrapped_has_no_wrap_jumps_and_shares_the_branch():
    """A cross receptance whose phase runs 0 → −360° (wrapped: a jump from −180° to +180°), measured with
    noise, and the fitted curve: both drawn continuous and on the same branch."""
    rng = np.random.default_rng(22)
    fitted = modes((800, 2e7, 0.02)) - modes((2600, 3e7, 0.03))
    measured = fitted * (1 + 0.0075 * (rng.standard_normal(F.size) + 1j * rng.standard_normal(F.size)))
    wrapped = np.degrees(np.angle(measured))
    assert np.max(np.abs(np.diff(wrapped))) > 300                    # the artefact
    p_meas = phase_unwrapped(F, measured)
    p_fit = phase_unwrapped(F, fitted - 0j, (F, p_meas))
    assert np.max(np.abs(np.diff(p_meas))) < 60
    assert p_meas[0] == pytest.approx(0, abs=5) and p_meas[-1] == pytest.approx(-360, abs=10)
    assert np.median(np.abs(p_fit - p_meas)) < 2
    shifted = phase_unwrapped(F, fitted * np.exp(2j * np.pi), (F, p_meas))   # same curve, another start
    assert np.allclose(shifted, p_fit)


def test_assembly_fit_phase_panels_are_continuous():
    rng = np.random.default_rng(5)
    fitted = FRF(F, (modes((800, 2e7, 0.02)) - modes((2600, 3e7, 0.03)))[:, None, None], ["1x"], ["2x"])
    noisy = fitted.values * (1 + 0.0075 * rng.standard_normal(fitted.values.shape))
    measured = FRF(F, noisy, ["1x"], ["2x"])
    fig = comparison_figure([("measured", measured), ("reconstructed", fitted)])
    ax_mag, ax_phase = fig.axes
    assert ax_mag.get_ylabel() == "|H| [m/N]"
    lines = ax_phase.get_lines()
    assert len(lines) == 2
    for ln in lines:
        y = np.asarray(ln.get_ydata(), float)
        assert np.all(np.isfinite(y)) and np.max(np.abs(np.diff(y))) < 60
    assert np.median(np.abs(lines[0].get_ydata() - lines[1].get_ydata())) < 2
    plt.close(fig)
