"""``predict`` says when the tip's dominant mode may lie outside the lines predicted (issue 22).

Known answers: a single-degree-of-freedom receptance ``1 / (k − mω² + i η k)`` has its only maximum at
``f_n = √(k/m) / 2π``; on lines that stop below ``f_n`` its largest |H| is on the last line (the flank of the
mode above), on lines starting above ``f_n`` it is on the first, and on lines covering it, inside. The same for a
real stack: the fixture's dominant tip mode (3120 Hz on 20 Hz lines to 6 kHz) predicted on lines starting at
3300 Hz is the flank on the first line; on lines covering it there is no note. The band's note is tested on
samples whose share on an edge line is set by hand.
"""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from typer.testing import CliRunner

from jointdb.cli import app
from jointdb.frf import FRF, Dof
from jointdb.usecases._stack_edge import BAND_EDGE_SHARE, band_edge_notes, edge_note, tip_edge_notes

ROOT = Path(__file__).resolve().parents[2]
STACK = ROOT / "fixtures" / "stacks" / "endmill-modelled-spindle.json"
K, M, ETA = 2.0e7, 0.05, 0.04
F_N = np.sqrt(K / M) / (2 * np.pi)  # 3183 Hz


def _sdof_tip(freq: np.ndarray, scale_y: float = 1.0) -> FRF:
    w = 2 * np.pi * freq
    h = 1.0 / (K - M * w ** 2 + 1j * ETA * K)
    v = np.zeros((freq.size, 2, 2), dtype=complex)
    v[:, 0, 0], v[:, 1, 1] = h, scale_y * h
    dofs = (Dof(1, "x"), Dof(1, "y"))
    return FRF(freq, v, dofs, dofs, "receptance")


def test_a_mode_above_the_lines_is_said_once_per_direction():
    f = np.arange(100.0, 0.8 * F_N, 10.0)
    notes = tip_edge_notes(_sdof_tip(f))
    last = f"{f[-1]:g} Hz"
    assert notes == (
        f"the largest |H| of the tip (x) is at the last line predicted ({last}): a mode may lie above it; extend "
        "frequency.max (--fmax) (the catalogued joints' lines allowing)",
        f"the largest |H| of the tip (y) is at the last line predicted ({last}): a mode may lie above it; extend "
        "frequency.max (--fmax) (the catalogued joints' lines allowing)")


def test_a_mode_below_the_lines_and_a_mode_inside():
    above = np.arange(1.2 * F_N, 8000.0, 10.0)
    assert [n.split(":")[0] for n in tip_edge_notes(_sdof_tip(above))] == [
        f"the largest |H| of the tip ({d}) is at the first line predicted ({above[0]:g} Hz)" for d in "xy"]
    assert "may lie below it; lower frequency.min (--fmin)" in tip_edge_notes(_sdof_tip(above))[0]
    assert tip_edge_notes(_sdof_tip(np.arange(100.0, 2 * F_N, 10.0))) == ()


def test_the_stack_on_lines_above_its_mode_and_on_lines_covering_it():
    from jointdb import usecases

    wide = usecases.predict_stack(STACK, None, np.arange(20.0, 6000.0 + 1e-9, 20.0)).prediction
    f_peak = wide.summary()[0]["peak_hz"]
    assert 2000.0 < f_peak < 5000.0
    assert not any("line predicted" in n for n in wide.notes)
    cut = usecases.predict_stack(STACK, None, np.arange(f_peak + 200.0, 6000.0 + 1e-9, 20.0)).prediction
    edge = [n for n in cut.notes if "line predicted" in n]
    assert [n[:60] for n in edge] == [f"the largest |H| of the tip ({d}) is at the first line predicte" for d in "xy"]


def test_predict_json_and_text_carry_the_note():
    runner = CliRunner()
    r = runner.invoke(app, ["predict", str(STACK), "--fmin", "3300", "--fmax", "6000", "--df", "20", "--json"])
    assert r.exit_code == 0, r.output
    notes = json.loads(r.stdout)["notes"]
    assert edge_note("x", "first", 3300.0) in notes and edge_note("y", "first", 3300.0) in notes
    r = runner.invoke(app, ["predict", str(STACK), "--fmax", "6000", "--df", "20", "--json"])
    assert r.exit_code == 0, r.output
    assert not any("line predicted" in n for n in json.loads(r.stdout)["notes"])
    r = runner.invoke(app, ["predict", str(STACK), "--fmin", "3300", "--fmax", "6000", "--df", "20"])
    assert r.exit_code == 0, r.output
    assert f"note: {edge_note('x', 'first', 3300.0)}" in r.stderr


def _band(freq: np.ndarray, at_last: int, n: int = 200) -> SimpleNamespace:
    """``n`` sampled tips, ``at_last`` of them SDOF with the mode above the lines, the others with it inside."""
    w = 2 * np.pi * freq
    low = 1.0 / (K * 0.5 - M * w ** 2 + 1j * ETA * K * 0.5)  # f_n / √2: inside the lines
    high = 1.0 / (K * 4.0 - M * w ** 2 + 1j * ETA * K * 4.0)  # 2 f_n: above them
    tips = np.array([high if i < at_last else low for i in range(n)])
    return SimpleNamespace(freq=freq, tips={"x": tips, "y": tips * 0 + low})


@pytest.mark.parametrize("at_last", [0, 9, 10, 60])
def test_the_band_says_so_from_five_percent_of_its_samples(at_last):
    f = np.arange(100.0, 1.5 * F_N, 10.0)
    band = _band(f, at_last)
    assert np.mean(np.argmax(np.abs(band.tips["x"]), axis=1) == f.size - 1) == at_last / 200
    notes = band_edge_notes(band)
    if at_last / 200 < BAND_EDGE_SHARE:
        assert notes == ()
    else:
        assert notes == (f"band: the largest |H| of the tip (x) is at the last line predicted ({f[-1]:g} Hz) in "
                         f"{at_last / 200:.0%} of the band's samples: a mode may lie above it; extend frequency.max "
                         "(--fmax) (the catalogued joints' lines allowing)",)
        # the nominal tip already on that line (x): its note says it, the band does not repeat it
        v = np.zeros((f.size, 2, 2), dtype=complex)
        v[:, 0, 0], v[:, 1, 1] = band.tips["x"][0], band.tips["y"][0]
        nominal = FRF(f, v, (Dof(1, "x"), Dof(1, "y")), (Dof(1, "x"), Dof(1, "y")), "receptance")
        assert tip_edge_notes(nominal) == (edge_note("x", "last", float(f[-1])),)
        assert band_edge_notes(band, nominal) == ()


def test_band_terms_carry_the_band_note_in_json():
    from jointdb.usecases._stack_band import BandTerms

    t = BandTerms(None, ("a note", "band: edge"), {"all": {}}, {}, ("band: edge",))
    assert t.to_json()["grid_edge"] == ["band: edge"]
