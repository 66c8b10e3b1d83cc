"""What the truth families of the band check (``_stack_truth_b``, ``_stack_truth_c``) share: the campaigns written on
the truth, the catalogue built from them, the truth tip, the spindle alone, the conditions and queries of a stack.

Each function takes the family's module first and reads from it what makes the family: ``truth_model``, ``spec_for``,
``spindle_segments``, ``spindle_ingredients``, ``hs_name``, ``TAPER``, ``FREQ``, ``HS_CAMPAIGNS``, ``TH_CAMPAIGNS``,
``TH_MACHINES``, ``NOISE_TAG`` (the seed prefix of its measurement noise) and ``CAMPAIGN_OPTIONS``. A family binds
them to itself (``truth_tip = functools.partial(family.truth_tip, sys.modules[__name__])``), so that the benches
call ``tb.truth_tip(case)`` whatever the family.
"""

from __future__ import annotations

import functools
from dataclasses import replace
from pathlib import Path

import _stack_validation as sv
from jointdb.fe import BeamModel, HystereticDamping, NamedPoint, model_to_dict
from jointdb.frf import FRF, Dof
from jointdb.io import write_uff58
from jointdb.stack import attach, holder_model, tool_model


def truth_tip(fam, case: sv.Case) -> FRF:
    """The truth's tool-tip receptance (x over x) on the family's grid."""
    model, _, _ = fam.truth_model(case)
    mesh = model.mesh()
    h = sv.solve_frf(model, [mesh.node_at(0.0)], [mesh.node_at(0.0)], fam.FREQ)
    return FRF(fam.FREQ, h, (Dof(1, "x"),), (Dof(1, "x"),), "receptance")


def spindle_model(fam) -> BeamModel:
    """The spindle alone (nose at z = 0, point "nose" = node 5)."""
    return BeamModel(tuple(fam.spindle_segments()), points=(NamedPoint("nose", 0.0, 5),),
                     ingredients=(*fam.spindle_ingredients(0.0), HystereticDamping(sv.ETA)), max_element_length=0.003)


def spindle_frf(fam) -> FRF:
    """The spindle alone at its nose (node 5: x, ry), exact; solved once per family (deterministic), each caller
    gets a copy."""
    frf = _spindle_frf(fam)
    return replace(frf, freq=frf.freq.copy(), values=frf.values.copy())


@functools.lru_cache(maxsize=4)
def _spindle_frf(fam) -> FRF:
    return spindle_model(fam).frf(fam.FREQ, ["nose"])


def hs_conditions(fam, case: sv.Case) -> dict:
    return {"materials": ["steel", "steel"], "preload_n": case.drawbar, "geometry": {"taper_diameter_m": fam.TAPER[0]}}


def th_conditions(fam, case: sv.Case) -> dict:
    """A tool–holder campaign's (or query's) conditions; with ``fam.RECORD_INSERTION`` set (bench option
    ``--record-insertion``) the insertion depth too, as ``geometry.insertion_m``."""
    geometry = {"shank_diameter_m": case.diameter, "taper_diameter_m": fam.TAPER[0]}
    if getattr(fam, "RECORD_INSERTION", False):
        geometry["insertion_m"] = case.insertion
    return {"materials": ["tungsten-carbide", "steel"], "torque_nm": case.torque, "preload_n": case.drawbar,
            "geometry": geometry}


def queries(fam, case: sv.Case) -> dict:
    """Both interfaces as catalogue queries at the stack's conditions, interpolated."""
    return {"tool-holder": {"query": {"joint_type": "tool-holder", **th_conditions(fam, case), "interpolate": True}},
            "holder-spindle": {"query": {"joint_type": "holder-spindle", **hs_conditions(fam, case),
                                         "interpolate": True}}}


def _campaign(fam, folder: Path, case: sv.Case, joint_type: str, b_model: BeamModel, a_file: tuple[str, FRF]) -> Path:
    """Measure the assembly (tip x over tip x and x at the mouth of the campaign's joint) and write a planar
    campaign: substructure A from ``a_file`` (x, ry at its interface node), B = ``b_model``."""
    folder.mkdir(parents=True, exist_ok=True)
    model, th, hs = fam.truth_model(case)
    mesh = model.mesh()
    th_side = joint_type == "tool-holder"
    tip, mouth = mesh.node_at(0.0), sv._mouth_node(model, mesh, model.assemble().K, th if th_side else hs)
    g = sv._noisy(sv.solve_frf(model, [tip], [tip, mouth], fam.FREQ), f"{fam.NOISE_TAG}-{folder.name}")
    a_node, b_node = (3, 2) if th_side else (5, 4)
    write_uff58(folder / "assembly.uff", FRF(fam.FREQ, g, (Dof(1, "x"),), (Dof(1, "x"), Dof(b_node, "x")),
                                             "receptance"), round_freq=False)
    write_uff58(folder / a_file[0], a_file[1], round_freq=False)
    sv._dump(folder / "b.json", model_to_dict(b_model))
    a_dofs, b_dofs = [f"{a_node}x", f"{a_node}ry"], [f"{b_node}x", f"{b_node}ry"]
    sv._dump(folder / "campaign.json", {
        "format": "jointdb-campaign/1", "name": folder.name, "joint_type": joint_type,
        "conditions": th_conditions(fam, case) if th_side else hs_conditions(fam, case), "joint_model": "planar",
        "substructures": {"a": {"uff58": a_file[0], "dofs": a_dofs}, "b": {"model": "b.json"}},
        "interface": {"a": "a", "a_dofs": a_dofs, "b": "b", "b_dofs": b_dofs},
        "measurements": ["assembly.uff"], "planar": {"b_tip": 1},
        "options": dict(fam.CAMPAIGN_OPTIONS),
    })
    return folder / "campaign.json"


def write_hs_campaign(fam, folder: Path, case: sv.Case) -> Path:
    """A = the measured spindle at its nose, B = the holder with a bonded test arbor (model)."""
    case = replace(case, bonded=True)
    spec = fam.spec_for(case, {"tool-holder": "rigid", "holder-spindle": "rigid"})
    tool, holder = tool_model(spec), holder_model(spec)
    b = BeamModel(tool.segments + holder.segments,
                  points=(NamedPoint("tip", 0.0, 1), NamedPoint("base", tool.length + holder.length, 4)),
                  ingredients=(HystereticDamping(sv.ETA),), max_element_length=0.005, name="holder + bonded arbor")
    return _campaign(fam, folder, case, "holder-spindle", b, ("spindle.uff", spindle_frf(fam)))


def write_th_campaign(fam, folder: Path, case: sv.Case, hs_joint: FRF) -> Path:
    """A = the holder on the spindle through the machine's catalogued taper joint, B = the blank overhang (model)."""
    spec = fam.spec_for(case, {"tool-holder": "rigid", "holder-spindle": "rigid"})
    h = holder_model(spec).frf(fam.FREQ, ["nose", "base"]).values
    j = hs_joint.resample(fam.FREQ).values if hs_joint.n_freq != fam.FREQ.size else hs_joint.values
    a33 = attach(h[:, :2, :2], h[:, :2, 2:], h[:, 2:, :2], h[:, 2:, 2:], spindle_frf(fam).values, j)
    a = (Dof(3, "x"), Dof(3, "ry"))
    return _campaign(fam, folder, case, "tool-holder", tool_model(spec),
                     ("holder-on-spindle.uff", FRF(fam.FREQ, a33, a, a, "receptance")))


def build_catalogue(fam, workdir: Path, repo, say=print) -> None:
    """Identify and catalogue every campaign of the family (holder–spindle first), through the library path the
    CLI's ``jointdb campaign catalogue`` uses (``usecases.catalogue_campaign``)."""
    from jointdb import usecases

    for case in fam.HS_CAMPAIGNS:
        out = usecases.catalogue_campaign(repo, write_hs_campaign(fam, workdir / case.name, case))
        say(f"  catalogued {out.row()['joint']}")
    hs = {f: repo.load_frf(repo.get(fam.hs_name(f))) for f in fam.TH_MACHINES}
    for case in fam.TH_CAMPAIGNS:
        out = usecases.catalogue_campaign(repo, write_th_campaign(fam, workdir / case.name, case, hs[case.drawbar]))
        say(f"  catalogued {out.row()['joint']}")
