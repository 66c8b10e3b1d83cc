"""The known-answer catalogue of the band tests (issue 22): planar tool–holder joints whose stiffness and
damping follow k, c ∝ T^0.5 exactly (3e7 N/m, 6e5 N·m/rad, 300 N·s/m, 3 N·m·s/rad at 80 N·m), catalogued at
five torques on one frequency grid."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from jointdb.coupling import spring_damper_joint
from jointdb.store import Conditions, Provenance, Repository

TORQUES = (30.0, 50.0, 80.0, 130.0, 200.0)
STACK = Path(__file__).resolve().parents[2] / "fixtures" / "stacks" / "endmill-modelled-spindle.json"
F = np.linspace(20.0, 6000.0, 300)


def law(t):
    """``([k_x, k_θ], [c_x, c_θ])`` of the joint at torque ``t`` [N·m]."""
    s = (t / 80.0) ** 0.5
    return [3e7 * s, 6e5 * s], [300.0 * s, 3.0 * s]


def catalogue_power_law(db) -> None:
    """Catalogue the joint at each of :data:`TORQUES` as ``th-030`` … ``th-200`` into the SQLite file ``db``."""
    with Repository(db) as repo:
        for t in TORQUES:
            k, c = law(t)
            repo.catalogue(f"th-{t:03.0f}", "tool-holder", spring_damper_joint(F, k, c, ["3x", "3ry"]),
                           Conditions(("tungsten-carbide", "steel"), torque_nm=t), "spring-damper-planar",
                           Provenance(method="output-error-planar"))


def spec_at(d: Path, torque: float, joint):
    """The end-mill stack of :data:`STACK` with ``joint`` as its tool–holder interface, on a 20–6000 Hz grid,
    written to ``d / stack-<torque>.json`` and loaded."""
    from jointdb import usecases

    doc = json.loads(STACK.read_text())
    doc["interfaces"]["tool-holder"] = joint
    doc["frequency"] = {"min": 20, "max": 6000, "step": 10}
    path = d / f"stack-{torque:g}.json"
    path.write_text(json.dumps(doc))
    return usecases.load_stack(path)


@pytest.fixture
def linear_combination(monkeypatch):
    """The linear combination of the neighbours' dynamic stiffness (``jointdb.store._query.INTERPOLATION_LAW``) for
    one test: the known answers of the leave-one-out machinery are the linear chord's errors on this catalogue's
    power law (convex in ln T), and the shank exchange is exact only for a linear mix. The product's power-law
    combination interpolates this catalogue exactly
    (test_line_band.py::test_the_power_law_combination_leaves_no_line_error)."""
    import jointdb.store._query as query

    monkeypatch.setattr(query, "INTERPOLATION_LAW", "linear")
