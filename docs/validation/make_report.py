#!/usr/bin/env python
"""Make the coupling/identification validation report: docs/validation/coupling.md + PNGs + JSON.

Every number in the report is computed here, from scratch, by the library
(jointdb.coupling, jointdb.fe) against independent references (monolithic FE
models, the exact joints used to make the synthetic data). The validation
structures of thesis ch. 5 and 6 are the ones the tests use
(tests/coupling/coupling_cases.py).

Usage: .venv/bin/python docs/validation/make_report.py [--out docs/validation]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests" / "coupling"))

import matplotlib  # noqa: E402

matplotlib.use("Agg", force=True)
import matplotlib.pyplot as plt  # noqa: E402
from coupling_cases import TABLE_5_1_C, TABLE_5_1_K, add_noise, blocks, plate_frfs, plates  # noqa: E402

from jointdb.coupling import (  # noqa: E402
    Interface,
    JointSubstructure,
    couple,
    equivalent_stiffness_damping,
    fit_constant_kc,
    identify_joint_matrix,
    identify_n_point_joints,
    identify_planar_joint,
    rotations_by_extension,
    rotations_by_finite_difference,
    spring_damper_joint,
)
from jointdb.coupling._frames import FrameSection, frame_element  # noqa: E402
from jointdb.coupling._matrices import (  # noqa: E402
    add_spring,
    merge_matrices,
    model_matrices,
    receptance_from_matrices,
)
from jointdb.fe import BeamModel, Clamp, HystereticDamping, NamedPoint, Segment  # noqa: E402
from jointdb.frf import Dof  # noqa: E402

R: dict = {}
LINES: list[str] = []


def say(text: str = "") -> None:
    LINES.append(text)


def rel_max(a, b):
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


def mean_dev(pred, truth):
    return float(np.mean(np.abs(pred - truth) / np.abs(truth)))


# ---------------------------------------------------------------- 1. forward coupling
def forward(out: Path) -> None:
    f = np.linspace(10.0, 4000.0, 400)
    eta = HystereticDamping(0.01)

    def m(length, d, pts, clamp=None):
        ing = (eta,) + ((Clamp(clamp),) if clamp is not None else ())
        return BeamModel(segments=(Segment(length, d),), points=tuple(NamedPoint(*p) for p in pts),
                         ingredients=ing, max_element_length=0.01)

    A = m(0.20, 0.03, [("end", 0.2, 3), ("mid", 0.1, 4)], clamp=0.0)
    B = m(0.10, 0.03, [("start", 0.0, 2), ("tip", 0.1, 1)])
    joined = BeamModel(segments=(Segment(0.20, 0.03), Segment(0.10, 0.03)),
                       points=(NamedPoint("mid", 0.1, 4), NamedPoint("tip", 0.3, 1)),
                       ingredients=(eta, Clamp(0.0)), max_element_length=0.01)
    fa, fb = A.frf(f), B.frf(f)
    g = couple({"A": fa, "B": fb}, [Interface("A", ["3x", "3ry"], "B", ["2x", "2ry"])],
               [("B", "1x"), ("A", "4x")])
    ref = joined.frf(f).select(["1x", "4x"], ["1x", "4x"])
    rigid = rel_max(g.values, ref.values)
    # springs
    B2 = m(0.12, 0.02, [("start", 0.0, 2), ("tip", 0.12, 1)])
    K, M, C, labels = merge_matrices(model_matrices(A, 1000), model_matrices(B2, 2000))
    idx = {d: i for i, d in enumerate(labels)}
    add_spring(K, C, idx[Dof(3, "x")], idx[Dof(2, "x")], 2e6, 100.0)
    add_spring(K, C, idx[Dof(3, "ry")], idx[Dof(2, "ry")], 8e4, 80.0)
    ref_s = receptance_from_matrices(f, K, M, labels, C, outputs=["1x"], inputs=["1x"])
    gs = couple({"A": fa, "B": B2.frf(f)}, [Interface("A", ["3x", "3ry"], "B", ["2x", "2ry"],
                                                      spring_damper_joint(f, [2e6, 8e4], [100.0, 80.0], ["3x", "3ry"]))],
                [("B", "1x")])
    springs = rel_max(gs.values, ref_s.values)
    # three bodies, two joints (rigid + springs)
    A3 = m(0.15, 0.04, [("end", 0.15, 3)], clamp=0.0)
    B3 = m(0.08, 0.03, [("start", 0.0, 4), ("end", 0.08, 5)])
    C3 = m(0.06, 0.012, [("start", 0.0, 6), ("tip", 0.06, 1)])
    K, M, C, labels = merge_matrices(model_matrices(A3, 1000), model_matrices(B3, 2000), model_matrices(C3, 3000))
    idx = {d: i for i, d in enumerate(labels)}
    add_spring(K, C, idx[Dof(5, "x")], idx[Dof(6, "x")], 5e6, 60.0)
    add_spring(K, C, idx[Dof(5, "ry")], idx[Dof(6, "ry")], 2e5, 20.0)
    keep = [d for d in labels if d.node != 4]
    T = np.zeros((len(labels), len(keep)))
    pos = {d: i for i, d in enumerate(keep)}
    for i, d in enumerate(labels):
        T[i, pos[Dof(3, d.direction) if d.node == 4 else d]] = 1.0
    ref3 = receptance_from_matrices(f, T.T @ K @ T, T.T @ M @ T, keep, T.T @ C @ T, outputs=["1x"], inputs=["1x"])
    g3 = couple({"A": A3.frf(f), "B": B3.frf(f), "C": C3.frf(f)},
                [Interface("A", ["3x", "3ry"], "B", ["4x", "4ry"]),
                 Interface("B", ["5x", "5ry"], "C", ["6x", "6ry"],
                           spring_damper_joint(f, [5e6, 2e5], [60.0, 20.0], ["5x", "5ry"]))], [("C", "1x")])
    three = rel_max(g3.values, ref3.values)
    # joint body with inertia (§1b)
    J = m(0.05, 0.02, [("a", 0.0, 7), ("b", 0.05, 8)])
    joinedj = BeamModel(segments=(Segment(0.20, 0.03), Segment(0.05, 0.02), Segment(0.10, 0.03)),
                        points=(NamedPoint("tip", 0.35, 1),), ingredients=(eta, Clamp(0.0)), max_element_length=0.01)
    gj = couple({"A": fa, "B": fb}, [Interface("A", ["3x", "3ry"], "B", ["2x", "2ry"],
                                               JointSubstructure(J.frf(f), ["7x", "7ry"], ["8x", "8ry"]))], [("B", "1x")])
    body = rel_max(gj.values, joinedj.frf(f).select(["1x"], ["1x"]).values)
    R["forward"] = {"rigid_two_beams": rigid, "springs_two_beams": springs, "three_bodies_two_joints": three,
                    "joint_body_with_inertia": body}
    say("## 1. Forward coupling vs monolithic FE models (docs/theory.md §1)")
    say()
    say("Timoshenko beams from `jointdb.fe` (10 mm elements, η = 0.01), 400 lines 10–4000 Hz. "
        "References: one FE model of the joined beam, or the merged FE matrices with the springs added.")
    say()
    say("| case | max relative deviation (over lines, entries) |")
    say("|---|---|")
    say(f"| two beams, rigid joint, vs single FE model of the joined beam | {rigid:.1e} |")
    say(f"| two beams, springs 2e6 N/m / 8e4 N·m/rad + dampers, vs FE with the springs | {springs:.1e} |")
    say(f"| three bodies, two joints (rigid + springs) vs merged FE | {three:.1e} |")
    say(f"| joint segment as a body with inertia (§1b) vs single FE model | {body:.1e} |")
    say()


# ---------------------------------------------------------------- 2. thesis §4.3
def thesis_43(out: Path) -> None:
    sys.path.insert(0, str(ROOT / "tests" / "coupling"))
    from test_coupling_planar import CR, CX, KR, KX, build_case  # the Table 4.1 structure of the tests

    f = np.linspace(5.0, 3000.0, 600)
    A, B, G = build_case(freq=f)
    res = identify_planar_joint(G, A, 3, B, 2, 1)
    w = 2 * np.pi * f
    et = np.abs(res.joint.entry("3x", "3x") * (KX + 1j * w * CX) - 1)
    er = np.abs(res.joint.entry("3ry", "3ry") * (KR + 1j * w * CR) - 1)
    k, c = equivalent_stiffness_damping(res.joint)
    R["thesis_4_3_first"] = {"max_rel_error_translational": float(et.max()), "max_rel_error_rotational": float(er.max()),
                             "lines": int(f.size), "flagged_lines": int(res.unreliable.sum())}
    fig, ax = plt.subplots(2, 2, figsize=(10, 6), sharex=True)
    for i, (kk, cc, lab) in enumerate(((KX, CX, "translational"), (KR, CR, "rotational"))):
        ax[i, 0].plot(f, k[:, i], label="identified")
        ax[i, 0].axhline(kk, ls="--", color="k", label="Table 4.1")
        ax[i, 1].plot(f, c[:, i], label="identified")
        ax[i, 1].axhline(cc, ls="--", color="k", label="Table 4.1")
        ax[i, 0].set_ylabel(f"k {lab}")
        ax[i, 1].set_ylabel(f"c {lab}")
        ax[i, 0].legend(fontsize=8)
    for a in ax[-1]:
        a.set_xlabel("frequency [Hz]")
    fig.suptitle("Thesis §4.3 first simulation: identified joint vs Table 4.1")
    fig.tight_layout()
    fig.savefig(out / "thesis43_table41.png", dpi=100)
    plt.close(fig)

    # second simulation: continuous joint segment, predict a shorter B
    f2 = np.linspace(5.0, 3000.0, 300)
    eta = HystereticDamping(0.2)

    def assembly(lb):
        return BeamModel(segments=(Segment(0.30, 0.03), Segment(0.05, 0.02), Segment(lb, 0.03)),
                         points=(NamedPoint("tip", 0.35 + lb, 1), NamedPoint("c", 0.35, 2)),
                         ingredients=(eta, Clamp(0.0)), max_element_length=0.01)

    def tool(lb):
        return BeamModel(segments=(Segment(lb, 0.03),), points=(NamedPoint("c", 0.0, 2), NamedPoint("tip", lb, 1)),
                         ingredients=(eta,), max_element_length=0.01)

    Am = BeamModel(segments=(Segment(0.30, 0.03),), points=(NamedPoint("end", 0.30, 3),),
                   ingredients=(eta, Clamp(0.0)), max_element_length=0.01).frf(f2)
    res2 = identify_planar_joint(assembly(0.20).frf(f2), Am, 3, tool(0.20).frf(f2), 2, 1)
    truth = assembly(0.12).frf(f2).entry("1x", "1x")
    fb = tool(0.12).frf(f2)
    iface = lambda j: [Interface("A", ["3x", "3ry"], "B", ["2x", "2ry"], j)]  # noqa: E731
    pred = couple({"A": Am, "B": fb}, iface(res2.joint), [("B", "1x")]).values[:, 0, 0]
    rig = couple({"A": Am, "B": fb}, iface(None), [("B", "1x")]).values[:, 0, 0]
    R["thesis_4_3_second"] = {"identified_mean_dev": mean_dev(pred, truth), "rigid_mean_dev": mean_dev(rig, truth),
                              "non_passive_lines": int(res2.flags["non_passive"].sum()), "lines": int(f2.size)}
    fig, ax = plt.subplots(figsize=(8, 4.5))
    ax.semilogy(f2, np.abs(truth), "k", lw=2, label="FE model of case B (reference)")
    ax.semilogy(f2, np.abs(pred), "--", label="RC with joint identified on case A")
    ax.semilogy(f2, np.abs(rig), ":", label="RC with rigid joint")
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("|G11| [m/N]")
    ax.legend()
    ax.set_title("Thesis §4.3 second simulation (cf. thesis Fig. 4.7)")
    fig.tight_layout()
    fig.savefig(out / "thesis43_caseB.png", dpi=100)
    plt.close(fig)
    s1, s2 = R["thesis_4_3_first"], R["thesis_4_3_second"]
    say("## 2. Thesis §4.3: planar spring–damper joint (docs/theory.md §2a)")
    say()
    say("**First simulation** (clamped Euler–Bernoulli beam A 0.30 m Ø30, free tool B 0.15 m Ø16, "
        "joint of Table 4.1: 2e6 N/m, 100 N·s/m, 8e4 N·m/rad, 80 N·m·s/rad; 600 lines 5–3000 Hz; "
        "inputs: the two translational assembly FRFs G11, G12):")
    say()
    say(f"- max relative error over all {s1['lines']} lines: translational {s1['max_rel_error_translational']:.1e}, "
        f"rotational {s1['max_rel_error_rotational']:.1e} (requirement ≤ 1e-8); flagged lines: {s1['flagged_lines']}.")
    say("- Root choice: of the two roots of the quadratic, the spurious one fails to reproduce the measurement "
        "when coupled back (and is non-passive on > 90 % of lines); passivity and continuity decide the rest.")
    say()
    say("![Table 4.1 joint](thesis43_table41.png)")
    say()
    say("**Second simulation** (A 0.30 m Ø30 clamped; joint: a continuous segment 50 mm Ø20, aspect ratio 2.5, "
        "1/6 of A; B 0.20 m Ø30 for identification, 0.12 m for validation; Timoshenko, hysteretic η = 0.2 ≈ the "
        "thesis's damping ratio 0.1; 300 lines 5–3000 Hz). Mean relative deviation of the predicted tip FRF of case B:")
    say()
    say("| joint | mean relative deviation | thesis |")
    say("|---|---|---|")
    say(f"| identified on case A (planar IRC) | {100 * s2['identified_mean_dev']:.1f} % | 5 % |")
    say(f"| rigid | {100 * s2['rigid_mean_dev']:.0f} % | 109 % |")
    say()
    say(f"The identified equivalent spring–damper is non-passive on {s2['non_passive_lines']} of {s2['lines']} lines "
        "(flagged): the segment has inertia that a massless joint can only mimic.")
    say()
    say("![case B prediction](thesis43_caseB.png)")
    say()


# ---------------------------------------------------------------- 3. thesis §5.2
def thesis_52(out: Path) -> None:
    f = np.linspace(20.0, 2000.0, 200)
    case = plates(f)
    fa, fb, g = plate_frfs(f, case)
    z = lambda nodes: [Dof(n, "z") for n in nodes]  # noqa: E731
    res = identify_n_point_joints(g, fa, z(case["internal"]), z(case["a_bolts"]), fb, z(case["b_bolts"]))
    k, c = equivalent_stiffness_damping(res.joint)
    ek = float(np.max(np.abs(k / np.array(TABLE_5_1_K) - 1)))
    ec = float(np.max(np.abs(c / np.array(TABLE_5_1_C) - 1)))
    fit = fit_constant_kc(res.joint)
    R["thesis_5_2_springs"] = {"max_rel_error_k": ek, "max_rel_error_c": ec, "fit_k": fit.k.tolist(),
                               "fit_c": fit.c.tolist(), "off_diagonal_median": float(np.median(res.extra["off_diagonal"]))}
    # beam-element bolts: identify z-spring model on A1, predict A2
    b1 = plates(f, "A1", joint="beams")
    fa1, fb1, g1 = plate_frfs(f, b1)
    r1 = identify_n_point_joints(g1, fa1, z(b1["internal"]), z(b1["a_bolts"]), fb1, z(b1["b_bolts"]))
    b2 = plates(f, "A2", joint="beams")
    fa2, fb2, g2 = plate_frfs(f, b2)
    outs = [("A", d) for d in z(b2["internal"])]
    subs = {"A": fa2, "B": fb2}
    pred = couple(subs, [Interface("A", z(b2["a_bolts"]), "B", z(b2["b_bolts"]), r1.joint)], outs).values
    rig = couple(subs, [Interface("A", z(b2["a_bolts"]), "B", z(b2["b_bolts"]))], outs).values
    tv = g2.values
    dev_id, dev_rig = mean_dev(pred, tv), mean_dev(rig, tv)
    # where the z-spring model breaks down: modes of the A1 assembly and the bolts' lateral strain energy
    Kr, Mr = b1["K"].real, b1["M"]
    lam, phi = __import__("scipy.linalg", fromlist=["eigh"]).eigh(Kr, Mr)
    fn = np.sqrt(np.clip(lam, 0, None)) / (2 * np.pi)
    idx = {d: i for i, d in enumerate(b1["labels"])}
    rows = []
    A, B = b1["A"], b1["B"]
    for mode in np.where((fn > 1.0) & (fn < 2000.0))[0]:
        v = phi[:, mode]
        e_total = 0.5 * v @ Kr @ v
        e_bolt = e_lat = 0.0
        for na, nb, kk in zip(b1["a_bolts"], b1["b_bolts"], TABLE_5_1_K):
            ke, _ = frame_element(A.coords[A.nodes.index(na)], B.coords[B.nodes.index(nb)],
                                  FrameSection.rectangle(0.006, 0.006))
            ke = ke * (kk / (200e9 * 0.006**2 / 0.02))
            dd = [idx[Dof(na, d)] for d in ("x", "y", "z", "rx", "ry", "rz")] + \
                 [idx[Dof(nb, d)] for d in ("x", "y", "z", "rx", "ry", "rz")]
            u = v[dd]
            eb = 0.5 * u @ ke @ u
            e_ax = 0.5 * kk * (u[2] - u[8]) ** 2
            e_bolt += eb
            e_lat += eb - e_ax
        line = int(np.argmin(np.abs(f - fn[mode])))
        rows.append((float(fn[mode]), float(e_bolt / e_total), float(e_lat / max(e_bolt, 1e-300)),
                     float(r1.residual[line]), float(r1.extra["off_diagonal"][line])))
    R["thesis_5_2_beams"] = {"identified_on_A1_predict_A2_mean_dev": dev_id, "rigid_predict_A2_mean_dev": dev_rig,
                             "off_diagonal_median": float(np.median(r1.extra["off_diagonal"])),
                             "residual_median": float(np.median(r1.residual)), "modes": rows}
    fig, ax = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    ax[0].semilogy(f, r1.residual, label="relative residual of the z-spring model (A1)")
    ax[0].semilogy(f, r1.extra["off_diagonal"], label="off-diagonal residue of identified H_J")
    for fr, eb, el, _, _ in rows:
        if eb > 0.01 and el > 0.5:
            ax[0].axvline(fr, color="r", lw=0.8, alpha=0.6)
    ax[0].legend(fontsize=8)
    ax[0].set_title("z-spring model with 6-DOF beam bolts: red = modes with mostly lateral bolt deformation")
    i0 = b2["internal"][0]
    ax[1].semilogy(f, np.abs(tv[:, 0, 0]), "k", lw=2, label=f"A2 assembly FE, G({i0}z,{i0}z)")
    ax[1].semilogy(f, np.abs(pred[:, 0, 0]), "--", label="predicted, joints identified on A1")
    ax[1].semilogy(f, np.abs(rig[:, 0, 0]), ":", label="predicted, rigid z joints")
    ax[1].legend(fontsize=8)
    ax[1].set_xlabel("frequency [Hz]")
    fig.tight_layout()
    fig.savefig(out / "thesis52_plates.png", dpi=100)
    plt.close(fig)
    s = R["thesis_5_2_springs"]
    say("## 3. Thesis §5.2: four bolts between two plates (docs/theory.md §2b)")
    say()
    say("Plates as grillages of 3-D frame elements (A: 0.30 × 0.20 m, 4 × 4 cells; B: 0.15 × 0.10 m, 2 × 2 cells), "
        "four z-springs of Table 5.1 (k = 4, 9, 10, 7 × 10⁶ N/m, c = 80, 100, 50, 90 N·s/m), z-receptances measured "
        "at six points of A (least squares, m = 6 > n = 4); 200 lines 20–2000 Hz.")
    say()
    say(f"- Springs recovered: max relative error of k(ω) {s['max_rel_error_k']:.1e}, of c(ω) {s['max_rel_error_c']:.1e}; "
        f"constant fit k = {', '.join(f'{v:.4g}' for v in s['fit_k'])} N/m, c = {', '.join(f'{v:.4g}' for v in s['fit_c'])} N·s/m; "
        f"off-diagonal residue (median) {s['off_diagonal_median']:.1e}.")
    b = R["thesis_5_2_beams"]
    say(f"- With 6-DOF beam-element bolts (same axial stiffness), the z-spring model identified on plate A1 predicts "
        f"the assembly with plate A2 (15 mm members instead of 12 mm) with mean relative deviation "
        f"{100 * b['identified_on_A1_predict_A2_mean_dev']:.1f} % vs {100 * b['rigid_predict_A2_mean_dev']:.1f} % for "
        f"rigid z joints. The model's misfit shows in the off-diagonal residue (median "
        f"{b['off_diagonal_median']:.2g}) and the residual (median {b['residual_median']:.2g}).")
    say("- Where it breaks down: modes of the A1 assembly below 2 kHz, the share of strain energy in the bolts and the "
        "lateral (non-axial) share of that, with the z-spring model's residual and off-diagonal residue at that line:")
    say()
    say("| mode [Hz] | bolt energy / total | lateral share of bolt energy | residual | off-diagonal |")
    say("|---|---|---|---|---|")
    for fr, eb, el, res_, off in rows:
        say(f"| {fr:.1f} | {eb:.3f} | {el:.2f} | {res_:.2g} | {off:.2g} |")
    say()
    say("Reading: the modes in which the bolts deform mostly laterally (shear/bending of the bolt, lateral share "
        "near 1, large bolt energy) are where the single-z-spring model fails outright (residual ~0.9): a z-spring "
        "cannot carry the in-plane force. The residual is also large at several axially dominated modes, because "
        "the beam bolts transmit moments (plate rotations are coupled through bolt bending) and carry mass, which "
        "the massless z-only model ignores; the off-diagonal residue of the identified H_J flags the misfit at "
        "every such line.")
    say()
    say("![plates](thesis52_plates.png)")
    say()


# ---------------------------------------------------------------- 4. thesis §6.2
def thesis_62(out: Path) -> None:
    f = np.linspace(150.0, 3000.0, 96)
    b = blocks(f)
    zt = np.linalg.inv(b["joint_true"].values)

    def zerr(res):
        return np.linalg.norm(np.linalg.inv(res.joint.values) - zt, axis=(1, 2)) / np.linalg.norm(zt, axis=(1, 2))

    outs = [("B", Dof(105, "z")), ("B", Dof(110, "z"))]
    truth = b["G"].select([d for _, d in outs], [d for _, d in outs]).values

    def pred_err(res):
        p = couple(b["subs"], [Interface("A", b["a_dofs"], "B", b["b_dofs"], res.joint_substructure())], outs).values
        return float(np.median(np.linalg.norm(p - truth, axis=(1, 2)) / np.linalg.norm(truth, axis=(1, 2))))

    rigid = couple(b["subs"], [Interface("A", b["a_dofs"], "B", b["b_dofs"])], outs).values
    rigid_err = float(np.median(np.linalg.norm(rigid - truth, axis=(1, 2)) / np.linalg.norm(truth, axis=(1, 2))))
    table = []
    exact = {}
    for which in ("m12", "m15"):
        r0 = identify_joint_matrix(b["G"], b["subs"], b[which], "A", b["a_dofs"], "B", b["b_dofs"])
        exact[which] = (float(np.median(zerr(r0))), float(np.max(zerr(r0))), float(np.median(r0.condition)),
                        float(np.max(r0.condition)))
        for label, kw in (("plain least squares", {}), ("Savitzky–Golay 4th order, 11 lines", {"smoothing": 11}),
                          ("truncated SVD, 3e-2", {"regularisation": "tsvd:3e-2"}),
                          ("Tikhonov, 3e-2", {"regularisation": "tikhonov:3e-2"}),
                          ("Tikhonov, 1e-1", {"regularisation": "tikhonov:1e-1"})):
            ez, ep = [], []
            for seed in range(5):
                r = identify_joint_matrix(add_noise(b["G"], 0.01, seed), b["subs"], b[which], "A", b["a_dofs"],
                                          "B", b["b_dofs"], **kw)
                ez.append(float(np.median(zerr(r))))
                try:
                    ep.append(pred_err(r))
                except Exception:  # noqa: BLE001 - a singular joint body (e.g. after truncation) counts as failure
                    ep.append(float("inf"))
            table.append((which, label, float(np.mean(ez)), float(np.median(ep))))
    R["thesis_6_2"] = {"noise_free": exact, "noisy_1pct": table, "rigid_prediction_error": rigid_err}
    r12 = identify_joint_matrix(add_noise(b["G"], 0.01, 0), b["subs"], b["m12"], "A", b["a_dofs"], "B", b["b_dofs"])
    r15 = identify_joint_matrix(add_noise(b["G"], 0.01, 0), b["subs"], b["m15"], "A", b["a_dofs"], "B", b["b_dofs"])
    r15t = identify_joint_matrix(add_noise(b["G"], 0.01, 0), b["subs"], b["m15"], "A", b["a_dofs"], "B", b["b_dofs"],
                                 regularisation="tikhonov:3e-2")
    fig, ax = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    ax[0].semilogy(f, r12.condition, label="L = 12")
    ax[0].semilogy(f, r15.condition, "--", label="L = 15")
    ax[0].set_ylabel("cond(H_IC)·cond(H_CI)")
    ax[0].legend()
    ax[1].semilogy(f, zerr(r12), label="L = 12, least squares")
    ax[1].semilogy(f, zerr(r15), label="L = 15, least squares")
    ax[1].semilogy(f, zerr(r15t), label="L = 15, Tikhonov 3e-2")
    ax[1].set_ylabel("relative error of joint dynamic stiffness")
    ax[1].set_xlabel("frequency [Hz]")
    ax[1].legend(fontsize=8)
    ax[0].set_title("Thesis §6.2: 2 × 6-DOF joint with inertia, 1 % noise (seed 0)")
    fig.tight_layout()
    fig.savefig(out / "thesis62_blocks.png", dpi=100)
    plt.close(fig)
    say("## 4. Thesis §6.2: 2 × 6-DOF joint with inertia between two 3-D bodies (docs/theory.md §2c)")
    say()
    say("Two 0.1 m box-frame bodies (3-D frame elements, 30 mm members), joined by a joint body with mass: one "
        "steel frame element 8 × 8 mm, 50 mm long, from a corner of A to a corner of B (nc = 12). Measured: x, y at "
        "three points on each body (L = 12), plus z at three points on A (L = 15, as in the thesis). "
        "96 lines 150–3000 Hz; η = 0.02. Errors are those of the joint's dynamic stiffness Z_J = (H^J)⁻¹ "
        "(the joint's free receptance H^J itself is dominated by its rigid-body terms, which the assembly barely "
        "sees); prediction error = median relative error of two unmeasured assembly FRFs (z on B) re-coupled "
        "with the identified joint body.")
    say()
    say("| L | noise-free Z_J error median / max | condition number median / max |")
    say("|---|---|---|")
    for which, (emed, emax, cmed, cmax) in exact.items():
        say(f"| {which[1:]} | {emed:.1e} / {emax:.1e} | {cmed:.3g} / {cmax:.3g} |")
    say()
    say("With 1 % complex Gaussian noise on every measured FRF (mean over 5 seeds of the median over lines):")
    say()
    say("| L | solver | Z_J error | prediction error |")
    say("|---|---|---|---|")
    for which, label, ez, ep in table:
        say(f"| {which[1:]} | {label} | {ez:.3f} | {ep:.3g} |")
    say(f"| – | rigid joint (for scale) | – | {rigid_err:.3g} |")
    say()
    say("Reading: noise-free, the joint is recovered to round-off wherever the system is well conditioned (the "
        "largest errors sit at the lowest lines, where both bodies move almost rigidly and the condition number "
        "peaks). The condition number of the block-diagonal H_IC is set by B's block here, so adding z on A "
        "(L = 15) leaves it unchanged, unlike in the thesis; still, with 1 % noise, 15 DOFs lower the joint "
        "error relative to 12 (the thesis's finding: redundancy averages noise). Because H_IC is block diagonal, "
        "the B–B block of P = (H_CC + H^J)⁻¹, which alone sets the predicted z-FRFs on B, depends only on the "
        "B-side measurements: the prediction errors for L = 12 and 15 coincide. Plain least squares with noise "
        "predicts worse than a rigid joint; Tikhonov regularisation lowers both the joint error and, much more, the prediction error; "
        "truncated SVD reduces the joint error but can make the joint body singular, which ruins re-coupling. "
        "Smoothing alone helps little here because the noise is white and the FRFs are sharp.")
    say()
    say("![blocks](thesis62_blocks.png)")
    say()


# ---------------------------------------------------------------- 5. round trip and rotations
def round_trip(out: Path, tmp: Path) -> None:
    from jointdb.campaign import load_campaign
    from jointdb.campaign import couple_campaign, identify_campaign, joint_attrs
    from jointdb.io import read_frf_hdf5, write_frf_hdf5
    from jointdb.plots._coupling import save_comparison_plot, save_kc_plot

    c = load_campaign(ROOT / "fixtures" / "campaigns" / "th-steel-30nm" / "campaign.json")
    res = identify_campaign(c)
    p = tmp / "joint.h5"
    write_frf_hdf5(p, res.result.joint, joint_attrs(res))
    back = read_frf_hdf5(p)
    identical = bool(np.array_equal(back.values, res.result.joint.values))
    coupled = couple_campaign(c, p)
    rigid = couple_campaign(c, None)
    truth = json.loads((ROOT / "fixtures" / "campaigns" / "th-steel-30nm" / "truth.json").read_text())["joint"]
    rep = res.report()
    R["round_trip"] = {"hdf5_bit_identical": identical, "coupled_back_mean_dev": coupled["error_mean"],
                       "rigid_mean_dev": rigid["error_mean"], "constant_fit": rep["constant_fit"], "truth": truth,
                       "validation": rep["validation"]}
    save_kc_plot(out / "fixture_kc.png", res.result.joint, res.kc, title="fixture th-steel-30nm: identified joint",
                 flagged=res.result.unreliable)
    save_comparison_plot(out / "fixture_validation.png",
                         [("measured", res.validation["measured"]), ("predicted (identified)", res.validation["predicted"]),
                          ("rigid", res.validation["rigid"])], title="fixture: short-tool validation assembly")
    fx = {row["dof"]: row for row in rep["constant_fit"]}
    say("## 5. Identify → store → couple back (fixture campaign `th-steel-30nm`)")
    say()
    say("Measured tip FRFs (G11, G12, accelerance UFF58) come from a finer model (4 mm vs 10 mm elements) with 1 % "
        "noise; the holder's contact block is a UFF58 file, the tool a model file; the campaign also holds a "
        "shorter-tool validation measurement.")
    say()
    say(f"- Joint HDF5 file read back bit-identical: {identical}.")
    say(f"- Coupling back through the stored joint reproduces the measured G11 with mean relative deviation "
        f"{100 * coupled['error_mean']:.1f} % (the noise is 1 %; the joint was identified from Savitzky–Golay-smoothed "
        f"data) vs {100 * rigid['error_mean']:.0f} % for a rigid joint.")
    say(f"- Constant fit (median over reliable lines, 100–4000 Hz): kx = {fx['3x']['k']:.4g} N/m (true {truth['kx']:.4g}), "
        f"cx = {fx['3x']['c']:.4g} N·s/m (true {truth['cx']:.4g}), kθ = {fx['3ry']['k']:.4g} N·m/rad "
        f"(true {truth['kr']:.4g}), cθ = {fx['3ry']['c']:.4g} (true {truth['cr']:.4g}). The rotational term is "
        "poorly determined by tip translations under noise (fit error "
        f"{fx['3ry']['error']:.2f}); the translational one is good (fit error {fx['3x']['error']:.2f}).")
    v = rep["validation"]
    say(f"- Validation assembly (shorter tool): mean deviation {100 * v['identified_joint_error_mean']:.1f} % with the "
        f"identified joint vs {100 * v['rigid_joint_error_mean']:.0f} % rigid.")
    say()
    say("![fixture k, c](fixture_kc.png)")
    say()
    say("![fixture validation](fixture_validation.png)")
    say()


def rotations(out: Path) -> None:
    f = np.linspace(20.0, 3000.0, 150)
    eta = HystereticDamping(0.02)
    A = BeamModel(segments=(Segment(0.08, 0.05), Segment(0.05, 0.03)),
                  points=(NamedPoint("inner", 0.12, 4), NamedPoint("contact", 0.13, 3)),
                  ingredients=(eta, Clamp(0.0)), max_element_length=0.005)
    E = BeamModel(segments=(Segment(0.05, 0.03),),
                  points=(NamedPoint("joint", 0.0, 10), NamedPoint("mid", 0.025, 11), NamedPoint("end", 0.05, 12)),
                  ingredients=(eta,), max_element_length=0.005)
    fa, fe = A.frf(f), E.frf(f)
    g = couple({"A": fa, "E": fe}, [Interface("A", ["3x", "3ry"], "E", ["10x", "10ry"])], [("E", "11x"), ("E", "12x")])
    true = fa.select(["3x", "3ry"], ["3x", "3ry"]).values
    meas_a = fa.select(["3x", "4x"], ["3x", "4x"])
    rel = lambda a, b_: np.abs(a - b_) / np.abs(b_)  # noqa: E731
    h0, _ = rotations_by_extension(g, fe, 10, (11, 12), 3)
    fd0 = rotations_by_finite_difference(meas_a, 3, 4, 0.01)
    fd20 = rotations_by_finite_difference(meas_a, 3, 4, 0.01, method="second-order")
    rows = [("extension method", float(np.median(rel(h0.values[:, 0, 1], true[:, 0, 1]))),
             float(np.median(rel(h0.values[:, 1, 1], true[:, 1, 1])))),
            ("finite difference, first order (p = n²/h)", float(np.median(rel(fd0.values[:, 0, 1], true[:, 0, 1]))),
             float(np.median(rel(fd0.values[:, 1, 1], true[:, 1, 1])))),
            ("finite difference, second order", float(np.median(rel(fd20.values[:, 0, 1], true[:, 0, 1]))),
             float(np.median(rel(fd20.values[:, 1, 1], true[:, 1, 1]))))]
    noisy = []
    for label, fn in (("extension method", lambda s: rotations_by_extension(add_noise(g, 0.01, s), fe, 10, (11, 12), 3)[0]),
                      ("finite difference, first order", lambda s: rotations_by_finite_difference(add_noise(meas_a, 0.01, s), 3, 4, 0.01)),
                      ("finite difference, second order", lambda s: rotations_by_finite_difference(
                          add_noise(meas_a, 0.01, s), 3, 4, 0.01, method="second-order"))):
        en, ep = [], []
        for seed in range(5):
            h = fn(seed).values
            en.append(np.median(rel(h[:, 0, 1], true[:, 0, 1])))
            ep.append(np.median(rel(h[:, 1, 1], true[:, 1, 1])))
        noisy.append((label, float(np.mean(en)), float(np.mean(ep))))
    R["rotations"] = {"noise_free": rows, "noisy_1pct": noisy}
    say("## 6. Rotational receptances at a contact point (docs/theory.md §3)")
    say()
    say("Holder A: clamped stepped shaft (80 mm Ø50 + 50 mm Ø30), contact point at its end; extension E: free 50 mm "
        "Ø30 cylinder (model) rigidly attached, measured at 25 and 50 mm (G11, G12, G22); finite differences with "
        "a second point 10 mm inside A. Median relative error over 150 lines (20–3000 Hz) of n = l and p:")
    say()
    say("Noise-free, the extension method is exact and finite differences carry a truncation error. With 1 % "
        "noise the extension method estimates p better than finite differences but n worse (its 2×2 inversion "
        "amplifies noise where the two measured points move alike); both are far from the noise-free accuracy.")
    say()
    say("| method | n (noise-free) | p (noise-free) | n (1 % noise) | p (1 % noise) |")
    say("|---|---|---|---|---|")
    for (label, n0, p0), (_, nn, pn) in zip(rows, noisy):
        say(f"| {label} | {n0:.1e} | {p0:.1e} | {nn:.3f} | {pn:.3f} |")
    say()


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", type=Path, default=Path(__file__).resolve().parent)
    args = ap.parse_args(argv)
    out = args.out
    out.mkdir(parents=True, exist_ok=True)
    import tempfile

    say("# Validation report: receptance coupling and joint identification")
    say()
    say("Generated by `docs/validation/make_report.py` (run `.venv/bin/python docs/validation/make_report.py`); "
        "all numbers below are recomputed by that script. Theory: docs/theory.md §1–3; cases: thesis ch. 4–6.")
    say()
    forward(out)
    thesis_43(out)
    thesis_52(out)
    thesis_62(out)
    with tempfile.TemporaryDirectory() as tmp:
        round_trip(out, Path(tmp))
    rotations(out)
    say("## 7. Benchmarks")
    say()
    say("See `bench/bench_coupling.py` and `bench/bench_irc.py` (they print times and ratios against the textbook "
        "implementations in the same process); results of one run are in `bench_results.txt` beside this report.")
    (out / "coupling.md").write_text("\n".join(LINES) + "\n", encoding="utf-8")
    from jointdb.io._jsonable import to_jsonable

    (out / "coupling_results.json").write_text(json.dumps(to_jsonable(R), indent=2) + "\n", encoding="utf-8")
    print(f"wrote {out / 'coupling.md'}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
