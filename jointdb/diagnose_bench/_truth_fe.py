"""The benchmark's own "truth" beam: a fine planar Timoshenko FE written for
the generator only.

It deliberately shares no code with :mod:`jointdb.fe` or
:mod:`jointdb.diagnose`: the concealed effects are injected here with their own
(higher-fidelity) physics, so a diagnosis that names them has found them in the
data, not in shared code.

Physics available to the truth (all SI):

- Timoshenko elements (shear, Cowper coefficient; rotary inertia), element
  length about 2 mm;
- per-element section properties, so a fluted section can have an area and a
  second moment that do not belong to any single circle;
- distributed added mass and rotary inertia over a length (a sensor of finite
  size);
- a Winkler bed (distributed translational springs, with a loss factor) over
  the insertion length of a shank in its holder, instead of a rigid clamp;
- Rayleigh (viscous) and structural (hysteretic) damping;
- an amplitude-dependent (softening, micro-slip) bed solved by single-harmonic
  balance at every frequency line (batched fixed point over lines).

Receptances come from the modal sum over *all* real modes (no truncation),
exact for the proportional part of the damping; the non-proportional parts
(a joint bed with its own loss factor, amplitude-dependent bed springs) enter
exactly through low-rank (Woodbury) corrections over the bed DOFs.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg

__all__ = ["TruthBeam", "cowper_kappa"]

#: A fixed-point step smaller than this fraction of the largest bed stiffness is round-off: the line
#: has converged (see TruthBeam._bed_fixed_point).
ROUND_OFF_STEP = 1e-15


def cowper_kappa(nu: float) -> float:
    """Cowper's shear coefficient of a solid circle, ``6(1+ν)/(7+6ν)``."""
    return 6.0 * (1.0 + nu) / (7.0 + 6.0 * nu)


def _timoshenko_element(EI, kGA, rhoA, rhoI, h):
    """Stiffness and consistent mass (n_el, 4, 4) of Timoshenko elements.

    DOFs ``(w1, t1, w2, t2)`` with ``t = +dw/dz``; interdependent interpolation
    (Friedman & Kosmatka 1993), Φ = 12 EI / (κGA h²).
    """
    phi = 12.0 * EI / (kGA * h * h)
    d = 1.0 + phi
    h2 = h * h
    k = np.zeros((h.size, 4, 4))
    base = EI / (h**3 * d)
    k[:, 0, 0] = k[:, 2, 2] = 12.0
    k[:, 0, 2] = k[:, 2, 0] = -12.0
    for a, b in ((0, 1), (0, 3)):
        k[:, a, b] = k[:, b, a] = 6.0 * h
    for a, b in ((1, 2), (2, 3)):
        k[:, a, b] = k[:, b, a] = -6.0 * h
    k[:, 1, 1] = k[:, 3, 3] = (4.0 + phi) * h2
    k[:, 1, 3] = k[:, 3, 1] = (2.0 - phi) * h2
    k *= base[:, None, None]

    m = np.zeros((h.size, 4, 4))
    t = rhoA * h / d**2
    p = phi
    m[:, 0, 0] = m[:, 2, 2] = t * (13 / 35 + 7 * p / 10 + p * p / 3)
    m[:, 0, 1] = m[:, 1, 0] = t * (11 / 210 + 11 * p / 120 + p * p / 24) * h
    m[:, 2, 3] = m[:, 3, 2] = -m[:, 0, 1]
    m[:, 0, 2] = m[:, 2, 0] = t * (9 / 70 + 3 * p / 10 + p * p / 6)
    c = t * (13 / 420 + 3 * p / 40 + p * p / 24) * h
    m[:, 0, 3] = m[:, 3, 0] = -c
    m[:, 1, 2] = m[:, 2, 1] = c
    m[:, 1, 1] = m[:, 3, 3] = t * (1 / 105 + p / 60 + p * p / 120) * h2
    m[:, 1, 3] = m[:, 3, 1] = -t * (1 / 140 + p / 60 + p * p / 120) * h2
    r = rhoI / (h * d**2)
    e = (1 / 10 - p / 2) * h
    rot = np.zeros_like(m)
    rot[:, 0, 0] = rot[:, 2, 2] = 6 / 5
    rot[:, 0, 2] = rot[:, 2, 0] = -6 / 5
    rot[:, 0, 1] = rot[:, 1, 0] = rot[:, 0, 3] = rot[:, 3, 0] = e
    rot[:, 1, 2] = rot[:, 2, 1] = rot[:, 2, 3] = rot[:, 3, 2] = -e
    rot[:, 1, 1] = rot[:, 3, 3] = (2 / 15 + p / 6 + p * p / 3) * h2
    rot[:, 1, 3] = rot[:, 3, 1] = (-1 / 30 - p / 6 + p * p / 6) * h2
    return k, m + rot * r[:, None, None]


@dataclass
class TruthBeam:
    """A planar beam on ``[z0, z1]`` meshed finely, with truth-only physics.

    Build it with :meth:`cylinder`, then change section properties and add
    physics with the ``add_*`` methods; finally call :meth:`receptance`.
    """

    z: np.ndarray                       # node positions (n_nodes,)
    E: float
    G: float
    rho: float
    kappa: float
    area: np.ndarray                    # per element
    inertia: np.ndarray                 # per element (second moment)
    extra_rhoA: np.ndarray = field(default=None)   # added mass per length, per element
    extra_rhoI: np.ndarray = field(default=None)   # added rotary inertia per length
    clamped_nodes: list = field(default_factory=list)
    bed: dict = field(default_factory=dict)         # node -> translational stiffness [N/m]
    bed_loss: float = 0.0
    rayleigh: tuple = (0.0, 0.0)
    structural_loss: float = 0.0
    shear: bool = True

    @classmethod
    def cylinder(cls, z0, z1, diameter, E, nu, rho, h=0.002, breaks=()):
        """A solid cylinder from ``z0`` to ``z1`` [m] with elements of about ``h``."""
        pts = sorted({float(z0), float(z1), *(float(b) for b in breaks if z0 < b < z1)})
        z = [pts[0]]
        for a, b in zip(pts[:-1], pts[1:]):
            n = max(1, int(np.ceil((b - a) / h - 1e-9)))
            z.extend(np.linspace(a, b, n + 1)[1:])
        z = np.asarray(z)
        n_el = z.size - 1
        A = np.pi * diameter**2 / 4.0
        I = np.pi * diameter**4 / 64.0
        G = E / (2.0 * (1.0 + nu))
        return cls(z=z, E=E, G=G, rho=rho, kappa=cowper_kappa(nu),
                   area=np.full(n_el, A), inertia=np.full(n_el, I),
                   extra_rhoA=np.zeros(n_el), extra_rhoI=np.zeros(n_el))

    # -- geometry helpers -------------------------------------------------
    @property
    def mid(self) -> np.ndarray:
        return 0.5 * (self.z[1:] + self.z[:-1])

    def node_at(self, position: float) -> int:
        i = int(np.argmin(np.abs(self.z - position)))
        if abs(self.z[i] - position) > 1e-9:
            raise ValueError(f"no truth node at z={position}")
        return i

    def elements_in(self, a: float, b: float) -> np.ndarray:
        m = self.mid
        return np.where((m > a) & (m < b))[0]

    # -- physics ----------------------------------------------------------
    def set_section(self, a, b, area, inertia):
        """Section area [m²] and second moment [m⁴] of the elements in (a, b)."""
        idx = self.elements_in(a, b)
        self.area[idx] = area
        self.inertia[idx] = inertia

    def add_distributed_mass(self, a, b, mass, rotary_inertia):
        """Mass [kg] and rotary inertia [kg·m²] spread uniformly over (a, b)."""
        idx = self.elements_in(a, b)
        length = b - a
        self.extra_rhoA[idx] += mass / length
        self.extra_rhoI[idx] += rotary_inertia / length

    def add_winkler_bed(self, a, b, stiffness_per_length, profile=None):
        """Distributed translational springs k'(z) [N/m²] over [a, b] (lumped at nodes)."""
        nodes = np.where((self.z >= a - 1e-12) & (self.z <= b + 1e-12))[0]
        zz = self.z[nodes]
        trib = np.zeros(nodes.size)
        dz = np.diff(zz)
        trib[:-1] += dz / 2
        trib[1:] += dz / 2
        w = np.ones(nodes.size) if profile is None else profile(zz)
        for n, t, ww in zip(nodes, trib, w):
            self.bed[int(n)] = self.bed.get(int(n), 0.0) + stiffness_per_length * t * ww

    # -- matrices ---------------------------------------------------------
    def matrices(self):
        h = np.diff(self.z)
        EI = self.E * self.inertia
        kGA = self.kappa * self.G * self.area if self.shear else np.full(h.size, 1e30)
        rhoA = self.rho * self.area + self.extra_rhoA
        rhoI = self.rho * self.inertia + self.extra_rhoI
        ke, me = _timoshenko_element(EI, kGA, rhoA, rhoI, h)
        n = 2 * self.z.size
        K = np.zeros((n, n))
        M = np.zeros((n, n))
        for e in range(h.size):  # assembly loop over elements (not frequency)
            s = slice(2 * e, 2 * e + 4)
            K[s, s] += ke[e]
            M[s, s] += me[e]
        Kb = np.zeros((n, n))
        for node, k in self.bed.items():
            Kb[2 * node, 2 * node] += k
        return K, M, Kb

    def free_dofs(self) -> np.ndarray:
        fixed = set()
        for node in self.clamped_nodes:
            fixed.update((2 * node, 2 * node + 1))
        return np.array([i for i in range(2 * self.z.size) if i not in fixed])

    def _modes(self):
        K, M, Kb = self.matrices()
        free = self.free_dofs()
        ix = np.ix_(free, free)
        w2, phi = scipy.linalg.eigh((K + Kb)[ix], M[ix])
        return w2, phi, free

    def _proportional(self, freq_hz, rows, cols):
        """Modal sum over all real modes with proportional damping (exact)."""
        w2, phi, free = self._modes()
        pos = {int(d): i for i, d in enumerate(free)}
        oi = [pos[int(d)] for d in rows]
        ii = [pos[int(d)] for d in cols]
        a, b = self.rayleigh
        w = 2.0 * np.pi * np.asarray(freq_hz, dtype=float)[:, None]
        g = 1.0 / (w2 * (1.0 + 1j * self.structural_loss) - w * w + 1j * w * (a + b * w2))
        return np.matmul(phi[oi][None, :, :] * g[:, None, :], phi[ii].T[None])

    def receptance(self, freq_hz, out_dofs, in_dofs):
        """Receptance ``(n_freq, n_out, n_in)`` between global DOF indices.

        DOF index ``2*node`` is the translation ``x``, ``2*node+1`` the rotation.
        Proportional damping (Rayleigh on the total stiffness, structural loss
        factor) through the modal sum over all modes; a bed loss factor that
        differs from the structural one is added exactly by a low-rank
        (Woodbury) correction over the bed DOFs.
        """
        outs, ins = list(out_dofs), list(in_dofs)
        if not self.bed or self.bed_loss == self.structural_loss:
            return self._proportional(freq_hz, outs, ins)
        nodes = sorted(self.bed)
        bd = [2 * n for n in nodes]
        H = self._proportional(freq_hz, bd + outs, bd + ins)
        nb = len(bd)
        d = 1j * (self.bed_loss - self.structural_loss) * np.array([self.bed[n] for n in nodes])
        S = np.eye(nb)[None] + H[:, :nb, :nb] * d[None, None, :]
        corr = np.linalg.solve(S, H[:, :nb, nb:])
        return H[:, nb:, nb:] - np.einsum("fob,b,fbi->foi", H[:, nb:, :nb], d, corr)

    def receptance_amplitude_dependent(self, freq_hz, out_dofs, in_dofs, force_amplitude,
                                       law, n_iter=60, relax=0.5, each_input=False):
        """Receptance with the bed springs following an amplitude law (harmonic balance).

        Every bed spring ``i`` is replaced by ``k_i·σ(a_i) (1 + i η(a_i))`` with
        ``a_i`` the displacement amplitude at its node for a force of amplitude
        ``force_amplitude`` [N] at ``in_dofs[0]`` (with ``each_input``: at each input
        in turn, column ``j`` of the result being the response to a force at
        ``in_dofs[j]``); ``law(a) -> (σ, η)``. The linear reference (``σ=1``,
        ``η=bed_loss``) is corrected by a low-rank (Woodbury) update and iterated to
        a fixed point at every line at once (:meth:`_bed_fixed_point`).
        """
        nodes = sorted(self.bed)
        bed_dofs = [2 * n for n in nodes]
        outs = list(out_dofs)
        ins = list(in_dofs)
        H = self.receptance(freq_hz, bed_dofs + outs, bed_dofs + ins)
        return self._amplitude_dependent(H, len(bed_dofs), force_amplitude, law, n_iter, relax, each_input)

    def amplitude_dependent_levels(self, freq_hz, out_dofs, in_dofs, force_amplitudes, law,
                                   n_iter=60, relax=0.5):
        """:meth:`receptance_amplitude_dependent` (``each_input``) at several force amplitudes [N],
        ``[(n_freq, n_out, n_in)]`` one per level; the linear receptance is computed once."""
        nodes = sorted(self.bed)
        bed_dofs = [2 * n for n in nodes]
        H = self.receptance(freq_hz, bed_dofs + list(out_dofs), bed_dofs + list(in_dofs))
        return [self._amplitude_dependent(H, len(bed_dofs), f, law, n_iter, relax, True) for f in force_amplitudes]

    def _amplitude_dependent(self, H, nb, force_amplitude, law, n_iter, relax, each_input):
        """The amplitude-dependent receptance from the linear one over ``bed + outputs`` × ``bed + inputs``."""
        Hbb, Hbi = H[:, :nb, :nb], H[:, :nb, nb:]
        Hob, Hoi = H[:, nb:, :nb], H[:, nb:, nb:]
        k0 = np.array([self.bed[n] for n in sorted(self.bed)])
        eye = np.eye(nb)
        cols = []
        for j in range(Hbi.shape[2] if each_input else 1):
            dk = self._bed_fixed_point(Hbb, Hbi[:, :, j], k0, force_amplitude, law, n_iter, relax)
            S = eye[None] + Hbb * dk[:, None, :]
            rhs = Hbi[:, :, j:j + 1] if each_input else Hbi
            corr = np.linalg.solve(S, rhs)
            cols.append(Hoi[:, :, j:j + 1] if each_input else Hoi)
            cols[-1] = cols[-1] - np.einsum("fob,fb,fbi->foi", Hob, dk, corr)
        return np.concatenate(cols, axis=2)

    def _bed_fixed_point(self, Hbb, hbi, k0, force_amplitude, law, n_iter, relax):
        """Bed stiffness changes ``dk`` ``(n_freq, n_bed)``: ``n_iter`` relaxed fixed-point steps per line.

        A line whose step no longer moves any spring by more than round-off (``1e-15`` of the largest
        bed stiffness) has reached its fixed point and leaves the working set (a further step would
        change it by round-off only), so the result is that of ``n_iter`` steps on every line.
        """
        nf, nb = hbi.shape
        dk = np.zeros((nf, nb), dtype=complex)
        eye = np.eye(nb)
        lin = 1 + 1j * self.bed_loss
        still = ROUND_OFF_STEP * float(k0.max())
        act, A, b = np.arange(nf), Hbb, hbi
        for _ in range(n_iter):  # fixed-point iteration; each step batched over lines
            # G = H - Hb· dK (I + Hbb dK)^-1 · H_b.
            S = eye[None] + A * dk[act][:, None, :]
            xb = np.linalg.solve(S, b[:, :, None])[:, :, 0]      # bed displacement / force
            sigma, eta = law(np.abs(xb) * force_amplitude)
            target = k0[None] * (sigma * (1 + 1j * eta) - lin)
            new = (1 - relax) * dk[act] + relax * target
            moving = np.abs(new - dk[act]).max(axis=1) > still
            dk[act] = new
            if not moving.any():
                break
            if moving.sum() < 0.9 * act.size:                 # compact the working set
                act, A, b = act[moving], A[moving], b[moving]
        return dk
