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

The slip amplitude each level produced at the joint (relative displacement of
the two sides at the level's first resonance) is reported with ``k(a)`` and
``η(a)`` (:meth:`MicroslipJoint.level_table`).
"""

from __future__ import annotations

import numpy as np

from jointdb.diagnose.physics import Param, register
from jointdb.diagnose.physics.interface import InterfaceContact, InterfaceJoint, Site, interface_sites

__all__ = ["MicroslipJoint", "MicroslipContact", "slip_amplitude"]


def _known_levels(levels) -> bool:
    return all(lv is not None and np.isfinite(lv) and lv > 0 for lv in levels)


def _law_params(levels) -> tuple[bool, list]:
    """Whether the describing-function law applies (levels known) and its parameters after the stiffness."""
    law = _known_levels(levels)
    extra = [Param("eta_0", "-", 1e-3, 1.0, 0.05, starts=(0.2,), plausible=(1e-3, 1.0))]
    if law:
        lv = np.asarray(levels, dtype=float)
        extra += [Param("force_slip", "N", lv.min() / 30, lv.max() * 30, float(np.sqrt(lv.min() * lv.max()))),
                  Param("s_max", "-", 0.0, 0.95, 0.3, log=False),
                  Param("eta_max", "-", 1e-3, 1.5, 0.1, starts=(0.4,), plausible=(1e-3, 1.0))]
    else:
        extra += [Param(f"s_{i + 1}", "-", 0.2, 1.5, 0.95) for i in range(1, len(levels))]
        extra += [Param(f"eta_{i + 1}", "-", 1e-3, 1.0, 0.1) for i in range(1, len(levels))]
    return law, extra


def _state(law: bool, levels, values, level: int) -> tuple[float, float]:
    if law:
        r = levels[level] / values["force_slip"]
        g = r / (1 + r)
        return 1.0 - values["s_max"] * g, values["eta_0"] + values["eta_max"] * g
    if level == 0:
        return 1.0, values["eta_0"]
    return values[f"s_{level + 1}"], values[f"eta_{level + 1}"]


class MicroslipContact(InterfaceContact):
    """A contact layer over an insertion whose stiffness falls and loss rises with the excitation level."""

    family = "softening_joint"
    per_level = True

    def __init__(self, model, site: Site, levels):
        super().__init__(model, site, damped=False)
        self.family = "softening_joint"
        self.name = f"interface_contact_microslip@{site.position * 1e3:.4g}mm"
        self.levels = tuple(levels)
        self.explanation = (f"an amplitude-dependent (micro-slip) contact over the insertion at {site.location} "
                            "whose stiffness falls and damping rises with the excitation")
        self.law, extra = _law_params(self.levels)
        self.params = self.params + tuple(extra)

    def state(self, values, level: int) -> tuple[float, float]:
        """(stiffness scale, loss factor) at ``level`` (0-based)."""
        return _state(self.law, self.levels, values, level)

    def apply(self, model, values, level=0):
        s, eta = self.state(values, level)
        v = dict(values)
        v["k_contact"] = values["k_contact"] * s
        v["eta_joint"] = eta
        return super().apply(model, v, level)

    def level_table(self, values, sigmas=None, **_):
        """Per level: level, contact stiffness per length, loss factor."""
        rows = []
        for i, lv in enumerate(self.levels):
            s, eta = self.state(values, i)
            rows.append({"level": lv, "k_contact_n_per_m2": values["k_contact"] * s, "loss_factor": eta,
                         "stiffness_scale": s, "position_m": self.site.position})
        return rows


class MicroslipJoint(InterfaceJoint):
    """A point joint at a site whose stiffness falls and loss rises with the excitation level."""

    family = "softening_joint"
    per_level = True

    def __init__(self, model, site: Site, levels):
        super().__init__(model, site, damped=False)
        self.family = "softening_joint"
        self.name = f"interface_microslip@{site.position * 1e3:.4g}mm"
        self.levels = tuple(levels)
        self.explanation = (f"an amplitude-dependent (micro-slip) joint at {site.location} whose stiffness falls "
                            "and damping rises with the excitation")
        self.law, extra = _law_params(self.levels)
        self.params = self.params + tuple(extra)

    def state(self, values, level: int) -> tuple[float, float]:
        """(stiffness scale, loss factor) at ``level`` (0-based)."""
        return _state(self.law, self.levels, values, level)

    def apply(self, model, values, level=0):
        s, eta = self.state(values, level)
        return model.with_ingredient(self.joint(values, scale=s, eta=eta))

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
