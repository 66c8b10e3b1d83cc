"""couple() (interface-sized, only the requested blocks, one gather per substructure) against the
textbook LM-FBS expression on the whole block-diagonal matrix, ``Y − Y Bᵀ (B Y Bᵀ + H_J)⁻¹ B Y``.

Tolerance from conditioning: both compute the same rational expression; their difference is
round-off of the interface solve, bounded by ``c · n · eps · cond(Z) · max|Y|`` per line with
``Z = B Y Bᵀ + H_J`` (a factor c = 10 for the few extra products)."""

import numpy as np
import pytest

from jointdb.coupling import Interface, JointSubstructure, couple, spring_damper_joint
from jointdb.frf import FRF, Dof

EPS = np.finfo(float).eps
FREQ = np.linspace(5.0, 900.0, 301)


def modal(freq, n, seed, node0):
    """Symmetric, passive receptance of a random damped n-DOF modal model, labelled node0+1.."""
    rng = np.random.default_rng(seed)
    fn = np.sort(rng.uniform(40, 1200, n))
    zeta = rng.uniform(0.01, 0.05, n)
    phi = rng.standard_normal((n, n))
    w, wn = 2 * np.pi * freq[:, None], 2 * np.pi * fn[None, :]
    d = 1.0 / (wn**2 - w**2 + 2j * zeta * wn * w)
    h = np.einsum("im,fm,jm->fij", phi, d, phi)
    labels = [Dof(node0 + i + 1, "x") for i in range(n)]
    return FRF(freq, h, labels, labels)


def textbook(subs, pairs, joints, outputs, inputs):
    """Full LM-FBS over all DOFs of all substructures; pairs = [(name_a, dof_a, name_b, dof_b)]."""
    names = list(subs)
    offset, o = {}, 0
    for name in names:
        offset[name] = o
        o += len(subs[name].outputs)
    nf, n = FREQ.size, o
    y = np.zeros((nf, n, n), dtype=complex)
    for name in names:
        k = len(subs[name].outputs)
        y[:, offset[name] : offset[name] + k, offset[name] : offset[name] + k] = subs[name].values
    pos = {(name, d): offset[name] + i for name in names for i, d in enumerate(subs[name].outputs)}
    b = np.zeros((len(pairs), n))
    for r, (na, da, nb, db) in enumerate(pairs):
        b[r, pos[(na, Dof.parse(da))]] += 1.0
        b[r, pos[(nb, Dof.parse(db))]] -= 1.0
    z = b @ y @ b.T + joints
    g = y - (y @ b.T) @ np.linalg.solve(z, b @ y)
    oi = [pos[(nm, Dof.parse(d))] for nm, d in outputs]
    ii = [pos[(nm, Dof.parse(d))] for nm, d in inputs]
    return g[:, oi][:, :, ii], z, y


def check(got, want, z, y):
    bound = 10 * z.shape[1] * EPS * np.linalg.cond(z) * np.max(np.abs(y))
    err = np.max(np.abs(got - want), axis=(1, 2))
    assert np.all(err <= bound), f"worst line: error {err.max():.2e}, bound there {bound[np.argmax(err / bound)]:.2e}"


@pytest.fixture
def three():
    return {"A": modal(FREQ, 7, 1, 0), "B": modal(FREQ, 6, 2, 100), "C": modal(FREQ, 5, 3, 200)}


def test_three_bodies_shared_contact_dof_mixed_signs_and_order(three):
    # interface 1: A{5x,2x,7x} - B{103x,101x,106x} spring (full 3x3 joint matrix, A-side labels
    # in another order: reordered by label); interface 2: C{201x,204x} - A{2x,3x} rigid, so A:2x
    # takes part in two interfaces and A is on side a once and side b once.
    rng = np.random.default_rng(7)
    kj = np.diag([3e4, 5e4, 8e4]) + 1e3 * rng.standard_normal((3, 3))
    kj = 0.5 * (kj + kj.T)
    hj = np.linalg.inv(kj + 1j * 2 * np.pi * FREQ[:, None, None] * 0.02 * kj)
    a1 = ["5x", "2x", "7x"]
    perm = [1, 2, 0]  # the joint FRF lists the same DOFs in another order
    joint = FRF(FREQ, hj[:, perm][:, :, perm], [a1[i] for i in perm], [a1[i] for i in perm])
    ifaces = [
        Interface("A", a1, "B", ["103x", "101x", "106x"], joint),
        Interface("C", ["201x", "204x"], "A", ["2x", "3x"]),
    ]
    outputs = [("B", "105x"), ("A", "2x"), ("C", "203x"), ("A", "1x")]
    inputs = [("C", "201x"), ("A", "7x"), ("B", "101x")]
    got = couple(three, ifaces, outputs, inputs)
    pairs = [("A", a, "B", b) for a, b in zip(a1, ["103x", "101x", "106x"])]
    pairs += [("C", c, "A", a) for c, a in zip(["201x", "204x"], ["2x", "3x"])]
    joints = np.zeros((FREQ.size, 5, 5), dtype=complex)
    joints[:, :3, :3] = hj
    want, z, y = textbook(three, pairs, joints, outputs, inputs)
    check(got.values, want, z, y)
    assert got.outputs == tuple(Dof.parse(d) for _, d in outputs)
    assert got.inputs == tuple(Dof.parse(d) for _, d in inputs)
    assert not got.values.flags.writeable


def test_joint_body_and_array_joint_equal_textbook(three):
    # a joint body J between A and B (two rigid interfaces in the textbook), and a constant
    # (n, n) array joint between B and C
    body = modal(FREQ, 4, 9, 300)
    ifaces = [
        Interface("A", ["6x", "4x"], "B", ["102x", "104x"], JointSubstructure(body, ["301x", "302x"], ["303x", "304x"])),
        Interface("B", ["105x"], "C", ["202x"], np.array([[1.0 / 7e4]])),
    ]
    outputs = [("A", "1x"), ("C", "205x")]
    got = couple(three, ifaces, outputs)
    subs = dict(three, J=body)
    pairs = [("A", "6x", "J", "301x"), ("A", "4x", "J", "302x"), ("J", "303x", "B", "102x"),
             ("J", "304x", "B", "104x"), ("B", "105x", "C", "202x")]
    joints = np.zeros((FREQ.size, 5, 5), dtype=complex)
    joints[:, 4, 4] = 1.0 / 7e4
    want, z, y = textbook(subs, pairs, joints, outputs, outputs)
    check(got.values, want, z, y)


def test_substructure_given_as_columns_uses_reciprocity_entry_by_entry(three):
    # A measured as two columns only (inputs 3x and 6x): every entry couple() needs is there
    # directly or by reciprocity, although the full square over A's DOFs is not.
    a = three["A"]
    cols = a.select(None, ["3x", "6x"])
    joint = spring_damper_joint(FREQ, 4e4, 2.0, ["3x"])
    ifaces = [Interface("A", ["3x"], "B", ["102x"], joint)]
    got = couple({"A": cols, "B": three["B"]}, ifaces, [("A", "6x"), ("B", "104x")], [("A", "3x"), ("B", "101x")])
    ref = couple({"A": a, "B": three["B"]}, ifaces, [("A", "6x"), ("B", "104x")], [("A", "3x"), ("B", "101x")])
    assert np.array_equal(got.values, ref.values)  # the same numbers, gathered from other places
    want, z, y = textbook({"A": a, "B": three["B"]}, [("A", "3x", "B", "102x")], joint.values,
                          [("A", "6x"), ("B", "104x")], [("A", "3x"), ("B", "101x")])
    check(got.values, want, z, y)


def test_frf_block_and_select_equal_two_step_indexing():
    f = modal(FREQ, 9, 4, 0)
    rng = np.random.default_rng(3)
    for _ in range(5):
        oi = rng.permutation(9)[: rng.integers(1, 9)]
        ii = rng.permutation(9)[: rng.integers(1, 9)]
        outs, ins = [f.outputs[i] for i in oi], [f.inputs[i] for i in ii]
        want = np.asarray(f.values)[:, oi][:, :, ii]
        block = f.block(outs, ins)
        assert np.array_equal(block, want) and block.flags.writeable  # a new array the caller owns
        sel = f.select(outs, ins)
        assert np.array_equal(sel.values, want) and not sel.values.flags.writeable
        assert sel.outputs == tuple(outs) and sel.inputs == tuple(ins)
        assert sel.freq is f.freq and not sel.freq.flags.writeable
