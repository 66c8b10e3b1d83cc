"""The JSON model description file, ingredients as composable parts, import hygiene."""

import copy
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from jointdb.errors import InputError, NotFoundError
from jointdb.fe import (
    MATERIALS,
    BeamModel,
    Clamp,
    HystereticDamping,
    ModalDamping,
    PointMass,
    Segment,
    Support,
    get_material,
    load_model,
    model_from_dict,
    model_to_dict,
)

FIXTURES = Path(__file__).resolve().parents[2] / "fixtures" / "models"

GOOD = {
    "format": "jointdb-beam-model/1",
    "name": "test shaft",
    "kind": "planar",
    "theory": "timoshenko",
    "max_element_length": 0.01,
    "materials": {"soft-steel": {"E": 190e9, "nu": 0.29, "rho": 7900}},
    "segments": [
        {"length": 0.05, "outer_diameter": 0.02, "material": "steel"},
        {"length": 0.04, "outer_diameter": 0.016, "inner_diameter": 0.004, "material": "soft-steel"},
        {"length": 0.03, "outer_diameter": 0.01, "material": {"E": 600e9, "nu": 0.2, "rho": 15000}},
    ],
    "points": [{"name": "tip", "position": 0.12, "node": 1}, {"name": "root", "position": 0.0, "node": 7}],
    "clamps": [{"position": 0.0}],
    "supports": [{"position": 0.05, "stiffness": {"x": 1e7}, "damping": {"x": 20.0}}],
    "point_masses": [{"position": 0.12, "mass": 0.003, "rotary_inertia": 1e-8}],
    "damping": [{"type": "modal", "zeta": [0.01, 0.02]}, {"type": "hysteretic", "eta": 0.001}],
}


def test_fixture_models_load_and_have_modes():
    files = sorted(FIXTURES.glob("*.json"))
    assert len(files) >= 3
    for path in files:
        model = load_model(path)
        modes = model.modes(4)
        elastic = modes.freq_hz[modes.n_rigid :]
        assert np.all(elastic > 500) and np.all(np.diff(modes.freq_hz) >= 0), path.name
        assert model.points, path.name


def test_bundled_demo_model_is_the_fixture():
    import jointdb

    bundled = Path(jointdb.__file__).parent / "data" / "models" / "end-mill-in-holder.json"
    assert json.loads(bundled.read_text()) == json.loads((FIXTURES / "end-mill-in-holder.json").read_text())


def test_model_dict_round_trip_gives_the_same_model():
    model = model_from_dict(GOOD)
    again = model_from_dict(json.loads(json.dumps(model_to_dict(model))))
    freq = np.linspace(10, 5000, 50)
    a, b = model.frf(freq), again.frf(freq)
    assert a.allclose(b, rtol=1e-12)
    assert [type(i) for i in model.ingredients] == [type(i) for i in again.ingredients]
    assert again.segments[1].mat.E == 190e9 and again.segments[2].mat.E == 600e9


@pytest.mark.parametrize(
    "change, message",
    [
        (lambda d: d["segments"][1].update(outer_diameter=-0.01), r"^segments\[1\]\.outer_diameter: must be > 0"),
        (lambda d: d["segments"][0].update(length=0), r"^segments\[0\]\.length: must be > 0"),
        (lambda d: d["segments"][1].update(inner_diameter=0.02), r"^segments\[1\]\.inner_diameter: must be < outer_diameter"),
        (lambda d: d["segments"][0].update(material="unobtainium"), r"^segments\[0\]\.material: unknown material 'unobtainium'"),
        (lambda d: d["segments"][2]["material"].pop("rho"), r"^segments\[2\]\.material\.rho: is required"),
        (lambda d: d["segments"][0].update(lenght=0.1), r"^segments\[0\]\.lenght: unknown field"),
        (lambda d: d.update(segments=[]), r"^segments: needs at least one segment"),
        (lambda d: d.pop("segments"), r"^segments: is required"),
        (lambda d: d.update(theory="bernoulli"), r"^theory: must be one of"),
        (lambda d: d.update(kind="3d"), r"^kind: must be one of"),
        (lambda d: d.update(max_element_length="fine"), r"^max_element_length: must be a number"),
        (lambda d: d["points"][0].update(position=0.5), r"^points\[0\]\.position: 0\.5 m is beyond the model's length"),
        (lambda d: d["points"][1].update(name="tip"), r"^points\[1\]\.name: duplicate point name 'tip'"),
        (lambda d: d["points"][1].update(node=-3), r"^points\[1\]\.node: must be an integer >= 0"),
        (lambda d: d["points"][0].pop("node"), r"^points\[0\]\.node: is required"),
        (lambda d: d["clamps"][0].update(position=-1), r"^clamps\[0\]\.position: must be >= 0"),
        (lambda d: d["supports"][0]["stiffness"].update(x=-5), r"^supports\[0\]\.stiffness\.x: must be >= 0"),
        (lambda d: d["supports"][0].update(position=0.2), r"^supports\[0\]\.position: 0\.2 m is beyond"),
        (lambda d: d["point_masses"][0].update(mass="heavy"), r"^point_masses\[0\]\.mass: must be a number"),
        (lambda d: d["damping"][0].update(type="coulomb"), r"^damping\[0\]\.type: must be one of"),
        (lambda d: d["damping"][0].update(zeta=[0.01, -0.2]), r"^damping\[0\]\.zeta\[1\]: must be a number >= 0"),
        (lambda d: d["damping"][1].update(eta=float("nan")), r"^damping\[1\]\.eta: must be finite"),
        (lambda d: d["materials"]["soft-steel"].update(nu=0.7), r"^materials\.soft-steel: nu must be in"),
        (lambda d: d.update(format="other/2"), r"^format: unsupported format"),
        (lambda d: d.update(colour="red"), r"^colour: unknown field"),
    ],
)
def test_bad_model_names_the_exact_field(change, message):
    data = copy.deepcopy(GOOD)
    change(data)
    with pytest.raises(InputError, match=message) as info:
        model_from_dict(data)
    assert "\n" not in str(info.value)


def test_bad_files_give_one_line_errors(tmp_path):
    with pytest.raises(NotFoundError, match="does not exist"):
        load_model(tmp_path / "missing.json")
    bad = tmp_path / "bad.json"
    bad.write_text('{"segments": [\n  {"length": 0.1,}\n]}')
    with pytest.raises(InputError, match=r"bad\.json: not valid JSON \(line 2"):
        load_model(bad)
    wrong = tmp_path / "wrong.json"
    wrong.write_text(json.dumps({"segments": [{"length": 0.1, "outer_diameter": 0}]}))
    with pytest.raises(InputError, match=r"^wrong\.json: segments\[0\]\.outer_diameter: must be > 0"):
        load_model(wrong)


def test_unknown_direction_and_point_are_refused():
    model = model_from_dict(GOOD)
    with pytest.raises(InputError, match="unknown point 'nose'"):
        model.frf([100.0], points=["nose"])
    with pytest.raises(InputError, match="direction 'z' does not exist in a planar model"):
        model.frf([100.0], directions=["z"])
    with pytest.raises(InputError, match="direction 'rz' does not exist in a planar model"):
        model.with_ingredient(Support(0.01, {"rz": 1e3})).assemble()


def test_materials_library_has_the_thesis_values():
    assert get_material("carbide") is MATERIALS["tungsten-carbide"]
    assert (MATERIALS["tungsten-carbide"].E, MATERIALS["tungsten-carbide"].rho) == (550e9, 15630.0)
    assert (MATERIALS["steel"].E, MATERIALS["steel"].rho) == (210e9, 7800.0)
    assert (MATERIALS["aluminium"].E, MATERIALS["aluminium"].nu, MATERIALS["aluminium"].rho) == (68.9e9, 0.3, 2712.0)
    with pytest.raises(InputError, match="unknown material 'gold'"):
        get_material("gold")


def test_ingredients_are_independent_and_composable():
    bare = BeamModel((Segment(0.1, 0.01),), max_element_length=0.01)
    clamped = bare.with_ingredient(Clamp(0.0))
    assert bare.modes(3).n_rigid == 2 and clamped.modes(3).n_rigid == 0
    # order of ingredients does not matter
    a = clamped.with_ingredient(PointMass(0.1, 0.01), ModalDamping(0.02), HystereticDamping(0.01))
    b = bare.with_ingredient(HystereticDamping(0.01), ModalDamping(0.02), PointMass(0.1, 0.01), Clamp(0.0))
    np.testing.assert_allclose(a.assemble().K_loss, b.assemble().K_loss, rtol=0, atol=0)
    np.testing.assert_allclose(a.assemble().C, b.assemble().C, rtol=1e-12, atol=1e-12 * np.abs(a.assemble().C).max())
    # switching one off by class, by name or by predicate
    assert a.without(PointMass).ingredients == (Clamp(0.0), ModalDamping(0.02), HystereticDamping(0.01))
    assert a.without("modal-damping").ingredients == (Clamp(0.0), PointMass(0.1, 0.01), HystereticDamping(0.01))
    assert len(a.without(lambda i: i.stage > 0).ingredients) == 2
    # each changes only its own matrix
    m0, m1 = clamped.assemble(), clamped.with_ingredient(PointMass(0.05, 0.2)).assemble()
    np.testing.assert_allclose(m0.K, m1.K, rtol=1e-12, atol=1e-12 * np.abs(m0.K).max())  # 0.05 m: already a node
    dm = m1.M - m0.M
    assert np.count_nonzero(np.abs(dm) > 1e-12 * np.abs(m0.M).max()) == 1 and dm.max() == pytest.approx(0.2)
    # a very stiff support is a clamp
    stiff = bare.with_ingredient(Support(0.0, {"x": 1e14, "ry": 1e8}))
    np.testing.assert_allclose(stiff.modes(3).freq_hz, clamped.modes(3).freq_hz, rtol=1e-4)
    # a pinned end (x only): one rigid-body rotation remains
    assert bare.with_ingredient(Clamp(0.0, ("x",))).modes(2).n_rigid == 1


def test_mesh_has_nodes_at_all_declared_positions():
    model = model_from_dict(GOOD)
    nodes = model.mesh().node_positions
    for z in (0.0, 0.05, 0.09, 0.12):
        assert np.min(np.abs(nodes - z)) < 1e-12
    assert np.max(np.diff(nodes)) <= 0.01 + 1e-12


def test_import_jointdb_fe_pulls_in_no_io_or_ui_library():
    code = (
        "import sys, jointdb.fe\n"
        "print(','.join(m for m in ('sqlalchemy', 'h5py', 'typer', 'matplotlib', 'pyuff', 'rich') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == ""


def test_two_points_with_one_node_label_are_refused_at_construction():
    from jointdb.fe import NamedPoint

    with pytest.raises(InputError, match=r"points\[1\]\.node: node 1 is already used by point 'a'"):
        BeamModel((Segment(0.1, 0.01),), (NamedPoint("a", 0.1, 1), NamedPoint("b", 0.05, 1)))
