"""Models of one geometry share a mesh (and its bare beam matrices): a fit makes one model per evaluation.

The shared path must give exactly (bit for bit) what a model that builds its own mesh gives, name its own
interfaces in the mesh, and never share across a change of geometry.
"""

import dataclasses

import numpy as np
import pytest

import jointdb.fe._model as fe_model
import jointdb.fe._bare as fe_bare
import jointdb.fe._rigid as fe_rigid
from jointdb.fe import BeamModel, Clamp, Contact, Insertion, Joint, NamedPoint, PointMass, Segment, Support
from jointdb.fe._joints import _foundation


@pytest.fixture
def empty_caches(monkeypatch):
    """Start with nothing shared (the caches are replaced for the test only)."""
    from collections import OrderedDict

    monkeypatch.setattr(fe_model, "_MESH_CACHE", OrderedDict())
    monkeypatch.setattr(fe_bare, "_BARE_CACHE", OrderedDict())
    monkeypatch.setattr(fe_bare, "_BARE_BYTES", [0])
    monkeypatch.setattr(fe_rigid, "_RIGID_CACHE", OrderedDict())


def _model(kind="planar", k_joint=3e7, k_contact=5e11, mass=0.05, diameter=0.012):
    segs = (Segment(0.03, 0.04), Segment(0.03, 0.03, 0.012), Segment(0.05, diameter, material="carbide"))
    dirs = {"x": 1.0, "y": 1.0, "z": 1.0, "rz": 1e-6} if kind == "frame3d" else {"x": 1.0}
    ins = Insertion(0.03, 0.06, 0.012, material="carbide",
                    contact=Contact({d: k_contact * v for d, v in dirs.items()}, loss_factor=0.1))
    joint = Joint(0.015, {"x": k_joint, "ry": 2e4}, loss_factor=0.02)
    return BeamModel(segs, points=(NamedPoint("tip", 0.11, 1), NamedPoint("mid", 0.08, 2)),
                     ingredients=(Clamp(0.0), joint, ins, PointMass(0.11, mass), Support(0.06, {"x": 1e6})),
                     kind=kind, max_element_length=0.004)


def _fresh(make):
    """What ``make()`` assembles with nothing shared (the caches emptied first, restored after)."""
    saved = fe_model._MESH_CACHE.copy(), fe_rigid._RIGID_CACHE.copy()
    fe_model._MESH_CACHE.clear()
    fe_rigid._RIGID_CACHE.clear()
    try:
        model = make()
        return model, model.assemble()
    finally:
        fe_model._MESH_CACHE.update(saved[0])
        fe_rigid._RIGID_CACHE.update(saved[1])


@pytest.mark.parametrize("kind", ["planar", "frame3d"])
def test_a_model_on_a_shared_mesh_assembles_bit_for_bit_what_its_own_mesh_gives(empty_caches, kind):
    first = _model(kind)
    first.assemble()
    changes = [dict(k_joint=5e7), dict(k_contact=2e11), dict(mass=0.2), dict(diameter=0.011)]
    for change in changes:
        shared = _model(kind, **change)
        assert shared.mesh().node_positions is first.mesh().node_positions      # the mesh is shared
        got = shared.assemble()
        own_model, want = _fresh(lambda: _model(kind, **change))
        assert own_model.mesh().node_positions is not first.mesh().node_positions
        for name in ("K", "M", "C", "K_loss", "fixed"):
            np.testing.assert_array_equal(getattr(got, name), getattr(want, name), err_msg=f"{change} {name}")
        assert got.dof_labels == want.dof_labels
        # the shared mesh names this model's interfaces (looked up by identity)
        joint, ins = shared.ingredients[1], shared.ingredients[2]
        assert shared.mesh().split_nodes(joint) == first.mesh().split_nodes(first.ingredients[1])
        assert shared.mesh().contact_pairs(ins) == first.mesh().contact_pairs(first.ingredients[2])
        np.testing.assert_array_equal(shared.modes(4).freq_hz, own_model.modes(4).freq_hz)


def test_no_sharing_across_a_change_of_geometry(empty_caches):
    base = _model()
    moved_joint = base.replace(ingredients=tuple(Joint(0.02, i.stiffness) if isinstance(i, Joint) else i
                                                 for i in base.ingredients))
    finer = base.replace(max_element_length=0.003)
    rigid_dir = base.replace(ingredients=tuple(Joint(0.015, {"ry": 2e4}) if isinstance(i, Joint) else i
                                               for i in base.ingredients))
    for other in (moved_joint, finer, rigid_dir):
        assert other.mesh().node_positions is not base.mesh().node_positions
        _, want = _fresh(lambda: other.replace())
        np.testing.assert_array_equal(other.assemble().K, want.K)
    assert rigid_dir.mesh().n_dof == base.mesh().n_dof - 1            # x tied at the joint


def test_the_bare_matrices_handed_out_are_copies(empty_caches):
    a = _model()
    K1 = a.assemble().K
    K1[:] = 0.0                      # a caller scribbling on its matrices
    np.testing.assert_array_equal(_model().assemble().K, _fresh(_model)[1].K)


def test_contact_layer_equals_the_element_by_element_sum():
    # the contact stiffness, added for all elements at once, equals the loop over elements and blocks
    m = _model("frame3d")
    ins = m.ingredients[2]
    mesh = m.mesh()
    fm = m.assemble()
    got = ins.apply(dataclasses.replace(fm, K=np.zeros_like(fm.K), K_loss=np.zeros_like(fm.K)), mesh).K
    want = np.zeros_like(got)
    for d, (t, r, sign) in {"x": ("x", "ry", 1.0), "y": ("y", "rx", -1.0)}.items():
        kp = ins.contact.stiffness_per_length[d]
        for ia, ib, ha, hb, h in mesh.contact_elements(ins):
            kf = _foundation(kp, h, sign)
            inner = [mesh.dof(ia, t), mesh.dof(ia, r), mesh.dof(ib, t), mesh.dof(ib, r)]
            host = [mesh.dof(ha, t), mesh.dof(ha, r), mesh.dof(hb, t), mesh.dof(hb, r)]
            for rows, cols, s in ((inner, inner, 1.0), (host, host, 1.0), (inner, host, -1.0), (host, inner, -1.0)):
                want[np.ix_(rows, cols)] += s * kf
    assert np.abs(want).max() > 0
    for inner, host, trib in mesh.contact_pairs(ins):       # axial and torsion: springs at the nodes
        for d in ("z", "rz"):
            k = ins.contact.stiffness_per_length[d] * trib
            i, j = mesh.dof(inner, d), mesh.dof(host, d)
            want[[i, j], [i, j]] += k
            want[[i, j], [j, i]] -= k
    np.testing.assert_array_equal(got, want)


def test_the_bare_matrices_kept_stay_within_their_byte_budget(empty_caches, monkeypatch):
    n = _model().assemble().K.shape[0]
    monkeypatch.setattr(fe_bare, "BARE_CACHE_BYTES", 3 * 2 * n * n * 8)      # room for three (K, M) pairs
    for d in (0.0110, 0.0111, 0.0112, 0.0113, 0.0114):                        # a diameter fit: new sections
        got = _model(diameter=d).assemble()
        np.testing.assert_array_equal(got.K, _fresh(lambda: _model(diameter=d))[1].K)
    assert len(fe_bare._BARE_CACHE) == 3
    assert fe_bare._BARE_BYTES[0] == sum(2 * v[1].nbytes for v in fe_bare._BARE_CACHE.values())
