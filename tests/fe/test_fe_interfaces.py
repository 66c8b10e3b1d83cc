"""Interfaces inside a beam model: point joints (split beams) and inserted parts."""

import numpy as np
import pytest

from jointdb.errors import InputError
from jointdb.fe import (
    BeamModel,
    Clamp,
    Contact,
    Insertion,
    Joint,
    NamedPoint,
    Segment,
    get_material,
    model_from_dict,
    model_to_dict,
)
from jointdb.stack import composite_material

EPS = np.finfo(float).eps


def _static_tip_compliance(model, point="tip"):
    """x/F at ``point`` from the stiffness matrix alone (static, exact)."""
    fm = model.assemble()
    free = ~fm.fixed
    mesh = model.mesh()
    i = mesh.dof(mesh.node_at(model.point(point).position), "x")
    pos = int(np.cumsum(free)[i] - 1)
    K = fm.K[np.ix_(free, free)]
    e = np.zeros(K.shape[0])
    e[pos] = 1.0
    return float(np.linalg.solve(K, e)[pos]), float(np.linalg.cond(K))


def test_joint_adds_its_exact_static_compliance_to_a_cantilever():
    # Euler–Bernoulli cubic elements give the exact static deflection, so the tip
    # compliance of a uniform cantilever with a joint at z = a is exactly
    # L^3/(3EI) + 1/k_x + (L - a)^2/k_theta (the joint carries F and F (L - a)).
    L, a, d = 0.12, 0.05, 0.02
    steel = get_material("steel")
    EI = steel.E * np.pi * d**4 / 64
    kx, kr = 3e7, 2e4
    model = BeamModel((Segment(a, d), Segment(L - a, d)), points=(NamedPoint("tip", L, 1),),
                      ingredients=(Clamp(0.0), Joint(a, {"x": kx, "ry": kr})), theory="euler-bernoulli",
                      max_element_length=0.01)
    got, cond = _static_tip_compliance(model)
    want = L**3 / (3 * EI) + 1 / kx + (L - a) ** 2 / kr
    assert got == pytest.approx(want, rel=100 * cond * EPS)


def test_joint_rigid_in_untouched_directions_and_stiff_joint_is_no_joint():
    base = BeamModel((Segment(0.06, 0.03), Segment(0.05, 0.012, material="carbide")),
                     points=(NamedPoint("tip", 0.11, 1),), ingredients=(Clamp(0.0),))
    n0 = base.mesh().n_dof
    only_rot = base.with_ingredient(Joint(0.06, {"ry": 1e4}))
    assert only_rot.mesh().n_dof == n0 + 1          # x stays tied (shared DOF), ry is split
    both = base.with_ingredient(Joint(0.06, {"x": 1e7, "ry": 1e4}))
    assert both.mesh().n_dof == n0 + 2
    f0 = base.modes(3).freq_hz
    # a joint k times stiffer than the local bending stiffness changes frequencies by ~ 1/k
    stiff = base.with_ingredient(Joint(0.06, {"x": 1e15, "ry": 1e12}))
    assert np.allclose(stiff.modes(3).freq_hz, f0, rtol=1e-5)
    soft = both.modes(3).freq_hz
    assert np.all(soft < f0 * 0.95)


def test_rigid_insertion_is_the_bonded_composite_section():
    # Euler–Bernoulli: the bonded composite's EI and rho A are the sums of the parts,
    # exactly what sharing the DOFs assembles; the two models are the same matrices
    # up to summation order.
    steel, carbide = get_material("steel"), get_material("carbide")
    comp = composite_material(steel, carbide, 0.03, 0.012, 0.012)
    common = dict(points=(NamedPoint("tip", 0.11, 1),), theory="euler-bernoulli")
    inserted = BeamModel((Segment(0.03, 0.04), Segment(0.03, 0.03, 0.012), Segment(0.05, 0.012, material="carbide")),
                         ingredients=(Clamp(0.0), Insertion(0.03, 0.06, 0.012, material="carbide")), **common)
    composite = BeamModel((Segment(0.03, 0.04), Segment(0.03, 0.03, 0.0, material=comp),
                           Segment(0.05, 0.012, material="carbide")), ingredients=(Clamp(0.0),), **common)
    fa, fb = inserted.modes(4).freq_hz, composite.modes(4).freq_hz
    assert inserted.mesh().n_dof == composite.mesh().n_dof
    # round-off of a symmetric-definite eigenproblem: |dλ| ≲ n eps λ_max, so df/f ≲ ½ n eps λ_max/λ
    lam = (2 * np.pi * composite.modes().freq_hz) ** 2
    tol = 0.5 * lam.size * EPS * lam.max() / lam[:4]
    assert np.all(np.abs(fa / fb - 1) <= tol), (np.abs(fa / fb - 1), tol)


def test_contact_layer_converges_to_the_rigid_insertion_and_softens_when_compliant():
    segs = (Segment(0.03, 0.04), Segment(0.03, 0.03, 0.012), Segment(0.05, 0.012, material="carbide"))
    rigid = BeamModel(segs, points=(NamedPoint("tip", 0.11, 1),), theory="euler-bernoulli",
                      ingredients=(Clamp(0.0), Insertion(0.03, 0.06, 0.012, material="carbide")))
    f_rigid = rigid.modes(3).freq_hz
    gaps = []
    for k in (1e11, 1e13, 1e15, 1e17):
        m = rigid.replace(ingredients=(Clamp(0.0), Insertion(0.03, 0.06, 0.012, material="carbide",
                                                              contact=Contact({"x": k}))))
        gaps.append(np.max(np.abs(m.modes(3).freq_hz / f_rigid - 1)))
    assert all(b < a for a, b in zip(gaps, gaps[1:]))     # monotone towards the bonded section
    assert gaps[0] > 0.1 and gaps[-1] < 2e-3


def test_contact_loss_damps_the_interface_mode_only_through_the_contact():
    segs = (Segment(0.03, 0.04), Segment(0.03, 0.03, 0.012), Segment(0.05, 0.012, material="carbide"))
    ins = Insertion(0.03, 0.06, 0.012, material="carbide", contact=Contact({"x": 5e11}, loss_factor=0.2))
    m = BeamModel(segs, points=(NamedPoint("tip", 0.11, 1),), ingredients=(Clamp(0.0), ins))
    fm = m.assemble()
    # the hysteretic matrix is exactly 0.2 x the contact stiffness: zero outside the contact DOFs
    mesh = m.mesh()
    inner = {i for i, _, _ in mesh.contact_pairs(ins)} | {h for _, h, _ in mesh.contact_pairs(ins)}
    rows = np.nonzero(np.abs(fm.K_loss).sum(axis=1))[0]
    assert {int(fm.dof_labels[r].node) for r in rows} <= inner
    f1 = m.modes(1).freq_hz[0]
    H = m.frf(np.linspace(0.8, 1.2, 401) * f1, points=["tip"], directions=["x"]).values[:, 0, 0]
    assert np.isfinite(H).all() and np.abs(H).max() < 1e3 * np.abs(H).min()


def test_model_file_round_trip_and_field_errors():
    data = {
        "segments": [{"length": 0.03, "outer_diameter": 0.04},
                     {"length": 0.03, "outer_diameter": 0.03, "inner_diameter": 0.012},
                     {"length": 0.05, "outer_diameter": 0.012, "material": "carbide"}],
        "points": [{"name": "tip", "position": 0.11, "node": 1}],
        "clamps": [{"position": 0.0}],
        "joints": [{"position": 0.03, "stiffness": {"x": 1e9, "ry": 1e6}, "loss_factor": 0.02, "label": "flange"}],
        "insertions": [{"start": 0.03, "end": 0.06, "outer_diameter": 0.012, "material": "carbide",
                        "joined_at": "end", "contact": {"stiffness_per_length": {"x": 5e11}, "loss_factor": 0.1},
                        "label": "tool shank"}],
    }
    m = model_from_dict(data)
    again = model_from_dict(model_to_dict(m))
    assert np.array_equal(m.modes(3).freq_hz, again.modes(3).freq_hz)
    bad = [
        ({"joints": [{"position": 0.0, "stiffness": {"x": 1.0}}]}, r"^joints\[0\]: .*inside the model"),
        ({"joints": [{"position": 0.05, "stiffness": {}}]}, r"^joints\[0\]\.stiffness: needs at least one"),
        ({"joints": [{"position": 0.05, "stiffness": {"x": 1.0}, "damping": {"ry": 1.0}}]},
         r"^joints\[0\]\.damping\.ry: a damper needs a spring"),
        ({"insertions": [{"start": 0.03, "end": 0.06, "outer_diameter": 0.012, "contact": "glue"}]},
         r"^insertions\[0\]\.contact: must be \"rigid\""),
        ({"insertions": [{"start": 0.06, "end": 0.03, "outer_diameter": 0.012}]}, r"^insertions\[0\]\.end: must be >"),
        ({"insertions": [{"start": 0.03, "end": 0.06, "outer_diameter": 0.012, "joined_at": "middle"}]},
         r"^insertions\[0\]\.joined_at"),
        ({"insertions": [{"start": 0.03, "end": 0.06, "outer_diameter": 0.012,
                          "contact": {"stiffness_per_length": {"x": -1.0}}}]},
         r"^insertions\[0\]\.contact\.stiffness_per_length\.x: must be >= 0"),
        ({"joints": [{"position": 0.06, "stiffness": {"x": 1.0}}],
          "insertions": [{"start": 0.03, "end": 0.06, "outer_diameter": 0.012,
                          "contact": {"stiffness_per_length": {"x": 1e11}}}]},
         r"^insertions\[0\]: .*already has an interface there"),
    ]
    base = {k: v for k, v in data.items() if k not in ("joints", "insertions")}
    for change, pattern in bad:
        with pytest.raises(InputError, match=pattern):
            model_from_dict(base | change)


def test_frame3d_joint_bends_alike_in_x_and_y():
    m = BeamModel((Segment(0.06, 0.03), Segment(0.05, 0.012)), points=(NamedPoint("tip", 0.11, 1),),
                  ingredients=(Clamp(0.0), Joint(0.06, {"x": 1e7, "y": 1e7, "ry": 1e4, "rx": 1e4})), kind="frame3d")
    H = m.frf([300.0, 900.0], points=["tip"], directions=["x", "y"]).values
    assert np.allclose(H[:, 0, 0], H[:, 1, 1], rtol=1e-9)
    with pytest.raises(InputError):
        BeamModel((Segment(0.06, 0.03), Segment(0.05, 0.012)), ingredients=(Clamp(0.0), Joint(0.06, {"y": 1e7})))\
            .assemble()
