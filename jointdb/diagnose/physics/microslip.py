"""Amplitude-dependent (micro-slip) joints at interfaces inside the stack.

As the vibration grows, a clamped contact slips at the edges of its contact
area: its stiffness falls and its damping rises with the slip amplitude. With
recordings at several excitation levels the candidate is a point joint at an
interface site (see :mod:`jointdb.diagnose.physics.interface`), or a contact
layer over an insertion there, whose stiffness
and loss follow a describing-function law of the excitation amplitude ``F_l``
of level ``l`` (all levels fitted *jointly*, one law)::

    r_l   = F_l / F_slip
    k_l   = k₀ (1 − s_max · r_l / (1 + r_l))          (k_x and k_ry alike)
    η_l   = η₀ + η_max · r_l / (1 + r_l)

(the Iwan-type shape: linear at small amplitude, saturating when the whole
contact slips). ``F_slip`` is the excitation at which half the possible
softening has happened. When the levels' amplitudes are not known, the law
cannot be written in them and the stiffness scale and loss are fitted per level
instead (stiffness scale 1 at the first level).

When the forces are known, the FRF at every line is solved by single-harmonic
balance with the law applied to the local slip amplitude there (so the joint is
soft and lossy at a resonance and nearly linear away from it; see
:mod:`jointdb.diagnose.physics._harmonic`); the law's ``F_slip`` is then the
force at which the slip at the linear joint's largest response reaches the
half-softening amplitude. The slip amplitude each level produced at the joint (relative displacement of
the two sides at the level's first resonance) is reported with ``k(a)`` and
``η(a)`` (:meth:`MicroslipJoint.level_table`).
"""

from __future__ import annotations

import numpy as np

from jointdb.diagnose.physics._candidate import Param, register
from jointdb.diagnose.physics.interface import InterfaceContact, InterfaceJoint, Site, interface_sites

__all__ = ["MicroslipJoint", "MicroslipContact", "slip_amplitude"]


def _known_levels(levels) -> bool:
    return all(lv is not None and np.isfinite(lv) and lv > 0 for lv in levels)


def _law_params(levels) -> tuple[bool, list]:
    """Whether the describing-function law applies (levels known) and its parameters after the stiffness."""
    law = _known_levels(levels)
    extra = [Param("eta_0", "-", 1e-3, 1.0, 0.05, starts=(0.2,), plausible=(1e-3, 1.0), key=False)]
    if law:
        lv = np.asarray(levels, dtype=float)
        # the law is an equivalent (describing-function) model of the contact: its parameters are equivalent ones
        extra += [Param("force_slip", "N", lv.min() / 30, lv.max() * 30, float(np.sqrt(lv.min() * lv.max())),
                        equivalent=True, key=False),
                  # the law's saturation values extrapolate beyond the recorded levels: shown, not key (the
                  # per-level stiffness and loss the levels did reach are in the level table)
                  Param("s_max", "-", 0.0, 0.95, 0.3, log=False, equivalent=True, key=False),
                  Param("eta_max", "-", 1e-3, 1.5, 0.1, starts=(0.4,), plausible=(1e-3, 1.0), equivalent=True,
                        key=False)]
    else:
        extra += [Param(f"s_{i + 1}", "-", 0.2, 1.5, 0.95, key=False) for i in range(1, len(levels))]
        extra += [Param(f"eta_{i + 1}", "-", 1e-3, 1.0, 0.1, key=False) for i in range(1, len(levels))]
    return law, extra


def _state(law: bool, levels, values, level: int) -> tuple[float, float]:
    if law:
        r = levels[level] / values["force_slip"]
        g = r / (1 + r)
        return 1.0 - values["s_max"] * g, values["eta_0"] + values["eta_max"] * g
    if level == 0:
        return 1.0, values["eta_0"]
    return values[f"s_{level + 1}"], values[f"eta_{level + 1}"]


class _Microslip:
    """What the micro-slip joint and contact share: the law over the levels, and harmonic balance
    line by line when the levels' forces are known (see :mod:`._harmonic`)."""

    family = "softening_joint"
    per_level = True

    def _start(self, model, site: Site, levels, kind: str, what: str) -> None:
        """The undamped linear candidate at ``site`` with the law over ``levels``; named ``kind@position``."""
        super().__init__(model, site, damped=False)
        self.name = f"{kind}@{site.position * 1e3:.4g}mm"
        self.explanation = (f"an amplitude-dependent (micro-slip) {what} at {site.location} whose stiffness "
                            "falls and damping rises with the excitation")
        self.family = "softening_joint"
        self.levels = tuple(levels)
        self.law, extra = _law_params(self.levels)
        self.params = self.params + tuple(extra)

    def state(self, values, level: int) -> tuple[float, float]:
        """(stiffness scale, loss factor) at ``level`` (0-based)."""
        return _state(self.law, self.levels, values, level)

    def _law(self, values, a_unit: float):
        a_c = values["force_slip"] * a_unit

        def law(a):
            g = (a / a_c) / (1 + a / a_c)
            return 1.0 - values["s_max"] * g, values["eta_0"] + values["eta_max"] * g
        return law

    #: solve line by line (set on the selected candidate for its final refinement; the screening fits use
    #: the cheaper per-level describing function at the linear peak, :meth:`apply`)
    line_by_line = False

    def refined(self):
        """A copy that solves every line by harmonic balance (None when the forces are unknown)."""
        if not self.law:
            return None
        import copy

        c = copy.copy(self)
        c.line_by_line = True
        c.name = self.name + "+hb"
        return c

    def receptance_at_level(self, ev, nominal, values, level):
        """``(n_freq, n_out, n_in)`` at the evaluator's lines and DOFs, or None to use :meth:`apply`."""
        if not (self.law and self.line_by_line):
            return None
        from jointdb.diagnose.physics._harmonic import harmonic_balance_receptance
        from jointdb.fe import frf_modal

        key = (id(ev), id(nominal), tuple(sorted((k, values[k]) for k in ("k_x", "k_ry", "k_contact", "insertion",
                                                                          "eta_0") if k in values)))
        cached = getattr(self, "_linear_cache", None)
        if cached is None or cached[0] != key:
            lin, rows = self._linear(nominal, values)
            mats = lin.assemble()
            out_dofs, in_dofs = ev.dof_indices(lin)
            n_modes = min(ev.n_modes, max(1, lin.mesh().n_dof - 4)) if ev.method == "modal" else None
            every = list(dict.fromkeys(out_dofs + in_dofs + rows.dofs))
            H = frf_modal(mats, ev.freq, every, n_modes=n_modes)
            pos = {d: i for i, d in enumerate(every)}
            # slip per unit force at the linear joint's worst line sets the scale of the law
            rel = [np.abs(H[:, pos[a], pos[in_dofs[0]]] - H[:, pos[b], pos[in_dofs[0]]]) * w
                   for (a, b), w in zip(rows.pairs, rows.weight)]
            a_unit = max(float(np.max(np.sum(rel, axis=0))), 1e-300)
            cached = (key, mats, rows, out_dofs, in_dofs, n_modes, H, a_unit)
            self._linear_cache = cached
        _, mats, rows, out_dofs, in_dofs, n_modes, H, a_unit = cached
        return harmonic_balance_receptance(mats, ev.freq, out_dofs, in_dofs, rows, float(self.levels[level]),
                                           self._law(values, a_unit), values["eta_0"], n_modes=n_modes,
                                           linear=H)


class MicroslipContact(_Microslip, InterfaceContact):
    """A contact layer over an insertion whose stiffness falls and loss rises with the excitation level."""

    def __init__(self, model, site: Site, levels):
        self._start(model, site, levels, "interface_contact_microslip", "contact over the insertion")

    def apply(self, model, values, level=0):
        s, eta = self.state(values, level)
        v = dict(values)
        v["k_contact"] = values["k_contact"] * s
        v["eta_joint"] = eta
        return super().apply(model, v, level)

    def _linear(self, nominal, values):
        """The model with the contact at its small-amplitude state, and the contact's relative DOFs."""
        from jointdb.diagnose.physics._harmonic import JointRows
        from jointdb.fe import Insertion

        v = dict(values)
        v["eta_joint"] = values["eta_0"]
        model = InterfaceContact.apply(self, nominal, v)
        ins = [i for i in model.ingredients if isinstance(i, Insertion) and not i.rigid][-1]
        mesh = model.mesh()
        k = ins.contact.stiffness_per_length
        radius = 0.5 * ins.outer_diameter
        pairs, stiff, group, weight = [], [], [], []
        for g, (inner, host, trib) in enumerate(mesh.contact_pairs(ins)):
            for t, r in self.planes:
                for d, w in ((t, 1.0), (r, radius)):
                    if k.get(d, 0.0) > 0:
                        pairs.append((mesh.dof(inner, d), mesh.dof(host, d)))
                        stiff.append(k[d] * trib)
                        group.append(g)
                        weight.append(w)
        return model, JointRows(pairs, stiff, group, weight)

    def level_table(self, values, sigmas=None, **_):
        """Per level: level, contact stiffness per length, loss factor."""
        rows = []
        for i, lv in enumerate(self.levels):
            s, eta = self.state(values, i)
            rows.append({"level": lv, "k_contact_n_per_m2": values["k_contact"] * s, "loss_factor": eta,
                         "stiffness_scale": s, "position_m": self.site.position})
        return rows


class MicroslipJoint(_Microslip, InterfaceJoint):
    """A point joint at a site whose stiffness falls and loss rises with the excitation level."""

    def __init__(self, model, site: Site, levels):
        self._start(model, site, levels, "interface_microslip", "joint")

    def apply(self, model, values, level=0):
        s, eta = self.state(values, level)
        return model.with_ingredient(self.joint(values, scale=s, eta=eta))

    def _linear(self, nominal, values):
        """The model with the joint at its small-amplitude state, and the joint's relative DOFs."""
        from jointdb.diagnose.physics._harmonic import JointRows

        joint = self.joint(values, scale=1.0, eta=values["eta_0"])
        model = nominal.with_ingredient(joint)
        mesh = model.mesh()
        a, b = mesh.split_nodes(joint)
        segs = nominal.segments
        radius = 0.5 * min(segs[self.site.lower].outer_diameter, segs[self.site.upper].outer_diameter)
        pairs, stiff, weight = [], [], []
        for t, r in self.planes:
            for d, w, key in ((t, 1.0, "k_x"), (r, radius, "k_ry")):
                pairs.append((mesh.dof(a, d), mesh.dof(b, d)))
                stiff.append(values[key])
                weight.append(w)
        return model, JointRows(pairs, stiff, [0] * len(pairs), weight)

    def level_table(self, values, sigmas=None, models=None, input_point=None, freq_hz=None):
        """Per level: level, k_x, k_ry, loss factor (and the slip amplitude when ``models`` are given)."""
        rows = []
        for i, lv in enumerate(self.levels):
            s, eta = self.state(values, i)
            row = {"level": lv, "k_x_n_per_m": values["k_x"] * s, "k_ry_nm_per_rad": values["k_ry"] * s,
                   "loss_factor": eta, "position_m": self.site.position}
            if models is not None and input_point is not None and freq_hz is not None:
                row["slip_amplitude_m"] = slip_amplitude(models[i], self.joint(values, s, eta), input_point,
                                                         freq_hz, lv if lv is not None else 1.0)
            rows.append(row)
        return rows


def slip_amplitude(model, joint, input_point: str, freq_hz: np.ndarray, force: float) -> float:
    """Largest relative displacement [m] of the two sides of ``joint`` in ``model`` over ``freq_hz``
    for a force of amplitude ``force`` [N] in x at ``input_point``."""
    from jointdb.fe import frf_direct

    mesh = model.mesh()
    mats = model.assemble()
    j = next((ing for ing in model.ingredients if ing is joint or ing == joint), None)
    if j is None:
        return float("nan")
    a, b = mesh.split_nodes(j)
    i_in = mesh.dof(mesh.node_at(model.point(input_point).position), "x")
    dofs = [i_in, mesh.dof(a, "x"), mesh.dof(b, "x")]
    H = frf_direct(mats, np.asarray(freq_hz, dtype=float), dofs, algorithm="lu")
    return float(np.max(np.abs(H[:, 1, 0] - H[:, 2, 0])) * force)


@register
def _factory(ctx):
    if ctx.n_levels < 2:
        return []
    out = []
    for site in interface_sites(ctx.model):
        out.append(MicroslipJoint(ctx.model, site, ctx.levels))
        if site.lower != site.upper or site.insertion is not None:
            try:
                out.append(MicroslipContact(ctx.model, site, ctx.levels))
            except ValueError:
                pass
    return out
