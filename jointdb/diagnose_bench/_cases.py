"""Seeded benchmark cases: a "recording" from the richer truth beam, plus the
nominal model a user would have written, with one effect (or none) hidden.

The nominal model is a cantilevered end-mill-like tool (shank + fluted
section, rigid clamp at z = 0, Rayleigh damping fitted to ~1 % in the first
two modes). The truth adds the hidden effect with its own physics
(:mod:`jointdb.diagnose_bench._truth_fe`), and a measurement chain with
finite frequency resolution (bin-averaged lines), seeded complex noise
(proportional + floor) and a coherence estimate consistent with that noise.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.signal

from jointdb.diagnose_bench._measure import BenchCase, Recording, dof_labels, lines, record
from jointdb.diagnose_bench._stack_cases import STACK_EFFECTS, generate_stack_case
from jointdb.diagnose_bench._truth_fe import TruthBeam

__all__ = ["EFFECTS", "BenchCase", "Recording", "generate_case", "generate_suite"]

#: Effects the generator can hide ("none" = null case, nothing hidden).
EFFECTS: tuple[str, ...] = (
    "none",
    "joint_compliance",
    "joint_damping",
    "sensor_mass",
    "shear_rotary",
    "fluted_diameter",
    "hysteretic_damping",
    "gain",
    "delay",
    "softening_joint",
    *STACK_EFFECTS,
)

STEEL = dict(E=210e9, nu=0.3, rho=7800.0)
POINT_NAMES = ("tip", "flute", "shank")


def _geometry(rng):
    length = float(rng.uniform(0.12, 0.16))
    d = float(rng.uniform(0.014, 0.018))
    flute = float(rng.uniform(0.35, 0.45)) * length
    flute_ratio = 0.8          # modeller's effective flute diameter / shank diameter
    return dict(length=round(length, 4), d=round(d, 4), flute_start=round(length - flute, 4),
                d_flute=round(d * flute_ratio, 5))


def _points(g):
    return {"tip": (1, g["length"]), "flute": (2, g["flute_start"]), "shank": (3, round(0.3 * g["length"], 4))}


def _nominal(g, theory="timoshenko", damping=None):
    from jointdb.fe import BeamModel, Clamp, NamedPoint, RayleighDamping, Segment, model_to_dict

    pts = _points(g)
    model = BeamModel(
        segments=(Segment(g["flute_start"], g["d"], material="steel"),
                  Segment(g["length"] - g["flute_start"], g["d_flute"], material="steel")),
        points=tuple(NamedPoint(n, z, node=node) for n, (node, z) in pts.items()),
        ingredients=(Clamp(0.0), RayleighDamping(*damping)),
        theory=theory,
        max_element_length=0.005,
        name="end mill in holder (nominal, rigid clamp)",
    )
    return model_to_dict(model)


def _truth_beam(g, insertion=0.0, h=0.002):
    pts = _points(g)
    breaks = sorted({0.0, g["flute_start"], *(z for _, z in pts.values())})
    b = TruthBeam.cylinder(-insertion, g["length"], g["d"], STEEL["E"], STEEL["nu"], STEEL["rho"],
                           h=h, breaks=breaks)
    df = g["d_flute"]
    b.set_section(g["flute_start"], g["length"], np.pi * df**2 / 4, np.pi * df**4 / 64)
    if insertion == 0.0:
        b.clamped_nodes = [b.node_at(0.0)]
    return b


def _rayleigh_for(beam, zeta=0.01):
    """α, β giving ``zeta`` in the first two modes of the (rigidly clamped) truth."""
    w2, _, _ = beam._modes()
    w = np.sqrt(w2[:2])
    A = np.array([[1 / (2 * w[0]), w[0] / 2], [1 / (2 * w[1]), w[1] / 2]])
    a, b = np.linalg.solve(A, [zeta, zeta])
    return float(a), float(b), w / (2 * np.pi)


def _receptances(beam, g, f_max, df, levels, law=None):
    """Noise-free receptances of the beam truth on the fine grid, one per level (the recorded lines
    and the labels with them): ``(freq, [H_fine], labels)``."""
    pts = _points(g)
    nodes_out = [beam.node_at(pts[n][1]) for n in POINT_NAMES]
    outs = [2 * n for n in nodes_out]
    ins = outs[:2]
    freq, fine = lines(f_max, df)
    if law is None:
        H = beam.receptance(fine, outs, ins)
        Hs = [H] * len(levels)
    else:
        # the force acts at each input in turn; the linear receptance is shared by all levels
        Hs = beam.amplitude_dependent_levels(fine, outs, ins, levels, law)
    return freq, Hs, dof_labels(pts[n][0] for n in POINT_NAMES)


@dataclass
class _Hidden:
    """What hiding one effect changed: the truth beam, the nominal model's theory, the measurement
    chain, the excitation levels and the band's top [Hz]."""

    beam: object
    theory: str = "timoshenko"
    chain: object = None
    levels: list = field(default_factory=lambda: [None])
    f_max: float = 0.0


def _hide(effect: str, rng, g: dict, clamped, f_max: float, truth: dict) -> _Hidden:
    """Hide ``effect`` in the truth (one beam effect or chain effect; ``truth`` records its values).
    The random draws are those of the case generator, in its order."""
    h = _Hidden(beam=clamped, f_max=f_max)
    sign = lambda: float(rng.choice([-1.0, 1.0]))  # noqa: E731
    if effect in ("joint_compliance", "joint_damping", "softening_joint"):
        ins = float(rng.uniform(0.03, 0.05))
        beam = h.beam = _truth_beam(g, insertion=ins)
        if effect == "joint_damping":
            kprime = float(np.exp(rng.uniform(np.log(1e12), np.log(3e12))))
            beam.bed_loss = float(rng.uniform(0.3, 0.6))
        else:
            kprime = float(np.exp(rng.uniform(np.log(2e11), np.log(2e12))))
        slope = float(rng.uniform(0.0, 1.5))     # contact pressure rising towards the mouth
        beam.add_winkler_bed(-ins, 0.0, kprime,
                             profile=lambda z: (1 + slope * (z + ins) / ins) / (1 + slope / 2))
        truth.update(insertion_m=ins, bed_stiffness_n_per_m2=kprime, bed_loss=beam.bed_loss,
                     pressure_slope=slope)
        if effect == "softening_joint":
            h.levels = [2.0, 10.0, 50.0]
            h.f_max = 1.25 * float(np.sqrt(clamped._modes()[0][1]) / (2 * np.pi))
    elif effect == "sensor_mass":
        where = str(rng.choice(["tip", "flute"]))
        mass = float(rng.uniform(0.003, 0.010))
        size = 0.006
        z = _points(g)[where][1]
        a, b = (z - size, z) if where == "tip" else (z - size / 2, z + size / 2)
        e = g["d"] / 2 + 0.003
        rot = mass * (size**2 / 12 + 0.006**2 / 12 + e**2)
        h.beam.add_distributed_mass(a, b, mass, rot)
        truth.update(where=where, mass_kg=mass, rotary_inertia_kgm2=rot, size_m=size)
    elif effect == "shear_rotary":
        h.theory = "euler-bernoulli"
        truth.update(nominal_theory=h.theory)
    elif effect == "fluted_diameter":
        delta = sign() * float(rng.uniform(0.05, 0.12))
        d_i = g["d_flute"] * (1 + delta)
        d_a = g["d_flute"] * (1 + 0.6 * delta)
        h.beam.set_section(g["flute_start"], g["length"], np.pi * d_a**2 / 4, np.pi * d_i**4 / 64)
        truth.update(relative_error=delta, inertia_diameter_m=d_i, area_diameter_m=d_a)
    elif effect == "hysteretic_damping":
        eta = float(rng.uniform(0.01, 0.03))
        truth.update(eta=eta)
    elif effect == "gain":
        gain = 1.0 + sign() * float(rng.uniform(0.08, 0.25))
        h.chain = lambda f: np.full(f.shape, gain)  # noqa: E731
        truth.update(gain=gain)
    elif effect == "delay":
        # channel skew (a pure delay) behind an 8th-order Bessel anti-alias filter
        # with its −3 dB point at 2.5 × the top of the band (group delay adds to the skew)
        skew = float(rng.uniform(15e-6, 60e-6))
        b_, a_ = scipy.signal.bessel(8, 2 * np.pi * 2.5 * h.f_max, analog=True, norm="mag")
        h.chain = lambda f: scipy.signal.freqs(b_, a_, 2 * np.pi * f)[1] * np.exp(-2j * np.pi * f * skew)  # noqa: E731
        w_, h_ = scipy.signal.freqs(b_, a_, [2 * np.pi * 1.0, 2 * np.pi * 2.0])
        tau_filter = float(-(np.angle(h_[1]) - np.angle(h_[0])) / (w_[1] - w_[0]))
        truth.update(delay_s=skew + tau_filter, skew_s=skew, filter_group_delay_s=tau_filter,
                     filter="8th-order Bessel anti-alias filter, -3 dB at 2.5 f_max")
    return h


def _softening_law(rng, beam, g: dict, f12, levels: list, truth: dict):
    """The micro-slip law of a softening joint: stiffness scale and loss factor against the amplitude
    at the mouth, scaled on the truth beam's response at the middle level."""
    r_mouth = beam.node_at(0.0)
    ref = beam.receptance(np.linspace(0.7, 1.0, 200) * f12[0], [2 * r_mouth], [2 * beam.node_at(g["length"])])
    a_ref = float(np.abs(ref).max()) * levels[1]
    a_c = a_ref / float(rng.uniform(0.5, 2.0))
    s_max = float(rng.uniform(0.4, 0.7))
    eta_max = float(rng.uniform(0.2, 0.4))

    def law(a, a_c=a_c, s_max=s_max, eta_max=eta_max, eta0=beam.bed_loss):
        r = a / a_c
        return 1.0 - s_max * r / (1.0 + r), eta0 + eta_max * r / (1.0 + r)

    truth.update(slip_amplitude_m=a_c, max_softening=s_max, max_loss=eta_max, levels_n=levels)
    return law


def generate_case(effect: str, seed: int) -> BenchCase:
    """One seeded case with ``effect`` hidden (``"none"``: nothing hidden).

    Raises
    ------
    ValueError
        For an unknown effect name.
    """
    if effect not in EFFECTS:
        raise ValueError(f"unknown effect {effect!r}; expected one of {', '.join(EFFECTS)}")
    rng = np.random.default_rng([seed, EFFECTS.index(effect)])
    if effect in STACK_EFFECTS:
        return generate_stack_case(effect, seed, rng)
    g = _geometry(rng)
    clamped = _truth_beam(g)
    alpha, beta, f12 = _rayleigh_for(clamped)
    truth: dict = {"effect": effect}
    df = float(rng.choice([2.5, 5.0]))
    f3 = float(np.sqrt(clamped._modes()[0][2]) / (2 * np.pi))
    h = _hide(effect, rng, g, clamped, 1.25 * f3, truth)
    beam, levels = h.beam, h.levels
    if effect == "hysteretic_damping":
        beam.rayleigh = (0.0, 0.0)
        beam.structural_loss = truth["eta"]
    else:
        beam.rayleigh = (alpha, beta)
    law = _softening_law(rng, beam, g, f12, levels, truth) if effect == "softening_joint" else None

    recs = []
    noise = []
    freq, Hs, labels = _receptances(beam, g, h.f_max, df, levels, law)
    for level, H in zip(levels, Hs):
        rec, rel = record(rng, freq, H, labels, labels[:2], level=level, chain=h.chain)
        recs.append(rec)
        noise.append(rel)
    truth.update(noise_rel=noise, resolution_hz=df, geometry=g)
    model = _nominal(g, theory=h.theory, damping=(alpha, beta))
    pmap = {node: name for name, (node, _) in _points(g).items()}
    return BenchCase(name=f"{effect}-{seed}", effects=(effect,), seed=seed, truth=truth,
                     model=model, recordings=tuple(recs), point_map=pmap)


def generate_suite(n_per_effect: int, seed: int = 0, effects=EFFECTS):
    """``n_per_effect`` cases per effect, seeds ``seed .. seed+n-1`` (a generator)."""
    for effect in effects:
        for k in range(n_per_effect):
            yield generate_case(effect, seed + k)
