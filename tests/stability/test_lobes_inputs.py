"""`jointdb lobes` with the inputs engineers have (issue 13 item 5): xx + yy only, --frf-y in turning,
cutting coefficients in the wrong unit."""

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from jointdb.cli import app
from jointdb.io import write_frf_hdf5, write_uff58
from jointdb.modal import ModalModel
from jointdb.stability import MillingCut, milling_lobes_zoa, turning_lobes

runner = CliRunner()
FREQ = np.arange(300.0, 1500.0, 0.5)
KX = 0.04 * (2 * np.pi * 922) ** 2
KY = 0.05 * (2 * np.pi * 780) ** 2


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("tip2")
    fx = ModalModel.from_modal_parameters([922], [0.011], [KX], "1x").synthesize(FREQ)
    fy = ModalModel.from_modal_parameters([780], [0.02], [KY], "1y").synthesize(FREQ)
    write_uff58(d / "x.uff", fx.to("accelerance"), binary=False)
    write_uff58(d / "y.uff", fy.to("accelerance"), binary=False)
    # the usual tap-test export: the two driving points in one file, no cross records
    (d / "xxyy.uff").write_bytes((d / "x.uff").read_bytes() + (d / "y.uff").read_bytes())
    write_frf_hdf5(d / "x.h5", fx)
    write_frf_hdf5(d / "y.h5", fy)
    return d, fx, fy


def lobes(*args):
    r = runner.invoke(app, ["lobes", *map(str, args), "--refine", "0", "--json"])
    return r


def rows(r):
    data = json.loads(r.stdout[r.stdout.index("{"):])
    return data, np.array([row["depth_m"] for row in data["rows"]], float)


def test_xx_yy_only_file_is_accepted_for_milling_with_a_note(files):
    d, fx, fy = files
    r = lobes(d / "xxyy.uff", "--op", "milling", "--teeth", "2", "--kt", "6e8", "--kr", "2e8",
              "--rpm-min", "5000", "--rpm-max", "20000", "--n-speeds", "200")
    assert r.exit_code == 0, r.output
    data, depth = rows(r)
    assert any("cross terms taken as zero" in n for n in data["notes"])
    # same as the library on the two driving points (x and y files)
    ref = milling_lobes_zoa(fx, MillingCut(2, 6e8, 2e8, 1.0, True), fy, spindle_speed_rpm=np.linspace(5000, 20000, 200))
    assert np.allclose(depth, ref.depth_m, rtol=1e-6, equal_nan=True)


def test_turning_uses_frf_y_and_the_xx_yy_file(files):
    d, fx, fy = files
    speeds = ["--rpm-min", "2000", "--rpm-max", "8000", "--n-speeds", "50"]
    only_x = rows(lobes(d / "x.h5", "--op", "turning", "--kf", "1e9", *speeds))[1]
    r = lobes(d / "x.h5", "--op", "turning", "--kf", "1e9", "--frf-y", d / "y.h5", "--orientation", "0.7,0.4", *speeds)
    assert r.exit_code == 0, r.output
    data, with_y = rows(r)
    assert any("from --frf-y" in n for n in data["notes"])
    # the library on the combined x + y receptance, weighted 0.7 and 0.4
    from jointdb.frf import FRF

    both = FRF(FREQ, np.stack([np.stack([fx.values[:, 0, 0], 0 * FREQ], 1),
                               np.stack([0 * FREQ, fy.values[:, 0, 0]], 1)], 1), ["1x", "1y"], ["1x", "1y"],
               "receptance")
    ref = turning_lobes(both, 1e9, [0.7, 0.4], spindle_speed_rpm=np.linspace(2000, 8000, 50))
    assert np.allclose(with_y, ref.depth_m, rtol=1e-9, equal_nan=True)
    assert not np.allclose(with_y, only_x, equal_nan=True)
    r2 = lobes(d / "xxyy.uff", "--op", "turning", "--kf", "1e9", "--orientation", "0.7,0.4", *speeds)
    assert r2.exit_code == 0, r2.output
    assert np.allclose(rows(r2)[1], with_y, rtol=1e-6, equal_nan=True)  # ASCII UFF keeps 12 digits


def test_turning_refuses_an_frf_y_it_cannot_use(files):
    d, _, _ = files
    r = lobes(d / "xxyy.uff", "--op", "turning", "--kf", "1e9", "--frf-y", d / "y.h5")
    assert r.exit_code != 0
    assert "already in the main tool-tip file" in str(r.exception) + r.output


@pytest.mark.parametrize("args,expect", [
    (["--op", "milling", "--teeth", "2", "--kt", "796", "--kr", "2e8"], "--kt 796 N/m² is implausibly small"),
    (["--op", "turning", "--kf", "2000"], "--kf 2000 N/m² is implausibly small"),
    (["--op", "milling", "--teeth", "2", "--kt", "6e8", "--kr", "3e13"], "--kr 3e+13 N/m² is implausibly large"),
])
def test_cutting_coefficients_in_the_wrong_unit_warn(files, args, expect):
    d, _, _ = files
    r = lobes(d / "x.h5", *args, "--n-speeds", "20")
    assert r.exit_code == 0, r.output
    notes = " ".join(rows(r)[0]["notes"])
    assert expect in notes
    if "small" in expect:
        assert "N/mm² (= MPa)" in notes  # names the likely unit and the value in N/m²
        assert ("7.96e+08" in notes) or ("2e+09" in notes)
    r = lobes(d / "x.h5", "--op", "milling", "--teeth", "2", "--kt", "6e8", "--kr", "2e8", "--n-speeds", "20")
    assert rows(r)[0]["notes"] == []


def coupled_tip(freq):
    """A 2×2 tip receptance whose two modes move along skewed directions: non-zero H[x,y]."""
    om = 2 * np.pi * freq
    h = np.zeros((freq.size, 2, 2), complex)
    for fn, zeta, k, angle in ((850.0, 0.02, 3e7, 0.5), (1100.0, 0.015, 4e7, 2.2)):
        wn = 2 * np.pi * fn
        phi = np.array([np.cos(angle), np.sin(angle)])
        h += np.outer(phi, phi)[None] / (k * (1 - (om / wn) ** 2 + 2j * zeta * om / wn))[:, None, None]
    from jointdb.frf import FRF
    return FRF(freq, h, ("1x", "1y"), ("1x", "1y"), "receptance")


def test_cross_terms_in_the_tip_file_are_used_by_default(tmp_path):
    tip = coupled_tip(FREQ)
    write_frf_hdf5(tmp_path / "tip.h5", tip)
    cut = MillingCut(2, 6e8, 2e8, 0.5, True)
    speeds = np.linspace(5000, 20000, 120)
    args = [tmp_path / "tip.h5", "--op", "milling", "--teeth", "2", "--kt", "6e8", "--kr", "2e8",
            "--immersion", "0.5", "--rpm-min", "5000", "--rpm-max", "20000", "--n-speeds", "120"]
    with_cross = milling_lobes_zoa(tip, cut, cross_terms=True, spindle_speed_rpm=speeds).depth_m
    without = milling_lobes_zoa(tip, cut, cross_terms=False, spindle_speed_rpm=speeds).depth_m
    assert not np.allclose(with_cross, without, rtol=1e-3, equal_nan=True)  # the case tells the two apart
    data, depth = rows(lobes(*args))
    assert np.allclose(depth, with_cross, rtol=1e-9, equal_nan=True)
    assert any("cross terms are used" in n for n in data["notes"])
    data, depth = rows(lobes(*args, "--no-cross-terms"))
    assert np.allclose(depth, without, rtol=1e-9, equal_nan=True)
    assert np.allclose(rows(lobes(*args, "--cross-terms"))[1], with_cross, rtol=1e-9, equal_nan=True)
