"""Joints *inside* the stack: at every interface, not only at the clamp.

In a tool / holder / spindle assembly the compliant joint that matters most is
between two parts — the tool in the holder bore, the holder in the spindle, a
bolted flange — not at the model's boundary. Every place where such a joint can
sit is a *site*:

- every segment boundary where the section or the material changes;
- every named point strictly inside the model;
- the mouth of every inserted part the model already has (an
  :class:`jointdb.fe.Insertion`, bonded in the nominal model).

At each site three kinds of joint are offered:

``interface_joint[_damped]@z``
    a point joint that splits the beam (:class:`jointdb.fe.Joint`):
    translational ``k_x`` and rotational ``k_ry`` stiffness, and in the damped
    variant one hysteretic loss factor η;
``interface_contact[_damped]@z``
    a distributed contact joint over an overlap: the smaller part continues
    inside the larger one over an insertion length ``L`` and rests on a contact
    layer of stiffness ``k'`` per length across and ``k' r²/2`` against relative
    rotation of the sections (:class:`jointdb.fe.Insertion` with a
    :class:`jointdb.fe.Contact`), optionally with a loss factor. At the mouth of
    an existing bonded insertion, its tie is replaced by the contact layer (the
    length is the model's own);
``interface_microslip@z``
    (with recordings at several excitation levels) a point joint whose
    stiffness falls and whose loss rises with the excitation (see
    :mod:`jointdb.diagnose.physics.microslip`).

Each candidate carries its ``position`` [m] and a ``location`` in words, so the
verdict can say where the joint is. Sites are screened cheaply before fitting
(:func:`screen_sites`): the recorded shift of every paired mode is compared
with the shift a small joint compliance at the site would cause (first-order
eigenvalue sensitivity), so adding sites does not multiply the run time.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.optimize

from jointdb.diagnose.physics._candidate import Candidate, Param, register
from jointdb.diagnose.physics._util import full_clamps, swap_ingredients
from jointdb.fe import Contact, Insertion, Joint, get_material

__all__ = ["Site", "interface_sites", "screen_sites", "InterfaceJoint", "InterfaceContact", "SITES_KEPT"]

#: Sites kept for fitting after the screening (the clamp's own candidates are always fitted). A fit at
#: one site costs ~1 s on a tool-in-holder model, so a stack with up to this many sites is fitted at all
#: of them; the first-order screening only trims models with more (it cannot tell sites apart reliably
#: from frequencies alone: the mode *shapes* at the measured points decide between them).
SITES_KEPT = 6


@dataclass(frozen=True)
class Site:
    """A place where a joint can sit: ``position`` [m], a description, the adjacent sections."""

    position: float
    location: str
    lower: int                   # index of the segment below (z < position)
    upper: int                   # index of the segment above
    insertion: object = None     # an existing bonded Insertion whose mouth is here


def _ei(seg) -> float:
    m = get_material(seg.material)
    return m.E * np.pi * (seg.outer_diameter**4 - seg.inner_diameter**4) / 64.0


def _section_text(seg) -> str:
    m = get_material(seg.material)
    return f"⌀{seg.outer_diameter * 1e3:.3g} mm {m.name}"


def interface_sites(model) -> list[Site]:
    """Candidate joint positions of ``model`` (see the module docstring), ascending z."""
    segs = model.segments
    ends = np.concatenate([[0.0], np.cumsum([s.length for s in segs])])
    length = float(ends[-1])
    tol = max(1e-6, 1e-4 * length)
    taken = [c.position for c in full_clamps(model)]
    taken += [i.position for i in model.ingredients if isinstance(i, Joint)]
    inserted = {round(i.mouth, 9): i for i in model.ingredients if isinstance(i, Insertion) and i.rigid}
    taken += [i.mouth for i in model.ingredients if isinstance(i, Insertion) and not i.rigid]

    def seg_at(z):
        k = int(np.clip(np.searchsorted(ends, z, side="right") - 1, 0, len(segs) - 1))
        return k

    sites: dict[float, Site] = {}
    for k in range(len(segs) - 1):
        a, b = segs[k], segs[k + 1]
        z = float(ends[k + 1])
        same = (abs(a.outer_diameter - b.outer_diameter) <= 1e-9 and abs(a.inner_diameter - b.inner_diameter)
                <= 1e-9 and get_material(a.material) == get_material(b.material))
        if same and round(z, 9) not in inserted:
            continue
        sites[z] = Site(z, f"the step from {_section_text(a)} to {_section_text(b)} (z = {z * 1e3:.4g} mm)", k, k + 1)
    for p in model.points:
        z = p.position
        if not tol < z < length - tol:
            continue
        near = [s for s in sites if abs(s - z) <= tol]
        if near:
            s = sites[near[0]]
            sites[near[0]] = Site(s.position, s.location[:-1] + f", point {p.name!r})", s.lower, s.upper)
            continue
        k = seg_at(z)
        sites[z] = Site(z, f"point {p.name!r} (z = {z * 1e3:.4g} mm)", k, k)
    for z, ins in inserted.items():
        near = [s for s in sites if abs(s - z) <= tol]
        if near:
            s = sites.pop(near[0])
            sites[s.position] = Site(s.position, s.location, s.lower, s.upper, ins)
    out = [s for z, s in sorted(sites.items()) if all(abs(z - t) > tol for t in taken) and tol < z < length - tol]
    return out


def _reference_stiffness(model, site: Site) -> tuple[float, float]:
    """(k_x, k_ry) scales: a cantilever of the smaller section from the site to the far free end."""
    segs = model.segments
    ei = min(_ei(segs[site.lower]), _ei(segs[site.upper]))
    clamps = [c.position for c in full_clamps(model)]
    if clamps:
        far = model.length - site.position if clamps[0] < site.position else site.position
    else:
        far = min(site.position, model.length - site.position)
    far = max(far, 0.05 * model.length)
    return 3 * ei / far**3, ei / far


def _planes(model) -> tuple[tuple[str, str], ...]:
    return (("x", "ry"),) if model.kind == "planar" else (("x", "ry"), ("y", "rx"))


class _Located(Candidate):
    """A candidate at a site: ``position`` [m] and ``location`` (words)."""

    site: Site

    @property
    def position(self) -> float:
        return self.site.position

    @property
    def location(self) -> str:
        return self.site.location


class InterfaceJoint(_Located):
    """A point joint splitting the beam at a site (translational + rotational, optional loss)."""

    def __init__(self, model, site: Site, damped: bool = False):
        self.site = site
        self.damped = damped
        self.planes = _planes(model)
        self.family = "joint_damping" if damped else "joint_compliance"
        self.slot = f"interface@{site.position:.6g}"
        self.name = f"interface_joint{'_damped' if damped else ''}@{site.position * 1e3:.4g}mm"
        self.explanation = (f"a compliant joint{' with its own damping' if damped else ''} at {site.location} "
                            "instead of a rigid connection")
        kx, kr = _reference_stiffness(model, site)
        ps = [Param("k_x", "N/m", 0.3 * kx, 1e5 * kx, 100 * kx, show=1e-6, show_unit="N/µm",
                    starts=(10 * kx, 3000 * kx), either="stiffness"),
              Param("k_ry", "N·m/rad", 0.03 * kr, 1e4 * kr, 10 * kr, show=1e-3, show_unit="kN·m/rad",
                    starts=(1 * kr, 300 * kr), either="stiffness")]
        if damped:
            ps.append(Param("eta_joint", "-", 1e-3, 2.0, 0.1, starts=(0.4,), plausible=(1e-3, 1.0), key=False))
        self.params = tuple(ps)

    def joint(self, values, scale: float = 1.0, eta: float | None = None) -> Joint:
        k = {}
        for t, r in self.planes:
            k[t] = values["k_x"] * scale
            k[r] = values["k_ry"] * scale
        loss = values.get("eta_joint", 0.0) if eta is None else eta
        return Joint(self.site.position, k, loss_factor=loss, label=self.site.location)

    def apply(self, model, values, level=0):
        return model.with_ingredient(self.joint(values))

    def describe(self, values, sigmas=None):
        sigmas = sigmas or {}
        parts = ", ".join(f"{p.name} = {p.fmt(values[p.name], sigmas.get(p.name))}" for p in self.params)
        return (f"a compliant joint{' with its own damping' if self.damped else ''} at {self.site.location} "
                f"({parts})")


class InterfaceContact(_Located):
    """A distributed contact joint over an overlap at a site (see the module docstring)."""

    def __init__(self, model, site: Site, damped: bool = False):
        self.site = site
        self.damped = damped
        segs = model.segments
        self.family = "joint_damping" if damped else "joint_compliance"
        self.slot = f"interface@{site.position:.6g}"
        self.name = f"interface_contact{'_damped' if damped else ''}@{site.position * 1e3:.4g}mm"
        ps = []
        if site.insertion is not None:
            ins = site.insertion
            self.existing = ins
            d = ins.outer_diameter
            self.explanation = (f"a compliant contact{' with its own damping' if damped else ''} between the "
                                f"inserted part and its host over {ins.length * 1e3:.3g} mm at {site.location}, "
                                "instead of a bonded one")
        else:
            self.existing = None
            lo, up = segs[site.lower], segs[site.upper]
            # the thinner part continues inside the thicker one (a tool in the holder bore)
            self.inner_is_upper = up.outer_diameter <= lo.outer_diameter
            inner = up if self.inner_is_upper else lo
            self.section = inner
            d = inner.outer_diameter
            host_room = self._room(model)
            hi = min(4.0 * d, host_room)
            if hi < 0.5 * d:
                raise ValueError("no room for an insertion here")
            self.explanation = (f"a compliant contact{' with its own damping' if damped else ''} over an "
                                f"insertion: the ⌀{d * 1e3:.3g} mm part continues inside its neighbour at "
                                f"{site.location} and rests on a contact layer, instead of a rigid connection")
            ps.append(Param("insertion", "m", 0.5 * d, hi, min(2.5 * d, 0.7 * hi), show=1e3, show_unit="mm",
                            equivalent=True, either="contact"))
        ps.insert(0, Param("k_contact", "N/m²", 1e10, 1e14, 1e12, show=1e-9, show_unit="GN/m²", starts=(2e11, 5e12),
                           equivalent=True, either="contact"))
        if damped:
            ps.append(Param("eta_joint", "-", 1e-3, 2.0, 0.1, starts=(0.4,), plausible=(1e-3, 1.0), key=False))
        self.params = tuple(ps)
        self.planes = _planes(model)

    def _room(self, model) -> float:
        """Length of host available beyond the site (up to the host segment's far end or a clamp)."""
        z = self.site.position
        ends = np.concatenate([[0.0], np.cumsum([s.length for s in model.segments])])
        stops = list(ends) + [c.position for c in full_clamps(model)]
        if self.inner_is_upper:
            below = [s for s in stops if s < z - 1e-9]
            return z - max(below)
        above = [s for s in stops if s > z + 1e-9]
        return min(above) - z

    def contact(self, values, scale: float = 1.0, eta: float | None = None) -> Contact:
        """The contact layer: ``k'`` across, and ``k' r²/2`` against relative rotation of the sections.

        A layer of equal normal and tangential stiffness ``k_a`` per area on a
        bore of radius ``r`` gives ``k' = ∮ k_a (cos²φ + sin²φ) r dφ = 2π r k_a``
        per length against relative deflection, and, through the axial shear at
        ``r cos φ``, ``k_θ' = ∮ k_a (r cos φ)² r dφ = π r³ k_a = k' r²/2`` against
        relative rotation of the two sections (which a Timoshenko shank would
        otherwise be free to take).
        """
        r = 0.5 * (self.existing.outer_diameter if self.existing is not None else self.section.outer_diameter)
        k = {}
        for t, rot in self.planes:
            k[t] = values["k_contact"] * scale
            k[rot] = values["k_contact"] * scale * r * r / 2.0
        loss = values.get("eta_joint", 0.0) if eta is None else eta
        return Contact(k, loss_factor=loss)

    def apply(self, model, values, level=0):
        z = self.site.position
        if self.existing is not None:
            new = Insertion(self.existing.start, self.existing.end, self.existing.outer_diameter,
                            self.existing.inner_diameter, self.existing.material, self.existing.joined_at,
                            self.contact(values), self.existing.label)
            return swap_ingredients(model, lambda i: i is self.existing or i == self.existing, new)
        L = float(values["insertion"])
        s = self.section
        start, end, joined = (z - L, z, "end") if self.inner_is_upper else (z, z + L, "start")
        return model.with_ingredient(Insertion(start, end, s.outer_diameter, s.inner_diameter, s.material, joined,
                                               self.contact(values), label=self.site.location))


def _sensitivities(model, site: Site, modes: np.ndarray, n: int) -> np.ndarray | None:
    """``(n, 2)``: relative change of λ_r per unit *relative* compliance in x and in ry at ``site``.

    First order in the compliance: a stiff joint (1000 × the reference
    stiffness) changes λ by ``−V_r²/k`` (shear) or ``−M_r²/k`` (moment); the
    columns are ``−Δλ/λ × 1000`` so that a joint at the reference stiffness
    scales them by one.
    """
    from jointdb.errors import InputError, NumericalError

    kx, kr = _reference_stiffness(model, site)
    lam0 = (2 * np.pi * modes[:n]) ** 2
    cols = []
    planes = _planes(model)
    for which in ("x", "ry"):
        k = {}
        for t, r in planes:
            k[t if which == "x" else r] = 1e3 * (kx if which == "x" else kr)
        try:
            f = model.with_ingredient(Joint(site.position, k)).modes(n).freq_hz
        except (InputError, NumericalError, np.linalg.LinAlgError):
            return None
        lam = (2 * np.pi * f[:n]) ** 2
        cols.append(-(lam / lam0 - 1) * 1e3)
    return np.column_stack(cols)


def screen_sites(model, sites: list[Site], pairs, keep: int = SITES_KEPT) -> list[Site]:
    """The ``keep`` sites whose joint compliance best explains the recorded frequency shifts.

    ``pairs``: the paired modes of the nominal comparison (each with
    ``model.freq_hz`` and ``shift``). For each site, the observed relative
    eigenvalue changes ``y_r = (1 + shift_r)² − 1`` are fitted by non-negative
    compliances in x and ry times the site's first-order sensitivities; sites
    are ranked by the relative residual ``‖y − S c‖ / ‖y‖``. With fewer than
    two paired modes nothing can be told apart and the first ``keep + 1`` sites
    by proximity to the largest mismatch are kept.
    """
    if len(sites) <= keep:
        return list(sites)
    good = [p for p in pairs if np.isfinite(p.shift)]
    if len(good) < 2:
        return list(sites)[: keep + 1]
    modes = model.modes(12).freq_hz
    y, idx = [], []
    for p in good:
        r = int(np.argmin(np.abs(modes - p.model.freq_hz)))
        if r not in idx:
            idx.append(r)
            y.append((1 + p.shift) ** 2 - 1)
    y = np.asarray(y)
    m = max(idx) + 1
    scores = []
    for s in sites:
        S = _sensitivities(model, s, modes, m)
        if S is None:
            scores.append(np.inf)
            continue
        A = -S[idx]
        c, res = scipy.optimize.nnls(A, y)
        scores.append(res / max(np.linalg.norm(y), 1e-12))
    order = np.argsort(scores, kind="stable")
    return [sites[i] for i in order[:keep]]


@register
def _factory(ctx):
    out = []
    for site in interface_sites(ctx.model):
        out += [InterfaceJoint(ctx.model, site), InterfaceJoint(ctx.model, site, damped=True)]
        if site.lower == site.upper and site.insertion is None:
            continue            # a point inside one segment: nothing is inserted there
        for damped in (False, True):
            try:
                out.append(InterfaceContact(ctx.model, site, damped=damped))
            except ValueError:
                pass
    return out
