"""Benchmark cases on a tool-in-holder stack (truth: :mod:`._truth_stack`).

The hidden effect sits at the holder–tool interface, inside the stack, not at
the clamp:

``interface_joint``
    a linear, lossy contact layer over the insertion (k' = 1e11–2e12 N/m²,
    η_c = 0–0.5, a random pressure profile);
``interface_softening``
    a micro-slip contact (stiffness falls, loss rises with the local relative
    displacement amplitude), recorded at 0.5, 5 and 25 N; the slip amplitude is
    chosen per case so that the first-mode peak moves down by 1.5–3.5 % from
    the lowest to the highest level;
``interface_none``
    the null case on the same geometry: a practically rigid contact
    (k' ≥ 1e15 N/m²) and a nominal model that states the rigid insertion.

In every case the holder's base sits on spindle-face springs (with a loss
factor) stiff enough that a rigid clamp changes modes 1–3 by 0.005–0.015 % at
most (measured and recorded): the nominal model (a rigid clamp) is never
exactly the truth, but the difference stays below what the recordings resolve.

The nominal model is what a user would write: holder body and nose (with its
bore) from the spindle face (rigid ``Clamp`` at z = 0), then the tool from the
holder face to the tip; Rayleigh damping fitted to 1 % in the truth's first
two modes; named points at the tip, on the tool near the holder face and
sometimes on the holder nose. The inserted shank is either left out (variant
"a") or stated as a rigidly tied insertion (variant "b", the model-file field
``"insertions"``); the null case always uses "b".
"""

from __future__ import annotations

import numpy as np

from jointdb.diagnose_bench._measure import BenchCase, dof_labels, lines, record
from jointdb.diagnose_bench._truth_stack import CARBIDE, STEEL, ToolInHolder

__all__ = ["STACK_EFFECTS", "LEVELS_N", "generate_stack_case", "stack_geometry", "nominal_stack_model"]

STACK_EFFECTS: tuple[str, ...] = ("interface_joint", "interface_softening", "interface_none")
#: excitation force amplitudes [N] of the amplitude-dependent cases
LEVELS_N: tuple[float, ...] = (0.5, 5.0, 25.0)
#: range of the largest rigid-clamp change of modes 1–3 (the spindle face is stiff but not rigid).
#: With 1 % damping and 1–2 % noise a change of 2e-4 is already found by the diagnosis (a clamp
#: joint improves a null case 1.2×; 3.5e-4: 1.33×), so the face stays below that: 0.5–1.5e-4.
BASE_SHIFT = (0.00005, 0.00015)
#: range of the first-mode shift from the lowest to the highest level (softening cases)
SOFTENING_SHIFT = (0.015, 0.035)
TOOL_MATERIAL = "tool-carbide"
#: the nominal's largest element [m]: at 5 mm its own discretisation error (mode 3 about 5e-4 high
#: on these 0.1-0.2 m stacks) is already visible at 1-2 % noise and 1 % damping; 3 mm keeps it ≲ 2e-4
NOMINAL_ELEMENT = 0.003
#: elements over the insertion in the amplitude-dependent cases (the contact is lumped at their
#: nodes; 2.5–5.6 mm long, which keeps harmonic balance cheap); linear cases use the 2 mm mesh
CONTACT_ELEMENTS = 8


def _r(x, nd=4):
    return round(float(x), nd)


def stack_geometry(rng) -> dict:
    """Random holder and tool dimensions [m] (all positions from the spindle face)."""
    d_s = _r(rng.uniform(0.010, 0.020))
    ins = _r(rng.uniform(0.020, 0.045))
    stick = _r(rng.uniform(0.040, 0.080))
    flute = _r(rng.uniform(0.4, 0.6) * stick)
    body_l, body_d = _r(rng.uniform(0.030, 0.050)), _r(rng.uniform(0.040, 0.050))
    nose_l = _r(ins + rng.uniform(0.005, 0.020))
    nose_d = _r(d_s + 2 * rng.uniform(0.006, 0.010))
    z_face = _r(body_l + nose_l, 6)
    tip = _r(z_face + stick, 6)
    g = dict(body_length=body_l, body_diameter=body_d, nose_length=nose_l, nose_diameter=nose_d,
             shank_diameter=d_s, flute_diameter=_r(0.8 * d_s, 5), insertion=ins, stick_out=stick,
             flute_length=flute, z_face=z_face, tip=tip, flute_start=_r(tip - flute, 6),
             shank_point=_r(z_face + rng.uniform(0.004, 0.008), 6))
    g["nose_point"] = _r(z_face - rng.uniform(0.004, 0.010), 6) if rng.random() < 0.5 else None
    return g


def _points(g) -> dict:
    """name -> (node label, part, z)."""
    pts = {"tip": (1, "tool", g["tip"]), "shank": (2, "tool", g["shank_point"])}
    if g["nose_point"] is not None:
        pts["holder_nose"] = (3, "holder", g["nose_point"])
    return pts


def _truth(g, kprime, profile, contact_elements=None) -> ToolInHolder:
    zf, ins = g["z_face"], g["insertion"]
    holder = [(0.0, g["body_length"], g["body_diameter"], 0.0, STEEL),
              (g["body_length"], zf, g["nose_diameter"], g["shank_diameter"], STEEL)]
    tool = [(zf - ins, g["flute_start"], g["shank_diameter"], 0.0, CARBIDE),
            (g["flute_start"], g["tip"], g["flute_diameter"], 0.0, CARBIDE)]
    extra = [z for _, _, z in _points(g).values()]
    return ToolInHolder.build(holder, tool, zf, ins, g["tip"], kprime, profile=profile, h=0.002,
                              extra_breaks=extra, contact_nodes=contact_elements)


def _fit_base(stack, rng, target):
    """Spindle-face springs (k_x, k_θ) whose rigid-clamp change of modes 1–3 is ``target`` at most."""
    ratio = float(np.exp(rng.uniform(np.log(0.5), np.log(2.0))))
    shape = np.array([1.0e10, 3.0e7 * ratio])
    c = 1.0
    for _ in range(30):          # the shift is ∝ 1/c for a stiff base: a few fixed-point steps
        shift = float(stack.with_(base=tuple(c * shape)).rigid_clamp_shift().max())
        if abs(shift / target - 1) < 0.02:
            break
        c *= shift / target
    base = tuple(float(v) for v in c * shape)
    return base, stack.with_(base=base).rigid_clamp_shift()


def nominal_stack_model(g, variant: str, damping) -> dict:
    """The jointdb model-file dict a user would write for this stack (``variant`` "a" or "b")."""
    seg = [
        {"length": g["body_length"], "outer_diameter": g["body_diameter"], "material": "steel",
         "label": "holder body"},
        {"length": g["nose_length"], "outer_diameter": g["nose_diameter"], "inner_diameter": g["shank_diameter"],
         "material": "steel", "label": "holder nose"},
        {"length": _r(g["stick_out"] - g["flute_length"]), "outer_diameter": g["shank_diameter"],
         "material": TOOL_MATERIAL, "label": "tool shank"},
        {"length": g["flute_length"], "outer_diameter": g["flute_diameter"], "material": TOOL_MATERIAL,
         "label": "tool flutes"},
    ]
    model = {
        "format": "jointdb-beam-model/1",
        "name": "carbide tool in a shrink-fit holder (nominal, rigid clamp at the spindle face)",
        "theory": "timoshenko",
        "max_element_length": NOMINAL_ELEMENT,
        "materials": {TOOL_MATERIAL: dict(CARBIDE)},
        "segments": seg,
        "points": [{"name": n, "position": z, "node": node} for n, (node, _, z) in _points(g).items()],
        "clamps": [{"position": 0.0}],
        "damping": [{"type": "rayleigh", "alpha": damping[0], "beta": damping[1]}],
    }
    if variant == "b":
        model["insertions"] = [{"start": _r(g["z_face"] - g["insertion"], 6), "end": g["z_face"],
                                "outer_diameter": g["shank_diameter"], "inner_diameter": 0.0,
                                "material": TOOL_MATERIAL, "joined_at": "end", "contact": "rigid"}]
    return model


def _rayleigh(stack, zeta=0.01):
    w = 2 * np.pi * stack.natural_frequencies(2)
    A = np.array([[1 / (2 * w[0]), w[0] / 2], [1 / (2 * w[1]), w[1] / 2]])
    a, b = np.linalg.solve(A, [zeta, zeta])
    return float(a), float(b)


def _micro_slip(a_c, s_max, eta0, eta_max):
    def law(a):
        r = a / a_c
        return 1.0 - s_max * r / (1.0 + r), eta0 + eta_max * r / (1.0 + r)
    return law


def _first_peaks(stack, law, f1, tip, levels):
    """Noise-free first peak [Hz] of the tip receptance at each level (parabolic refinement)."""
    f = np.linspace(0.6 * f1, 1.02 * f1, 161)          # wide: a strongly slipped contact moves mode 1 far
    H = np.abs(stack.receptance_amplitude_dependent(f, [tip], [tip], levels, law)[:, :, 0, 0])
    out = []
    for h in H:
        i = int(np.clip(np.argmax(h), 1, f.size - 2))
        y0, y1, y2 = h[i - 1], h[i], h[i + 1]
        den = y0 - 2 * y1 + y2
        out.append(float(f[i] + (0.5 * (y0 - y2) / den if den != 0 else 0.0) * (f[1] - f[0])))
    return np.array(out)


def _tune_slip(stack, rng, f1, tip, target):
    """Slip amplitude a_c giving a first-mode shift ``target`` between the lowest and highest level."""
    s_max = float(rng.uniform(0.5, 0.8))
    eta_max = float(rng.uniform(0.2, 0.4))
    eta0 = stack.contact_loss
    x = stack.receptance(np.array([f1]), [("tool", z) for z in stack.contact_z()], [tip])
    a_ref = float(np.abs(x).max()) * LEVELS_N[1]       # a displacement scale to start the search from
    ends = [LEVELS_N[0], LEVELS_N[-1]]

    def shift(log_ac):
        p = _first_peaks(stack, _micro_slip(np.exp(log_ac), s_max, eta0, eta_max), f1, tip, ends)
        return 1.0 - p[1] / p[0]

    hi = np.log(a_ref) + np.log(100.0)     # nearly linear at every level
    prev, best = hi, (0.0, hi)
    for k in range(1, 17):                 # step a_c down until the shift reaches the target
        x_ = hi - k * np.log(10.0) / 4
        s = shift(x_)
        if s >= target:
            break
        best, prev = max(best, (s, x_)), x_
    else:                                  # not reachable: the largest shift found
        return best[1], s_max, eta0, eta_max, ends
    a, b = prev, x_
    for _ in range(7):                      # bisection in log a_c
        m = 0.5 * (a + b)
        if shift(m) >= target:
            b = m
        else:
            a = m
    return 0.5 * (a + b), s_max, eta0, eta_max, ends


def generate_stack_case(effect: str, seed: int, rng) -> BenchCase:
    """One seeded stack case (``effect`` in :data:`STACK_EFFECTS`)."""
    g = stack_geometry(rng)
    variant = "b" if effect == "interface_none" else str(rng.choice(["a", "b"]))
    pa, pb = float(rng.uniform(-0.6, 0.6)), float(rng.uniform(-0.3, 0.3))

    def profile(zeta):       # pressure profile along the insertion (shifted Legendre P1, P2)
        return np.maximum(1 + pa * (2 * zeta - 1) + pb * (6 * zeta**2 - 6 * zeta + 1), 0.05)

    if effect == "interface_none":
        kprime = float(np.exp(rng.uniform(np.log(1e16), np.log(1e17))))
    elif effect == "interface_joint":
        kprime = float(np.exp(rng.uniform(np.log(1e11), np.log(2e12))))
    else:
        kprime = float(np.exp(rng.uniform(np.log(1e11), np.log(8e11))))
    eta_c = float(rng.uniform(0.0, 0.5)) if effect != "interface_softening" else float(rng.uniform(0.0, 0.1))
    coarse = CONTACT_ELEMENTS if effect == "interface_softening" else None
    stack = _truth(g, kprime, profile, coarse).with_(contact_loss=eta_c, base_loss=float(rng.uniform(0.02, 0.08)))
    base, clamp_shift = _fit_base(stack, rng, float(rng.uniform(*BASE_SHIFT)))
    stack = stack.with_(base=base)
    alpha, beta = _rayleigh(stack)
    stack = stack.with_(rayleigh=(alpha, beta))
    f123 = stack.natural_frequencies(3)
    pts = _points(g)
    tip = ("tool", g["tip"], "x")
    truth = {"effect": effect, "interface_z_m": g["z_face"], "insertion_m": g["insertion"],
             "contact_stiffness_n_per_m2": kprime, "contact_loss": eta_c,
             "pressure_profile_p1_p2": [pa, pb], "nominal_variant": variant,
             "base_stiffness": {"x_n_per_m": base[0], "theta_nm_per_rad": base[1]},
             "base_loss": stack.base_loss, "rigid_clamp_shift_modes_1_3": [float(v) for v in clamp_shift],
             "natural_frequencies_hz": [float(v) for v in f123], "truth": "two concentric beams (tool in holder)"}
    outs = [(part, z, "x") for _, part, z in pts.values()]
    ins = outs[:2]
    if effect == "interface_softening":
        target = float(rng.uniform(*SOFTENING_SHIFT))
        log_ac, s_max, eta0, eta_max, _ = _tune_slip(stack, rng, float(f123[0]), tip, target)
        law = _micro_slip(float(np.exp(log_ac)), s_max, eta0, eta_max)
        peaks = _first_peaks(stack, law, float(f123[0]), tip, list(LEVELS_N))
        f_max = 1.25 * float(f123[1])
        truth.update(slip_amplitude_m=float(np.exp(log_ac)), max_softening=s_max, max_loss=eta_max,
                     levels_n=list(LEVELS_N), first_peak_hz_per_level=[float(p) for p in peaks],
                     first_mode_shift=float(1 - peaks[-1] / peaks[0]), target_first_mode_shift=target)
        levels = list(LEVELS_N)
    else:
        f_max = 1.25 * float(f123[2])
        levels = [None]
    n_lo, n_hi = (600, 2000) if effect == "interface_softening" else (800, 3200)   # lines in the band
    ok = [d for d in (2.5, 5.0, 10.0) if n_lo <= f_max / d <= n_hi] or [10.0]
    df = float(rng.choice(ok))
    freq, fine = lines(f_max, df)
    if effect == "interface_softening":
        H_all = stack.receptance_amplitude_dependent(fine, outs, ins, levels, law)
    else:
        H_all = stack.receptance(fine, outs, ins)[None]
    labels = dof_labels(node for node, _, _ in pts.values())
    recs, noise = [], []
    for H, level in zip(H_all, levels):
        rec, rel = record(rng, freq, H, labels, labels[:2], level=level)
        recs.append(rec)
        noise.append(rel)
    truth.update(noise_rel=noise, resolution_hz=df, geometry=g)
    model = nominal_stack_model(g, variant, (alpha, beta))
    pmap = {node: name for name, (node, _, _) in pts.items()}
    return BenchCase(name=f"{effect}-{seed}", effects=(effect,), seed=seed, truth=truth,
                     model=model, recordings=tuple(recs), point_map=pmap)
