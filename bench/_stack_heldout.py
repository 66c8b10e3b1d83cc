"""A larger held-out set for the stack-prediction validation, and a spindle receptance "measured" the way a
user gets it (translations on an extension + ``jointdb rotations``' extension estimate), with its noise.

- :func:`draw_heldout`: stacks drawn with a fixed seed inside the catalogued range of
  ``_stack_validation`` (carbide shank Ø10–16 mm, gauge 3–6 diameters within 35–80 mm,
  insertion 30–38 mm, torque log-uniform 40–120 N·m, HSK-A63 12–24 kN or BT40 8–16 kN,
  fluted over 40–70 % of the gauge or blank). Never used to build the catalogue and not
  tuned: the draw is what it is.
- :func:`spindle_by_extension`: the spindle's (x, θ) nose receptance from three translational
  FRFs (G_11, G_12, G_22) measured on a steel extension bolted to the nose, with the same
  noise as the campaigns (6 digits, 0.2 % complex), through
  :func:`jointdb.campaign._rotations.estimate_rotations` (what ``jointdb rotations
  --method extension`` runs), and the noise amplification it reports.
"""

from __future__ import annotations

import zlib

import numpy as np

import _stack_validation as sv
from jointdb.fe import BeamModel, HystereticDamping, NamedPoint, Segment
from jointdb.frf import FRF, Dof

HELDOUT_SEED = 20261124
HELDOUT_SIZE = 18
#: The extension bolted to the spindle nose for the rotation estimate: steel cylinder Ø40 × 100 mm,
#: translations measured at its free end and 50 mm from the nose.
EXTENSION = (0.040, 0.100, 0.050)


def draw_heldout(n: int | None = None, seed: int | None = None) -> list[sv.Case]:
    """``n`` stacks (default :data:`HELDOUT_SIZE`) drawn with ``seed`` (default :data:`HELDOUT_SEED`) inside
    the catalogued range (module docstring)."""
    n = HELDOUT_SIZE if n is None else n
    rng = np.random.default_rng(HELDOUT_SEED if seed is None else seed)
    out = []
    for i in range(n):
        d = float(rng.integers(10, 17)) / 1e3
        gauge = round(min(max(float(rng.uniform(3.0, 6.0)) * d, 0.035), 0.080), 3)
        insertion = round(float(rng.uniform(0.030, 0.038)), 3)
        torque = float(np.round(np.exp(rng.uniform(np.log(40.0), np.log(120.0))) / 5.0) * 5.0)
        taper = "HSK-A63" if rng.random() < 0.5 else "BT40"
        lo, hi = (12e3, 24e3) if taper == "HSK-A63" else (8e3, 16e3)
        drawbar = float(np.round(rng.uniform(lo, hi) / 500.0) * 500.0)
        fluted = round(float(rng.uniform(0.4, 0.7)) * gauge, 3) if rng.random() < 0.5 else 0.0
        kind = "end mill" if fluted else "blank"
        name = (f"H{i + 1:02d}: Ø{d * 1e3:.0f} {kind}, {gauge * 1e3:.0f} mm gauge, {torque:.0f} N·m, "
                f"{taper} {drawbar / 1e3:g} kN")
        out.append(sv.Case(name, d, gauge, insertion, torque, taper, drawbar, fluted))
    return out


def _extension_segments() -> tuple[Segment, ...]:
    d, length, _ = EXTENSION
    return (Segment(length, d, 0.0, "steel"),)


def extension_model() -> BeamModel:
    """The extension alone (free–free): free end ``p1`` (node 11) at z = 0, ``p2`` (node 12), ``joint``
    (node 10) at the end bolted to the nose."""
    d, length, p2 = EXTENSION
    return BeamModel(_extension_segments(),
                     points=(NamedPoint("p1", 0.0, 11), NamedPoint("p2", p2, 12), NamedPoint("joint", length, 10)),
                     ingredients=(HystereticDamping(sv.ETA),), max_element_length=0.005, name="spindle extension")


def measured_on_extension(taper: str) -> FRF:
    """G_11, G_12, G_22 (receptance, nodes 11 and 12) of the extension on the truth spindle, with noise."""
    d, length, p2 = EXTENSION
    segs = _extension_segments() + tuple(sv.spindle_segments(taper))
    model = BeamModel(segs, points=(NamedPoint("p1", 0.0, 11), NamedPoint("p2", p2, 12)),
                      ingredients=(*sv.spindle_ingredients(length), HystereticDamping(sv.ETA)),
                      max_element_length=0.003, name="extension on the spindle")
    g = model.frf(sv.FREQ, ["p1", "p2"])
    dofs = (Dof(11, "x"), Dof(12, "x"))
    vals = g.block(list(dofs), list(dofs))
    rng = np.random.default_rng([sv.SEED, zlib.crc32(f"spindle-extension-{taper}".encode())])
    scale = 10.0 ** (np.floor(np.log10(np.abs(vals))) - 5)
    v = np.round(vals.real / scale) * scale + 1j * np.round(vals.imag / scale) * scale
    z = (rng.standard_normal(v.shape) + 1j * rng.standard_normal(v.shape)) / np.sqrt(2)
    return FRF(sv.FREQ, v * (1 + sv.NOISE * z), dofs, dofs, "receptance")


def spindle_by_extension(taper: str):
    """``(spindle FRF over 5x, 5ry, RotationEstimate)`` from :func:`measured_on_extension` through the
    extension estimate of ``jointdb rotations`` (noise amplification at the campaigns' 0.2 %, 20 trials)."""
    from jointdb.campaign._rotations import estimate_rotations

    est = estimate_rotations(measured_on_extension(taper), "extension", node=5, extension=extension_model(),
                             joint_point="joint", points=("p1", "p2"), noise=sv.NOISE, trials=20, seed=1)
    return est.frf, est


def oracle_joints(case: sv.Case, workdir, side_repo, cache: dict) -> dict:
    """Joints identified by campaigns at exactly ``case``'s conditions (same campaign design as the
    catalogue's): holder–spindle with the bonded Ø12 arbor at its taper and drawbar force, then tool–holder
    with a 45 mm / 35 mm blank of its shank and torque on that machine (A through that taper joint); catalogued
    in ``side_repo``: the prediction path's error with no interpolation. ``cache`` maps a campaign's
    conditions to its joint FRF (campaigns shared between stacks)."""
    from jointdb import usecases

    hs_key = ("hs", case.taper, case.drawbar)
    th_key = ("th", case.taper, case.drawbar, case.diameter, case.torque)
    if hs_key not in cache:
        name = f"oracle-hs-{case.taper.lower()}-{case.drawbar:.0f}n"
        c = sv.Case(name, 0.012, 0.045, 0.035, 80.0, case.taper, case.drawbar)
        out = usecases.catalogue_campaign(side_repo, sv.write_hs_campaign(workdir / name, c))
        cache[hs_key] = side_repo.load_frf(side_repo.get(out.row()["joint"].split("@")[0]))
    if th_key not in cache:
        name = f"oracle-th-{case.taper.lower()}-{case.drawbar:.0f}n-d{case.diameter * 1e3:.0f}-{case.torque:.0f}nm"
        c = sv.Case(name, case.diameter, 0.045, 0.035, case.torque, case.taper, case.drawbar)
        out = usecases.catalogue_campaign(side_repo, sv.write_th_campaign(workdir / name, c, cache[hs_key]))
        cache[th_key] = side_repo.load_frf(side_repo.get(out.row()["joint"].split("@")[0]))
    return {"tool-holder": cache[th_key], "holder-spindle": cache[hs_key]}


def oracle_row(case: sv.Case, joints: dict) -> dict:
    """Errors of the prediction with ``joints`` (from :func:`oracle_joints`) against the truth."""
    from jointdb.stack import predict_tool_tip

    truth = sv.truth_tip(case).values[:, 0, 0]
    h = predict_tool_tip(sv.spec_for(case, sv.queries(case)), joints, sv.FREQ).tip.values[:, 0, 0]
    ft, at = sv._dominant(truth)
    f, a = sv._dominant(h)
    fn, an = sv._nearest_peak(h, ft)
    return {"case": case.name, "oracle_freq_err": f / ft - 1, "oracle_peak_err": a / at - 1,
            "oracle_floor_err": sv._floor(h) / sv._floor(truth) - 1,
            "oracle_near_freq_err": fn / ft - 1, "oracle_near_peak_err": an / at - 1}
