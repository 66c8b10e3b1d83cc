"""Validation set for stack prediction: a structurally richer "truth" than the prediction path.

The prediction path (``jointdb.stack``) models a stack as three beams joined at
two *points*: the tool overhang (fluted section as a Kops–Vo cylinder, with
that cylinder's mass), the holder with the clamped shank as a bonded composite
section, and the spindle side as a receptance at its nose; each joint is a 2×2
receptance from the catalogue.

The truth model here is ONE finite-element model of the whole stack with:

- the tool shank **inserted** in the holder bore over the insertion length
  and held by a distributed **contact layer** (stiffness per unit length
  growing with the clamping torque as ``(T/80 N·m)^0.5``, 0.75× for a steel
  shank, loss factor 0.05) — not a point spring;
- the holder's taper **inserted** in the spindle nose over the taper length,
  held by a contact layer growing with the drawbar force as
  ``(F/20 kN)^0.35`` (HSK-A63: short stiff taper; BT40: long, 0.4× as stiff
  per length), loss factor 0.05;
- the spindle shaft on two bearing sets (springs + viscous dampers) with its
  motor rotor as a lumped mass and rotary inertia;
- the fluted section with its TRUE mass: the Kops–Vo diameter sets its bending
  stiffness, but its density is raised so its mass per length is that of a
  section with 60 % of the full circle's area (a 4-flute cutter), which the
  prediction path does not know.

Campaigns are "measured" on this truth (tip FRFs, 0.2 % noise, 6 digits):
holder–spindle campaigns (spindle measured at its nose; B = holder with a
bonded test arbor, model) and tool–holder campaigns on machines of each taper
family at its lowest and highest drawbar force (A = holder on spindle through
that machine's catalogued taper joint, B = blank test-tool overhang, model).
Stacks never used to build the catalogue are then predicted and compared with
their truth tip FRFs.

Used by ``bench/bench_stack_prediction.py`` (the report) and by
``tests/stack/test_stack_validation.py``.
"""

from __future__ import annotations

import functools
import json
import zlib
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from jointdb.fe import (BeamModel, HystereticDamping, NamedPoint, PointMass, Segment, Support,
                        get_material, model_to_dict)
from jointdb.fe._joints import Contact, Insertion
from jointdb.fe._materials import Material
from jointdb.frf import FRF, Dof
from jointdb.io import write_uff58
from jointdb.stack import attach, holder_model, stack_from_dict, tool_model

FREQ = np.arange(100.0, 5000.0 + 1e-9, 10.0)  # the campaigns' band: joints are identified only there
ETA = 0.003                     # structural loss factor of every part (truth and prediction)
CONTACT_ETA = 0.05              # loss factor of the contact layers
FLUTED_AREA = 0.60              # true section area of a fluted portion / full circle (4-flute cutter)
NOISE = 0.002
SEED = 20261123
HOLDER_NOSE, HOLDER_BODY = 0.040, 0.030
#: taper → (gauge diameter [m], inserted taper diameter [m], taper length [m], contact per length at 20 kN:
#: translation k' [N/m²], rotation k'_θ [N·m/rad/m] — HSK's face contact makes it much stiffer in rotation)
TAPERS = {"HSK-A63": (0.063, 0.048, 0.032, 6.0e10, 6.0e7), "BT40": (0.04445, 0.044, 0.065, 1.2e10, 1.0e7)}
TH_KP = (2.0e9, 1.0e7)          # tool–holder contact per length at 80 N·m, carbide shank: N/m², N·m/rad/m
SHANK = {"carbide": 1.0, "steel": 0.75}
SPINDLE_LEN = (0.12, 0.18)
BEARINGS = ((0.03, {"x": 3e8, "ry": 2e5}, {"x": 4000.0}), (0.26, {"x": 1.5e8}, {"x": 2000.0}))
ROTOR = (0.20, 3.0, 2e-3)       # position from the nose [m], mass [kg], rotary inertia [kg m²]


@dataclass(frozen=True)
class Case:
    """One stack: tool Ø / gauge / insertion / fluted length [m], torque [N·m], taper, drawbar [N]."""

    name: str
    diameter: float
    gauge: float
    insertion: float
    torque: float
    taper: str
    drawbar: float
    fluted: float = 0.0
    material: str = "carbide"
    bonded: bool = False        # tool bonded in the holder (holder–spindle test arbor)


def th_contact(torque: float, material: str) -> dict:
    s = (torque / 80.0) ** 0.5 * SHANK[material]
    return {"x": TH_KP[0] * s, "ry": TH_KP[1] * s}


def hs_contact(drawbar: float, taper: str) -> dict:
    s = (drawbar / 20e3) ** 0.35
    return {"x": TAPERS[taper][3] * s, "ry": TAPERS[taper][4] * s}


def _fluted_material(material: str) -> Material:
    m = get_material(material)
    ratio = 0.656 ** 2
    return Material(f"{m.name} (fluted, true mass)", m.E, m.nu, m.rho * FLUTED_AREA / ratio)


def spindle_segments(taper: str) -> list[Segment]:
    _, d_in, lt, _, _ = TAPERS[taper]
    return [Segment(lt, 0.070, d_in), Segment(SPINDLE_LEN[0] - lt, 0.070, 0.030),
            Segment(SPINDLE_LEN[1], 0.060, 0.030)]


def spindle_ingredients(z0: float) -> list:
    ings = [Support(z0 + p, dict(k), dict(c)) for p, k, c in BEARINGS]
    ings.append(PointMass(z0 + ROTOR[0], ROTOR[1], ROTOR[2]))
    return ings


def truth_model(case: Case, element: float = 0.003):
    """The whole stack as one beam model (tip at z = 0). Returns (model, th_insertion, hs_insertion)."""
    d, g, li = case.diameter, case.gauge, case.insertion
    segs = []
    if case.fluted > 0:
        segs.append(Segment(case.fluted, 0.656 * d, 0.0, _fluted_material(case.material)))
    segs.append(Segment(g - case.fluted, d, 0.0, case.material))
    segs += [Segment(HOLDER_NOSE, 0.032, d), Segment(HOLDER_BODY, 0.050, 0.0)]
    zs = g + HOLDER_NOSE + HOLDER_BODY
    segs += spindle_segments(case.taper)
    _, d_in, lt, _, _ = TAPERS[case.taper]
    th = Insertion(g, g + li, d, 0.0, case.material, "start",
                   "rigid" if case.bonded else Contact(th_contact(case.torque, case.material), CONTACT_ETA),
                   "tool shank in holder bore")
    hs = Insertion(zs, zs + lt, d_in, 0.0, "steel", "start",
                   Contact(hs_contact(case.drawbar, case.taper), CONTACT_ETA), "taper in spindle nose")
    model = BeamModel(tuple(segs), points=(NamedPoint("tip", 0.0, 1),),
                      ingredients=(th, hs, *spindle_ingredients(zs), HystereticDamping(ETA)),
                      max_element_length=element, name=f"truth: {case.name}")
    return model, th, hs


def _mouth_node(model, mesh, K, ins) -> int:
    """The node of the inserted part's side at an insertion's mouth (the low-z beam that continues it)."""
    if ins.rigid:
        return mesh.node_at(ins.mouth)
    a, b = mesh.split_nodes(ins)
    # the side connected by beam elements to the main chain just below the mouth
    pos = mesh.node_positions
    main = np.arange(mesh.n_main)
    lower = main[pos[main] < ins.mouth - 1e-9]
    nb = lower[np.argmax(pos[lower])]
    ix = mesh.dof(nb, "x")
    for n in (a, b):
        if K[ix, mesh.dof(n, "x")] != 0:
            return n
    raise RuntimeError("cannot find the mouth node")


def solve_frf(model, out_nodes, in_nodes, freq=FREQ) -> np.ndarray:
    """Receptance (n_freq, n_out, n_in) on x DOFs of mesh nodes, by a sparse LU per line."""
    m = model.assemble()
    keep = np.flatnonzero(~m.fixed)
    K = sp.csc_matrix((m.K + 1j * m.K_loss)[np.ix_(keep, keep)])
    C = sp.csc_matrix(m.C[np.ix_(keep, keep)])
    M = sp.csc_matrix(m.M[np.ix_(keep, keep)])
    mesh = model.mesh()
    pos = {g: i for i, g in enumerate(keep)}
    ri = [pos[mesh.dof(n, "x")] for n in in_nodes]
    ro = [pos[mesh.dof(n, "x")] for n in out_nodes]
    rhs = np.zeros((keep.size, len(ri)), dtype=complex)
    rhs[ri, np.arange(len(ri))] = 1.0
    out = np.empty((freq.size, len(ro), len(ri)), dtype=complex)
    for k, f in enumerate(freq):  # one sparse factorisation per line (the contact layers break the band)
        w = 2 * np.pi * f
        x = spla.splu((K + 1j * w * C - w * w * M).tocsc()).solve(rhs)
        out[k] = x[ro]
    return out


def truth_tip(case: Case, freq=FREQ) -> FRF:
    model, _, _ = truth_model(case)
    mesh = model.mesh()
    h = solve_frf(model, [mesh.node_at(0.0)], [mesh.node_at(0.0)], freq)
    return FRF(freq, h, (Dof(1, "x"),), (Dof(1, "x"),), "receptance")


def spindle_frf(taper: str, freq=FREQ) -> FRF:
    """The spindle alone at its nose (node 5: x, ry), as measured (exact: no noise).

    The model is deterministic and the catalogue asks for the same spindle once per campaign and stack: it is
    solved once per taper and band, and each caller gets its own copy of the values."""
    frf = _spindle_frf(taper, tuple(np.asarray(freq, dtype=float).tolist()))
    return replace(frf, freq=frf.freq.copy(), values=frf.values.copy())


@functools.lru_cache(maxsize=8)
def _spindle_frf(taper: str, freq: tuple) -> FRF:
    model = BeamModel(tuple(spindle_segments(taper)), points=(NamedPoint("nose", 0.0, 5),),
                      ingredients=(*spindle_ingredients(0.0), HystereticDamping(ETA)), max_element_length=0.003)
    return model.frf(np.array(freq), ["nose"])


def stack_doc(case: Case, joints: dict, fluted_mass: bool = True) -> dict:
    """The prediction path's stack file for ``case`` (spindle: measured FRF attached separately);
    ``fluted_mass``: tell it the fluted section's true area ratio (``tool.fluted_area_ratio``)."""
    segs = []
    if case.fluted > 0:
        segs.append({"length": case.fluted, "diameter": case.diameter, "fluted": True})
    segs.append({"length": case.gauge + case.insertion - case.fluted, "diameter": case.diameter})
    return {
        "format": "jointdb-stack/1", "name": case.name,
        "tool": {"material": case.material, "loss_factor": ETA, "segments": segs,
                 **({"fluted_area_ratio": FLUTED_AREA} if fluted_mass and case.fluted > 0 else {})},
        "gauge_length": case.gauge,
        "holder": {"material": "steel", "loss_factor": ETA,
                   "segments": [{"length": HOLDER_NOSE, "outer_diameter": 0.032, "inner_diameter": case.diameter},
                                {"length": HOLDER_BODY, "outer_diameter": 0.050}]},
        "spindle": {"file": "spindle.uff", "node": 5},
        "interfaces": joints,
        "frequency": {"min": float(FREQ[0]), "max": float(FREQ[-1]), "step": float(FREQ[1] - FREQ[0])},
    }


def spec_for(case: Case, joints: dict, fluted_mass: bool = True):
    from jointdb.stack import MeasuredSpindle

    spec = stack_from_dict(stack_doc(case, joints, fluted_mass))
    return spec.replace(spindle=MeasuredSpindle("spindle.uff", 5, spindle_frf(case.taper)))


def th_conditions(case: Case) -> dict:
    """Tool–holder conditions. ``geometry.taper_diameter_m`` and ``preload_n`` name the machine the joint was
    identified on (its taper and drawbar force): a per-line tool–holder joint carries what its campaign's
    substructure A (holder on that spindle, through that machine's catalogued taper joint) could not
    represent, so it transfers to stacks on a machine like that one, and is interpolated along the drawbar
    force like the torque (see :data:`TH_MACHINES`). For a stack they are its spindle's taper and force."""
    mats = ["tungsten-carbide" if case.material == "carbide" else case.material, "steel"]
    return {"materials": mats, "torque_nm": case.torque, "preload_n": case.drawbar,
            "geometry": {"shank_diameter_m": case.diameter, "taper_diameter_m": TAPERS[case.taper][0]}}


def hs_conditions(case: Case) -> dict:
    return {"materials": ["steel", "steel"], "preload_n": case.drawbar,
            "geometry": {"taper_diameter_m": TAPERS[case.taper][0]}}


def _noisy(values: np.ndarray, name: str) -> np.ndarray:
    rng = np.random.default_rng([SEED, zlib.crc32(name.encode())])
    scale = 10.0 ** (np.floor(np.log10(np.abs(values))) - 5)
    v = np.round(values.real / scale) * scale + 1j * np.round(values.imag / scale) * scale
    z = (rng.standard_normal(v.shape) + 1j * rng.standard_normal(v.shape)) / np.sqrt(2)
    return v * (1 + NOISE * z)


def _dump(path: Path, doc: dict) -> None:
    path.write_text(json.dumps(doc, indent=2, sort_keys=True) + "\n", encoding="utf-8")


def write_hs_campaign(folder: Path, case: Case) -> Path:
    """Holder–spindle campaign: A = measured spindle, B = holder with a bonded test arbor (model)."""
    folder.mkdir(parents=True, exist_ok=True)
    case = replace(case, bonded=True)
    model, _, hs = truth_model(case)
    mesh = model.mesh()
    K = model.assemble().K
    tip, flange = mesh.node_at(0.0), _mouth_node(model, mesh, K, hs)
    g = _noisy(solve_frf(model, [tip], [tip, flange]), folder.name)
    write_uff58(folder / "assembly.uff", FRF(FREQ, g, (Dof(1, "x"),), (Dof(1, "x"), Dof(4, "x")), "receptance"),
                round_freq=False)
    write_uff58(folder / "spindle.uff", spindle_frf(case.taper), round_freq=False)
    spec = spec_for(case, {"tool-holder": "rigid", "holder-spindle": "rigid"})
    tool, holder = tool_model(spec), holder_model(spec)
    b = BeamModel(tool.segments + holder.segments,
                  points=(NamedPoint("tip", 0.0, 1), NamedPoint("base", tool.length + holder.length, 4)),
                  ingredients=(HystereticDamping(ETA),), max_element_length=0.005, name="holder + bonded arbor")
    _dump(folder / "holder.json", model_to_dict(b))
    _dump(folder / "campaign.json", {
        "format": "jointdb-campaign/1", "name": folder.name, "joint_type": "holder-spindle",
        "conditions": hs_conditions(case), "joint_model": "planar",
        "substructures": {"spindle": {"uff58": "spindle.uff", "dofs": ["5x", "5ry"]},
                          "holder": {"model": "holder.json"}},
        "interface": {"a": "spindle", "a_dofs": ["5x", "5ry"], "b": "holder", "b_dofs": ["4x", "4ry"]},
        "measurements": ["assembly.uff"], "planar": {"b_tip": 1},
        "options": {"smoothing": 9, "fit_band": [100.0, 5000.0]},
    })
    return folder / "campaign.json"


def write_th_campaign(folder: Path, case: Case, hs_joint: FRF) -> Path:
    """Tool–holder campaign on the machine ``case.taper`` at ``case.drawbar``: A = holder on the spindle through
    that machine's catalogued taper joint ``hs_joint`` (a 2×2 receptance, as the prediction path couples it),
    B = blank overhang (model)."""
    folder.mkdir(parents=True, exist_ok=True)
    model, th, _ = truth_model(case)
    mesh = model.mesh()
    K = model.assemble().K
    tip, face = mesh.node_at(0.0), _mouth_node(model, mesh, K, th)
    g = _noisy(solve_frf(model, [tip], [tip, face]), folder.name)
    write_uff58(folder / "assembly.uff", FRF(FREQ, g, (Dof(1, "x"),), (Dof(1, "x"), Dof(2, "x")), "receptance"),
                round_freq=False)
    spec = spec_for(case, {"tool-holder": "rigid", "holder-spindle": "rigid"})
    h = holder_model(spec).frf(FREQ, ["nose", "base"]).values
    s = spindle_frf(case.taper).values
    j = hs_joint.resample(FREQ).values if hs_joint.n_freq != FREQ.size else hs_joint.values
    a33 = attach(h[:, :2, :2], h[:, :2, 2:], h[:, 2:, :2], h[:, 2:, 2:], s, j)
    a = (Dof(3, "x"), Dof(3, "ry"))
    write_uff58(folder / "holder-on-spindle.uff", FRF(FREQ, a33, a, a, "receptance"), round_freq=False)
    _dump(folder / "tool.json", model_to_dict(tool_model(spec)))
    _dump(folder / "campaign.json", {
        "format": "jointdb-campaign/1", "name": folder.name, "joint_type": "tool-holder",
        "conditions": th_conditions(case), "joint_model": "planar",
        "substructures": {"holder": {"uff58": "holder-on-spindle.uff", "dofs": ["3x", "3ry"]},
                          "tool": {"model": "tool.json"}},
        "interface": {"a": "holder", "a_dofs": ["3x", "3ry"], "b": "tool", "b_dofs": ["2x", "2ry"]},
        "measurements": ["assembly.uff"], "planar": {"b_tip": 1},
        "options": {"smoothing": 9, "fit_band": [100.0, 5000.0]},
    })
    return folder / "campaign.json"


def hs_name(taper: str, drawbar: float) -> str:
    """The name of the holder–spindle campaign (catalogued joint) of ``taper`` at ``drawbar`` [N]."""
    return f"hs-{taper.lower()}-{int(round(drawbar / 1e3)):02d}kn"


#: Catalogued holder–spindle conditions: tapers × drawbar forces.
HS_CAMPAIGNS = [Case(hs_name(t, f), 0.012, 0.045, 0.035, 80.0, t, f)
                for t, fs in (("HSK-A63", (12e3, 18e3, 24e3)), ("BT40", (8e3, 12e3, 16e3))) for f in fs]
#: The machines the tool–holder campaigns run on: each taper family at its lowest and highest catalogued
#: drawbar force (their catalogued taper joints give the campaigns' substructure A).
TH_MACHINES = {"HSK-A63": (12e3, 24e3), "BT40": (8e3, 16e3)}
TH_CAMPAIGNS = [Case(f"th-{'hsk' if taper == 'HSK-A63' else 'bt40'}-{int(force / 1e3):02d}kn-d{int(d * 1e3):02d}-"
                     f"{int(t):03d}nm", d, 0.045, 0.035, t, taper, force)
                for taper, forces in TH_MACHINES.items() for force in forces
                for d, ts in ((0.010, (40.0, 120.0)), (0.012, (40.0, 80.0, 120.0)), (0.016, (40.0, 120.0)))
                for t in ts]
#: Stacks the catalogue never saw (inside its range), and two outside it.
VALIDATION = [
    Case("Ø12 end mill, 55 mm gauge, 100 N·m, HSK-A63 20 kN", 0.012, 0.055, 0.035, 100.0, "HSK-A63", 20e3, 0.025),
    Case("Ø12 blank, 65 mm gauge, 60 N·m, HSK-A63 15 kN", 0.012, 0.065, 0.032, 60.0, "HSK-A63", 15e3),
    Case("Ø16 end mill, 60 mm gauge, 80 N·m, HSK-A63 22 kN", 0.016, 0.060, 0.036, 80.0, "HSK-A63", 22e3, 0.030),
    Case("Ø10 end mill, 40 mm gauge, 90 N·m, HSK-A63 18 kN", 0.010, 0.040, 0.032, 90.0, "HSK-A63", 18e3, 0.020),
    Case("Ø12 end mill, 50 mm gauge, 70 N·m, BT40 10 kN", 0.012, 0.050, 0.035, 70.0, "BT40", 10e3, 0.025),
    Case("Ø14 blank, 55 mm gauge, 110 N·m, BT40 14 kN", 0.014, 0.055, 0.035, 110.0, "BT40", 14e3),
]
OUTSIDE = [
    Case("Ø12 end mill, 55 mm gauge, 200 N·m, HSK-A63 30 kN (outside)", 0.012, 0.055, 0.035, 200.0, "HSK-A63",
         30e3, 0.025),
    Case("Ø20 blank, 70 mm gauge, 80 N·m, HSK-A63 18 kN (outside)", 0.020, 0.070, 0.038, 80.0, "HSK-A63", 18e3),
]


# ------------------------------------------------------------------ catalogue and validation


def _adequacy(out) -> dict:
    """Which joint the identification kept (constant output-error k, c or the per-line IRC joint) and why."""
    a = (out.identified.quality or {}).get("model_adequacy") or {}
    return {"kept": a.get("catalogued_joint"), "misfit_to_noise": a.get("misfit_to_noise")}


def build_catalogue(workdir: Path, repo, say=print) -> list[dict]:
    """Write and catalogue every campaign (holder–spindle first: the tool–holder campaigns' A needs the
    reference machine's taper joint). Returns one row per campaign (joint, constant k, residual, joint kept)."""
    from jointdb import usecases

    rows = []
    for case in HS_CAMPAIGNS:
        out = usecases.catalogue_campaign(repo, write_hs_campaign(workdir / case.name, case))
        rows.append(out.row() | {"type": "holder-spindle", "case": case.name} | _adequacy(out))
        say(f"  catalogued {rows[-1]['joint']}: k_x={rows[-1]['k_x_n_per_m']:.3e} N/m, "
            f"k_θ={rows[-1]['k_theta_nm_per_rad']:.3e} N·m/rad")
    hs_joints = {}
    for case in TH_CAMPAIGNS:
        machine = hs_name(case.taper, case.drawbar)
        if machine not in hs_joints:
            hs_joints[machine] = repo.load_frf(repo.get(machine))
        out = usecases.catalogue_campaign(repo, write_th_campaign(workdir / case.name, case, hs_joints[machine]))
        rows.append(out.row() | {"type": "tool-holder", "case": case.name} | _adequacy(out))
        say(f"  catalogued {rows[-1]['joint']}: k_x={rows[-1]['k_x_n_per_m']:.3e} N/m, "
            f"k_θ={rows[-1]['k_theta_nm_per_rad']:.3e} N·m/rad")
    return rows


def queries(case: Case, interpolate: bool = True) -> dict:
    return {
        "tool-holder": {"query": {"joint_type": "tool-holder", **th_conditions(case),
                                  "interpolate": interpolate, "neighbours": 2}},
        "holder-spindle": {"query": {"joint_type": "holder-spindle", **hs_conditions(case),
                                     "interpolate": interpolate, "neighbours": 2}},
    }


def _refine(h: np.ndarray, k: int, freq: np.ndarray = FREQ) -> tuple[float, float]:
    """Frequency and |H| of the peak at line ``k``, by a parabola through log|H| on the (uniform) grid ``freq``."""
    if 0 < k < h.size - 1:
        a, b, c = np.log(h[k - 1:k + 2])
        d = 0.5 * (a - c) / (a - 2 * b + c)
        return float(freq[k] + d * (freq[1] - freq[0])), float(np.exp(b - 0.25 * (a - c) * d))
    return float(freq[k]), float(h[k])


def _dominant(frf_values: np.ndarray, freq: np.ndarray = FREQ) -> tuple[float, float]:
    h = np.abs(frf_values)
    return _refine(h, int(np.argmax(h)), freq)


def _nearest_peak(frf_values: np.ndarray, f_hz: float) -> tuple[float, float]:
    """The resonance (local maximum of |H|) nearest ``f_hz``: frequency and |H|, refined."""
    h = np.abs(frf_values)
    peaks = np.flatnonzero((h[1:-1] > h[:-2]) & (h[1:-1] >= h[2:])) + 1
    k = int(peaks[np.argmin(np.abs(FREQ[peaks] - f_hz))]) if peaks.size else int(np.argmax(h))
    return _refine(h, k)


def second_peak_ratio(frf_values: np.ndarray) -> float:
    """Height of the second-largest resonance / the largest (near 1: the dominant mode is ill-defined)."""
    h = np.abs(frf_values)
    peaks = np.flatnonzero((h[1:-1] > h[:-2]) & (h[1:-1] >= h[2:])) + 1
    tops = np.sort(h[peaks])[::-1]
    return float(tops[1] / tops[0]) if tops.size > 1 else 0.0


def _floor(h: np.ndarray, freq: np.ndarray = FREQ) -> float:
    from jointdb.stability import MillingCut, milling_lobes_zoa

    cut = MillingCut(n_teeth=4, kt=7.96e8, kr=0.212 * 7.96e8, radial_immersion=0.5, down_milling=True)
    out = (Dof(1, "x"), Dof(1, "y"))
    v = np.zeros((freq.size, 2, 2), dtype=complex)
    v[:, 0, 0] = v[:, 1, 1] = h
    return float(milling_lobes_zoa(FRF(freq, v, out, out, "receptance"), cut,
                                   spindle_speed_rpm=np.linspace(3000, 30000, 200)).min_depth_m)


def idw_joints(case: Case, repo) -> dict:
    """The joints as resolved before the axis-aware interpolation: inverse-distance weights of the two
    nearest (``method="idw"``), for the before/after comparison (interface → InterpolatedJoint)."""
    import warnings

    from jointdb.store import Conditions, OutsideCatalogueWarning

    out = {}
    for name, q in queries(case).items():
        query = dict(q["query"])
        jt = query.pop("joint_type")
        query.pop("interpolate"), query.pop("neighbours")
        cond = Conditions.from_dict(query)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", OutsideCatalogueWarning)
            matches = repo.nearest(jt, cond, k=2)
        out[name] = repo.interpolate(matches, cond, method="idw")
    return out


def validate(case: Case, repo, spindle=None, before: bool = False) -> dict:
    """Predict ``case`` from the catalogue and with rigid joints; compare with its truth tip FRF.

    ``spindle``: a spindle FRF (5x, 5ry) to predict with as well (e.g. estimated from noisy translations;
    key ``cat_est_spindle``); ``before``: also the joints interpolated the old way (key ``cat_idw``) and the
    tool–holder joints of the other taper family's machines (key ``cat_th_other_family``) and of the
    family's low-force machine only (key ``cat_th_one_machine``).
    Per variant: dominant-mode frequency / peak / lobe-floor errors, and the mode-matched comparison (the
    predicted resonance nearest the truth's dominant one: ``near_freq_err``, ``near_peak_err``).
    """
    from jointdb import usecases
    from jointdb.stack import MeasuredSpindle, predict_tool_tip

    truth = truth_tip(case).values[:, 0, 0]
    spec = spec_for(case, queries(case))
    res = usecases.resolve_joints(spec, repo)
    joints = {n: r.frf for n, r in res.items() if r.frf is not None}
    pred = predict_tool_tip(spec, joints, FREQ)
    variants = {"cat": pred.tip.values[:, 0, 0], "rigid": pred.rigid.values[:, 0, 0]}
    if case.fluted > 0:  # the same prediction without the fluted section's true mass (the default model)
        spec0 = spec_for(case, queries(case), fluted_mass=False)
        variants["cat_cylinder_mass"] = predict_tool_tip(spec0, joints, FREQ).tip.values[:, 0, 0]
    idw = idw_joints(case, repo) if before else {}
    if before:
        variants["cat_idw"] = predict_tool_tip(spec, {n: j.frf for n, j in idw.items()}, FREQ).tip.values[:, 0, 0]
        # the tool–holder joints of the other taper family (identified on the other reference machine)
        other = next(t for t in TH_MACHINES if t != case.taper)
        q = queries(case)
        q["tool-holder"]["query"]["geometry"] = {**q["tool-holder"]["query"]["geometry"],
                                                 "taper_diameter_m": TAPERS[other][0]}
        ores = usecases.resolve_joints(spec_for(case, q), repo)
        variants["cat_th_other_family"] = predict_tool_tip(
            spec, {**joints, "tool-holder": ores["tool-holder"].frf}, FREQ).tip.values[:, 0, 0]
        # the tool–holder joints of the family's low-force machine only (as if catalogued on one machine)
        q = queries(case)
        q["tool-holder"]["query"]["preload_n"] = min(TH_MACHINES[case.taper])
        ores = usecases.resolve_joints(spec_for(case, q), repo)
        variants["cat_th_one_machine"] = predict_tool_tip(
            spec, {**joints, "tool-holder": ores["tool-holder"].frf}, FREQ).tip.values[:, 0, 0]
    if spindle is not None:
        spec_e = spec.replace(spindle=MeasuredSpindle("spindle.uff", 5, spindle))
        variants["cat_est_spindle"] = predict_tool_tip(spec_e, joints, FREQ).tip.values[:, 0, 0]
    ft, at = _dominant(truth)
    lt = _floor(truth)
    row = {"case": case.name, "truth_hz": ft, "truth_peak": at, "truth_floor_mm": lt * 1e3,
           "truth_second_peak_ratio": second_peak_ratio(truth),
           "extrapolating": any(r.extrapolating for r in res.values()),
           "warnings": [w for r in res.values() for w in r.warnings],
           "joints": {n: r.description if r.kind == "interpolated" else f"{r.name}@{r.version}"
                      for n, r in res.items()},
           "idw_joints": {n: j.describe() for n, j in idw.items()}}
    for key, h in variants.items():
        f, a = _dominant(h)
        row[f"{key}_hz"], row[f"{key}_peak"] = f, a
        row[f"{key}_freq_err"] = f / ft - 1
        row[f"{key}_peak_err"] = a / at - 1
        if key != "cat_cylinder_mass":  # reported as frequency and peak only
            row[f"{key}_floor_mm"] = _floor(h) * 1e3
            row[f"{key}_floor_err"] = row[f"{key}_floor_mm"] / (lt * 1e3) - 1
        fn, an = _nearest_peak(h, ft)
        row[f"{key}_near_freq_err"] = fn / ft - 1
        row[f"{key}_near_peak_err"] = an / at - 1
    return row
