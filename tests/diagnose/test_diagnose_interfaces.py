"""Joints inside the stack: interface sites, their candidates, plausibility and the verdict's texts."""

import numpy as np
import pytest

from jointdb.diagnose._select import plausibility as _plausibility
from jointdb.diagnose import Fit
from jointdb.diagnose._verdict import separating_measurement
from jointdb.diagnose.physics import Param
from jointdb.diagnose.physics.diameter import EffectiveDiameter, _free_end_segment
from jointdb.diagnose.physics.interface import InterfaceContact, InterfaceJoint, interface_sites, screen_sites
from jointdb.diagnose.physics.microslip import MicroslipContact, MicroslipJoint
from jointdb.fe import BeamModel, Clamp, Insertion, Joint, NamedPoint, Segment, model_to_dict

HOLDER_TOOL = BeamModel(
    segments=(Segment(0.045, 0.045), Segment(0.04, 0.026, 0.012), Segment(0.03, 0.012, material="carbide"),
              Segment(0.025, 0.0096, material="carbide")),
    points=(NamedPoint("tip", 0.14, 1), NamedPoint("shank", 0.09, 2), NamedPoint("nose", 0.08, 3)),
    ingredients=(Clamp(0.0),),
)


def test_sites_are_the_section_steps_and_inner_points_in_words():
    sites = interface_sites(HOLDER_TOOL)
    z = [round(s.position, 6) for s in sites]
    assert z == [0.045, 0.08, 0.085, 0.09, 0.115]          # not the clamp at 0, not the tip at the end
    face = sites[2]
    assert "⌀26 mm steel to ⌀12 mm" in face.location and "85 mm" in face.location
    assert "point 'nose'" in sites[1].location
    # a bonded insertion's mouth is a site that knows its insertion
    bonded = HOLDER_TOOL.with_ingredient(Insertion(0.06, 0.085, 0.012, material="carbide"))
    mouth = [s for s in interface_sites(bonded) if abs(s.position - 0.085) < 1e-9][0]
    assert mouth.insertion is not None


def test_interface_candidates_put_their_joint_at_the_site_and_into_the_model_file():
    site = [s for s in interface_sites(HOLDER_TOOL) if abs(s.position - 0.085) < 1e-9][0]
    point = InterfaceJoint(HOLDER_TOOL, site, damped=True)
    m = point.apply(HOLDER_TOOL, {"k_x": 2e8, "k_ry": 3e5, "eta_joint": 0.1})
    doc = model_to_dict(m)
    assert doc["joints"][0]["position"] == pytest.approx(0.085) and doc["joints"][0]["loss_factor"] == 0.1
    contact = InterfaceContact(HOLDER_TOOL, site, damped=False)
    # the thinner part (the tool) continues into the holder bore, towards the clamp
    assert contact.inner_is_upper
    m2 = contact.apply(HOLDER_TOOL, {"k_contact": 5e11, "insertion": 0.03})
    ins = model_to_dict(m2)["insertions"][0]
    assert ins["start"] == pytest.approx(0.055) and ins["end"] == pytest.approx(0.085) and ins["joined_at"] == "end"
    # across: k'; against relative rotation of the sections: k' r^2/2 (axial shear of an isotropic layer, r = 6 mm)
    assert ins["contact"]["stiffness_per_length"] == pytest.approx({"x": 5e11, "ry": 5e11 * 0.006**2 / 2})
    # the insertion cannot be longer than the host segment (40 mm here)
    assert contact.params[1].upper <= 0.04 + 1e-12
    assert m2.modes(1).freq_hz[0] < HOLDER_TOOL.modes(1).freq_hz[0]
    assert point.position == contact.position == pytest.approx(0.085)


def test_bonded_insertion_contact_candidate_replaces_the_tie():
    bonded = HOLDER_TOOL.with_ingredient(Insertion(0.06, 0.085, 0.012, material="carbide"))
    site = [s for s in interface_sites(bonded) if abs(s.position - 0.085) < 1e-9][0]
    c = InterfaceContact(bonded, site)
    assert [q.name for q in c.params] == ["k_contact"]          # the length is the model's own
    m = c.apply(bonded, {"k_contact": 1e12})
    ins = [i for i in m.ingredients if isinstance(i, Insertion)]
    assert len(ins) == 1 and not ins[0].rigid and ins[0].start == pytest.approx(0.06)


def test_microslip_law_softens_and_damps_monotonically_with_level():
    site = [s for s in interface_sites(HOLDER_TOOL) if abs(s.position - 0.085) < 1e-9][0]
    mj = MicroslipJoint(HOLDER_TOOL, site, (0.5, 5.0, 25.0))
    v = {"k_x": 1e8, "k_ry": 1e5, "eta_0": 0.05, "force_slip": 5.0, "s_max": 0.5, "eta_max": 0.3}
    states = [mj.state(v, i) for i in range(3)]
    assert all(a[0] > b[0] and a[1] < b[1] for a, b in zip(states, states[1:]))
    # r = F/F_slip = 1 at the middle level: half of the softening and of the extra loss
    assert states[1] == pytest.approx((0.75, 0.2))
    mc = MicroslipContact(HOLDER_TOOL, site, (0.5, 5.0, 25.0))
    assert {"k_contact", "insertion", "force_slip"} <= {q.name for q in mc.params}
    # unknown levels: a stiffness scale and a loss per level instead of the law
    free = MicroslipJoint(HOLDER_TOOL, site, (None, None))
    assert {"s_2", "eta_2"} <= {q.name for q in free.params} and not free.law
    rows = mj.level_table(v)
    assert [r["level"] for r in rows] == [0.5, 5.0, 25.0] and rows[2]["k_x_n_per_m"] < rows[0]["k_x_n_per_m"]


def test_screening_keeps_every_site_of_a_small_model_and_trims_a_large_one():
    sites = interface_sites(HOLDER_TOOL)
    assert screen_sites(HOLDER_TOOL, sites, [], keep=6) == sites
    assert len(screen_sites(HOLDER_TOOL, sites, [], keep=2)) == 3     # no paired modes: nearest first few


def test_plausible_range_shrinks_the_bic_gain_and_is_reported():
    q = Param("diameter", "m", 0.006, 0.014, 0.01, plausible=(0.0097, 0.0103))
    assert q.implausibility(0.01) == 0.0
    assert q.implausibility(0.011) == pytest.approx((np.log(0.011) - np.log(0.0103)) /
                                                    (np.log(0.0103) - np.log(0.0097)))
    seg = Segment(0.04, 0.026, 0.012)
    plain = EffectiveDiameter(1, seg, free_end=False)
    nominal = Fit(None, {}, {}, 1.0, 100, 0, 0.0, 1.0, np.ones(1))
    fit = Fit(plain, {"diameter": 0.026 * 1.10, "mass_diameter": 0.026}, {}, 0.1, 100, 2, -500.0, 0.1, np.ones(1))
    _plausibility(fit, nominal)
    assert "diameter" in fit.implausible and -500.0 < fit.score < 0.0
    ok = Fit(plain, {"diameter": 0.026 * 1.01, "mass_diameter": 0.026}, {}, 0.1, 100, 2, -500.0, 0.1, np.ones(1))
    _plausibility(ok, nominal)
    assert ok.implausible == {} and ok.score == -500.0
    # only the section at the free end may be fluted
    assert _free_end_segment(HOLDER_TOOL) == 3


def test_separating_measurement_names_what_tells_two_explanations_apart():
    site_a, site_b = interface_sites(HOLDER_TOOL)[0], interface_sites(HOLDER_TOOL)[2]

    def fit(c):
        return Fit(c, {}, {}, 1.0, 10, 1, 0.0, 0.1, np.ones(1))

    a, b = fit(InterfaceJoint(HOLDER_TOOL, site_a)), fit(InterfaceJoint(HOLDER_TOOL, site_b))
    text = separating_measurement(a, b, n_levels=1, n_points=2)
    assert "between z = 45 and 85 mm" in text
    d = fit(EffectiveDiameter(1, HOLDER_TOOL.segments[1]))
    assert "both sides of the interface" in separating_measurement(a, d, 1, 2)


def test_a_place_that_already_has_a_joint_is_not_offered_again():
    m = HOLDER_TOOL.with_ingredient(Joint(0.045, {"x": 1e9, "ry": 1e6}))
    assert 0.045 not in [round(s.position, 6) for s in interface_sites(m)]


def test_screening_ranks_the_joint_site_first_from_the_frequency_shifts_it_causes():
    # eight steps, seven sites: a joint at each in turn; the first-order sensitivity screening must
    # rank that site first from the shifts of modes 1-4 alone (noise-free, so no tolerance)
    from types import SimpleNamespace as NS

    segs = tuple(Segment(0.02, d) for d in (0.05, 0.045, 0.04, 0.035, 0.03, 0.025, 0.02, 0.016))
    m = BeamModel(segs, points=(NamedPoint("tip", 0.16, 1),), ingredients=(Clamp(0.0),))
    sites = interface_sites(m)
    assert len(sites) == 7
    f0 = m.modes(4).freq_hz
    for s in sites:
        f1 = m.with_ingredient(Joint(s.position, {"x": 5e8, "ry": 2e5})).modes(4).freq_hz
        pairs = [NS(model=NS(freq_hz=a), shift=b / a - 1) for a, b in zip(f0, f1)]
        assert screen_sites(m, sites, pairs, keep=3)[0] == s
