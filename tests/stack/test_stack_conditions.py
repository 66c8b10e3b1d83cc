"""Conditions that change a joint are conditions (issue 22, item 3): the stack's insertion length joins a
tool–holder query when the catalogue records it (and is warned about outside its span); a drawbar force the
catalogue holds at one value only is used with a note, not an extrapolation warning."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from jointdb.coupling import spring_damper_joint
from jointdb.store import Conditions, Provenance, Repository

ROOT = Path(__file__).resolve().parents[2]
STACK = ROOT / "fixtures" / "stacks" / "endmill-modelled-spindle.json"  # tool 80 mm long, 50 mm gauge
F = np.linspace(20.0, 6000.0, 200)


@pytest.fixture(scope="module")
def db(tmp_path_factory):
    d = tmp_path_factory.mktemp("conditions")
    path = d / "j.sqlite"
    with Repository(path) as repo:
        for t in (40.0, 120.0):
            for ins in (0.025, 0.040):
                k = 3e7 * (t / 80) ** 0.5 * ins / 0.03
                repo.catalogue(f"th-{t:.0f}-{ins * 1e3:.0f}", "tool-holder",
                               spring_damper_joint(F, [k, k / 50], [300.0, 3.0], ["3x", "3ry"]),
                               Conditions(("tungsten-carbide", "steel"), preload_n=12000.0, torque_nm=t,
                                          geometry={"insertion_m": ins}), "spring-damper-planar",
                               Provenance(method="output-error-planar"))
    return d, path


def _predict(d: Path, db: Path, gauge: float, query: dict):
    from jointdb import usecases

    doc = json.loads(STACK.read_text())
    doc["gauge_length"] = gauge
    doc["interfaces"]["tool-holder"] = {"query": {"joint_type": "tool-holder",
                                                  "materials": ["tungsten-carbide", "steel"], **query}}
    doc["frequency"] = {"min": 20, "max": 6000, "step": 20}
    path = d / f"stack-{gauge}.json"
    path.write_text(json.dumps(doc))
    return usecases.predict_stack(usecases.load_stack(path), str(db)).joints["tool-holder"]


def test_insertion_length_is_a_condition_when_the_catalogue_records_it(db):
    d, path = db
    res = _predict(d, path, 0.050, {"torque_nm": 80.0, "interpolate": True})  # 30 mm inserted
    assert not res.extrapolating
    assert any("insertion length 30 mm is a condition" in w for w in res.warnings)
    used = {n for n, _, _, _ in res.neighbours}
    assert used == {"th-40-25", "th-40-40", "th-120-25", "th-120-40"}  # bracketed in torque and insertion
    res = _predict(d, path, 0.060, {"torque_nm": 80.0, "interpolate": True})  # 20 mm: shorter than catalogued
    assert res.extrapolating and "geometry.insertion_m" in res.outside_range and res.method == "edge"


def test_a_drawbar_force_catalogued_at_one_value_gives_a_note_not_a_warning(db):
    d, path = db
    res = _predict(d, path, 0.050, {"torque_nm": 80.0, "preload_n": 20000.0, "interpolate": True})
    assert not res.extrapolating and "preload_n" not in res.outside_range
    notes = [w for w in res.warnings if w.startswith("note: ")]
    assert any("catalogued at one preload_n only (12000)" in n and "20000" in n for n in notes)


def test_an_unvaried_drawbar_force_still_widens_the_joint_choice_error(db):
    """A note, not an edge — but the request's distance from what the catalogue saw still counts: on truth
    family B a reduced catalogue with tool–holder joints of a 10 kN machine only puts an 18 kN stack's peak off
    by tens of per cent (tests/stack/test_band_truth_b.py), which no catalogued data could have shown."""
    d, path = db
    with_force = _predict(d, path, 0.050, {"torque_nm": 80.0, "preload_n": 20000.0, "interpolate": True})
    without = _predict(d, path, 0.050, {"torque_nm": 80.0, "interpolate": True})
    assert with_force.choice_error.distance > without.choice_error.distance > 0
    # the torque and insertion lines are left out either way; the unvaried force adds single left-out joints
    # scaled by the distance (no line says how much it matters)
    assert {p.axis for p in without.choice_error.points} == {"torque_nm", "geometry.insertion_m"}
    assert "" in {p.axis for p in with_force.choice_error.points}


def test_an_interpolated_joint_without_enough_neighbours_for_leave_one_out_still_gets_a_band(tmp_path):
    from jointdb import usecases
    from jointdb.usecases._stack_band import prediction_band

    db = tmp_path / "two.sqlite"
    with Repository(db) as repo:
        for t in (40.0, 120.0):
            k = 3e7 * (t / 80) ** 0.5
            repo.catalogue(f"th-{t:.0f}", "tool-holder", spring_damper_joint(F, [k, k / 50], [300.0, 3.0],
                                                                             ["3x", "3ry"]),
                           Conditions(("tungsten-carbide", "steel"), torque_nm=t), "spring-damper-planar")
    res = _predict(tmp_path, db, 0.050, {"torque_nm": 80.0, "interpolate": True})
    assert res.kind == "interpolated" and res.choice_error is None
    doc = json.loads(STACK.read_text())
    doc["interfaces"]["tool-holder"] = {"query": {"joint_type": "tool-holder", "torque_nm": 80.0,
                                                  "interpolate": True}}
    doc["frequency"] = {"min": 20, "max": 6000, "step": 20}
    (tmp_path / "s.json").write_text(json.dumps(doc))
    result = usecases.predict_stack(usecases.load_stack(tmp_path / "s.json"), str(db))
    band, notes = prediction_band(result, n=50)
    assert band is not None and band.interfaces == ("prediction path",)
    assert any("no joint-choice error" in n for n in notes)
