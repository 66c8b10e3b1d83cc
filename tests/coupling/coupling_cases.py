"""Validation structures shared by the coupling tests (thesis ch. 5 and 6)."""

import numpy as np

from jointdb.coupling._frames import FrameSection, block_frame, frame_element, grillage, merge
from jointdb.coupling._matrices import add_spring, receptance_from_matrices
from jointdb.frf import Dof

TABLE_5_1_K = (4e6, 9e6, 10e6, 7e6)
TABLE_5_1_C = (80.0, 100.0, 50.0, 90.0)
DIRS6 = ("x", "y", "z", "rx", "ry", "rz")


def _dofs(nodes, direction):
    return [Dof(n, direction) for n in nodes]


def plates(freq, plate_a="A1", joint="springs", eta=0.01):
    """Two grillage plates joined at four bolts (thesis §5.2).

    Plate A: 0.30 × 0.20 m grillage, 4 × 4 cells, members 12 mm (A1) or 15 mm (A2) square;
    plate B: 0.15 × 0.10 m, 2 × 2 cells, 10 mm members, 20 mm above A, its corners over
    A's interior nodes 7, 9, 17, 19 (the bolts). joint = "springs" (z springs of Table 5.1)
    or "beams" (short 3-D frame elements: full 6-DOF bolts with the table's axial stiffness).
    Measured: z at A's corners and edge midpoints (6 internal points).
    """
    sec_a = FrameSection.rectangle(*((0.012, 0.012) if plate_a == "A1" else (0.015, 0.015)))
    sec_b = FrameSection.rectangle(0.010, 0.010)
    A = grillage(0.30, 0.20, 4, 4, sec_a, first_node=1)
    B = grillage(0.15, 0.10, 2, 2, sec_b, first_node=101, z=0.02)
    B = type(B)(B.K, B.M, B.nodes, B.coords + np.array([0.075, 0.05, 0.0]))
    a_bolts = [7, 9, 17, 19]
    b_bolts = [101, 103, 107, 109]
    internal = [1, 5, 21, 25, 3, 13]
    K, M, labels = merge(A, B)
    K = K * (1 + 1j * eta)
    C = np.zeros_like(M)
    idx = {d: i for i, d in enumerate(labels)}
    for (na, nb, k, c) in zip(a_bolts, b_bolts, TABLE_5_1_K, TABLE_5_1_C):
        pa = A.coords[A.nodes.index(na)]
        pb = B.coords[B.nodes.index(nb)]
        assert np.allclose(pa[:2], pb[:2])
        if joint == "springs":
            add_spring(K, C, idx[Dof(na, "z")], idx[Dof(nb, "z")], k, c)
        elif joint == "beams":
            ke, me = frame_element(pa, pb, FrameSection.rectangle(0.006, 0.006))
            ke = ke * (k / (200e9 * 0.006**2 / 0.02))  # axial stiffness = table value
            dofs = [idx[Dof(na, d)] for d in DIRS6] + [idx[Dof(nb, d)] for d in DIRS6]
            ix = np.ix_(dofs, dofs)
            K[ix] += ke * (1 + 1j * eta)
            M[ix] += me
            for d, cc in ((Dof(na, "z"), c), (Dof(nb, "z"), c)):
                C[idx[d], idx[d]] += cc
            C[idx[Dof(na, "z")], idx[Dof(nb, "z")]] -= c
            C[idx[Dof(nb, "z")], idx[Dof(na, "z")]] -= c
    return dict(A=A, B=B, K=K, M=M, C=C, labels=labels, a_bolts=a_bolts, b_bolts=b_bolts, internal=internal,
                eta=eta)


def plate_frfs(freq, case):
    A, B = case["A"], case["B"]
    eta = case["eta"]
    fa = receptance_from_matrices(freq, A.K * (1 + 1j * eta), A.M, A.labels,
                                  outputs=_dofs(case["internal"] + case["a_bolts"], "z"),
                                  inputs=_dofs(case["internal"] + case["a_bolts"], "z"))
    fb = receptance_from_matrices(freq, B.K * (1 + 1j * eta), B.M, B.labels,
                                  outputs=_dofs(case["b_bolts"], "z"), inputs=_dofs(case["b_bolts"], "z"))
    g = receptance_from_matrices(freq, case["K"], case["M"], case["labels"], case["C"],
                                 outputs=_dofs(case["internal"], "z"), inputs=_dofs(case["internal"], "z"))
    return fa, fb, g




def blocks(freq, eta=0.02, joint_section=(0.008, 0.008), member=0.03):
    """Two 3-D box-frame bodies joined by a joint body with inertia (thesis §6.2).

    A: 0.10 m cube at the origin (nodes 1..12); B: 0.10 m cube above it (nodes 101..112);
    joint: one frame element (steel, 20×20 mm, 50 mm) from A's top corner node 7 to B's
    bottom corner node 103 — a 2 × 6-DOF joint with mass. Measured candidates: x, y at
    three points per body and z at three points on A.
    """
    sec = FrameSection.rectangle(member, member)
    A = block_frame((0.1, 0.1, 0.1), sec, first_node=1)
    B = block_frame((0.1, 0.1, 0.1), sec, first_node=101, origin=(0.0, 0.0, 0.15))
    a_node, b_node = 7, 103  # A corner (a, b, c) ; B corner (a, b, 0)+origin
    assert np.allclose(A.coords[A.nodes.index(a_node)] + [0, 0, 0.05], B.coords[B.nodes.index(b_node)])
    kj, mj = frame_element(A.coords[A.nodes.index(a_node)], B.coords[B.nodes.index(b_node)],
                           FrameSection.rectangle(*joint_section))
    K, M, labels = merge(A, B)
    K = K * (1 + 1j * eta)
    idx = {d: i for i, d in enumerate(labels)}
    jd = [idx[Dof(a_node, d)] for d in DIRS6] + [idx[Dof(b_node, d)] for d in DIRS6]
    K[np.ix_(jd, jd)] += kj * (1 + 1j * eta)
    M[np.ix_(jd, jd)] += mj
    a_dofs = [Dof(a_node, d) for d in DIRS6]
    b_dofs = [Dof(b_node, d) for d in DIRS6]
    pts_a, pts_b = [1, 3, 10], [105, 107, 110]
    m12 = [("A", Dof(n, d)) for n in pts_a for d in "xy"] + [("B", Dof(n, d)) for n in pts_b for d in "xy"]
    m15 = m12 + [("A", Dof(n, "z")) for n in pts_a]
    # joint body's free receptance on its own labels (nodes 7 and 103 re-used as its end labels)
    jl = a_dofs + b_dofs
    joint_true = receptance_from_matrices(freq, kj * (1 + 1j * eta), mj, jl)
    subs = {}
    for name, body, meas in (("A", A, pts_a), ("B", B, pts_b)):
        want = [Dof(n, d) for n in meas for d in "xyz"] + (a_dofs if name == "A" else b_dofs)
        subs[name] = receptance_from_matrices(freq, body.K * (1 + 1j * eta), body.M, body.labels,
                                              outputs=want, inputs=want)
    all_meas = [d for _, d in m15] + [Dof(n, "z") for n in pts_b]
    g = receptance_from_matrices(freq, K, M, labels, outputs=all_meas, inputs=all_meas)
    return dict(subs=subs, G=g, a_dofs=a_dofs, b_dofs=b_dofs, m12=m12, m15=m15, joint_true=joint_true)


def add_noise(frf, level, seed):
    """Relative complex Gaussian noise on every entry (level = 0.01 for 1 %)."""
    rng = np.random.default_rng(seed)
    z = (rng.standard_normal(frf.values.shape) + 1j * rng.standard_normal(frf.values.shape)) / np.sqrt(2)
    return frf.replace(values=frf.values * (1 + level * z))
