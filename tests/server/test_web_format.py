"""What the pages show of a joint version (jointdb.server.web_format): engineering units, k and c
with their standard errors from a stored output-error record, a refit of a bare FRF against the
spring–damper it was made from, the verdict, the plot data."""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("fastapi", reason="the server extra is not installed")

from jointdb.server import web_format as wf  # noqa: E402


def test_numbers_as_people_write_them():
    assert [wf.num(x) for x in (8000.0, 0.012, 18.0, 1497.3, 401234.0)] == ["8000", "0.012", "18", "1497", "401200"]
    assert wf.num(1.45e8) == "1.45 × 10⁸" and wf.num(3.2e-7) == "3.2 × 10⁻⁷"
    assert wf.num(None) == "–" and wf.num(float("nan")) == "–"


def test_conditions_in_engineering_units_and_words():
    rows = dict(wf.condition_rows({"materials": ["steel", "steel"], "preload_n": 18000.0, "torque_nm": None,
                                   "geometry": {"taper_diameter_m": 0.063}, "extra": {"taper": "HSK-A63"}},
                                  "holder-spindle"))
    assert rows == {"materials": "steel + steel", "drawbar force": "18 kN", "taper diameter": "63 mm",
                    "taper": "HSK-A63"}
    rows = dict(wf.condition_rows({"materials": ["tungsten-carbide", "steel"], "torque_nm": 80.0, "preload_n": 8000.0,
                                   "geometry": {"shank_diameter_m": 0.012}}, "tool-holder"))
    assert rows["clamping torque"] == "80 N·m" and rows["preload"] == "8 kN" and rows["shank diameter"] == "12 mm"
    assert wf.humanise_text("outside the range for: preload_n, geometry.shank_diameter_m") == \
        "outside the range for: drawbar force / preload, shank diameter"


def _record(k, c, rel):
    """An output-error record of a planar spring–damper (θ = ln k, ln c per DOF) with relative σ ``rel``."""
    names = ["k 3x", "c 3x", "k 3ry", "c 3ry"]
    theta = [math.log(k[0]), math.log(c[0]), math.log(k[1]), math.log(c[1])]
    cov = np.diag(np.square(rel)).tolist()
    return {"provenance": {"parameters": {"uncertainty": {
        "format": "jointdb-joint-uncertainty/1", "model": "spring-damper", "names": names, "theta": theta,
        "covariance": cov, "theta_is_log": True, "dofs": ["3x", "3ry"], "order": 0}}},
        "quality": {"model_adequacy.misfit_to_noise": 1.1, "model_adequacy.misfit_to_noise_limit": 2.0}}


def test_k_c_with_sigma_and_units_from_the_stored_fit():
    v = _record((2e7, 3e5), (300.0, 2.5), [0.01, 0.02, 0.05, 0.2])
    rows, source = wf.kc_rows(v)
    assert "output-error" in source
    assert rows[0] == {"dof": "3x", "k": "2 × 10⁷ N/m", "k_sigma": "± 200000 N/m", "k_rel": "1 %",
                       "c": "300 N·s/m", "c_sigma": "± 6 N·s/m", "c_rel": "2 %"}
    assert rows[1]["k"] == "300000 N·m/rad" and rows[1]["c_sigma"] == "± 0.5 N·m·s/rad"
    ok, lines = wf.verdict(v)  # c 3ry at 20 %: poorly determined
    assert not ok and "c 3ry is poorly determined" in lines[0]
    ok, lines = wf.verdict(_record((2e7, 3e5), (300.0, 2.5), [0.01, 0.02, 0.05, 0.05]))
    assert ok and lines == ["OK: largest standard error 5.0% (k 3ry); constant (k, c) misfit 1.10× the measurement "
                            "noise (limit 2×)"]


def test_a_bare_joint_frf_is_refitted_without_inventing_sigma():
    from jointdb.frf import FRF, Quantity, dofs

    freq = np.linspace(50.0, 4000.0, 200)
    w = 2 * np.pi * freq
    h = np.zeros((freq.size, 2, 2), complex)
    h[:, 0, 0] = 1 / (4e6 + 1j * w * 120.0)
    h[:, 1, 1] = 1 / (5e4 + 1j * w * 0.8)
    frf = FRF(freq, h, dofs(["2x", "2ry"]), dofs(["2x", "2ry"]), Quantity.RECEPTANCE)
    rows, source = wf.kc_rows({"provenance": {"parameters": {}}, "quality": {}}, frf)
    assert "no σ recorded" in source
    assert rows[0]["k"] == "4 × 10⁶ N/m" and rows[0]["c"] == "120 N·s/m" and rows[0]["k_sigma"] == "(σ not recorded)"
    assert rows[1]["k"] == "50000 N·m/rad" and rows[1]["c"] == "0.8 N·m·s/rad"
    assert wf.verdict({"provenance": {}, "quality": {}}) == (
        True, ["no identification record: uploaded as a joint FRF, its quality is not known"])
    plots = {p["id"]: p for p in wf.kc_plots(frf, "v1") + wf.frf_plots([("v1", frf)], "j")}
    assert np.allclose(plots["k-translation"]["series"][0]["y"], 4e6, rtol=1e-5)
    assert np.allclose(plots["c-rotation"]["series"][0]["y"], 0.8, rtol=1e-5)
    assert plots["frf-mag-0"]["y"] == "|H| [m/N]" and plots["frf-mag-1"]["y"] == "|H| [rad/(N·m)]"
    assert all(p["x"] == "frequency [Hz]" for p in plots.values())
