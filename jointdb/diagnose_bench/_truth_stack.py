"""A second benchmark truth, structurally unlike :mod:`jointdb.fe`: a tool
inside a holder bore as TWO CONCENTRIC BEAMS tied by a contact layer.

Written for the generator only; it shares no code with :mod:`jointdb.fe` or
:mod:`jointdb.diagnose` (it reuses only the generator's own Timoshenko element
routine from :mod:`jointdb.diagnose_bench._truth_fe`).

The stack (planar, SI units, ``z`` along the axis from the spindle face):

- a **holder** beam from ``z = 0`` to the holder face ``z_face`` (sections of
  any outer and inner diameter, e.g. a body and a nose with a bore);
- a **tool** beam from ``z_face − L`` (the bottom of the inserted shank) to the
  tip; over the insertion length ``L`` its nodes coincide with the holder's;
- a **contact layer** over the insertion: translational springs per unit
  length ``k'(z)`` [N/m²] between the two beams' ``x`` DOFs, lumped at the
  shared node positions (no rotational tie, no rigid clamp at the face), with
  its own loss factor ``η_c`` and, optionally, an amplitude-dependent
  (micro-slip) law on the local *relative* displacement amplitude;
- the holder's **base** on its own spindle-face springs ``k_x`` [N/m] and
  ``k_θ`` [N·m/rad] to ground with a loss factor (or rigidly clamped).

Damping: Rayleigh on the total stiffness (beams + contact + base) is treated
exactly by the modal sum over *all* real modes; the loss factors of the
contact and the base are non-proportional and enter exactly by a low-rank
(Woodbury) correction over the connector coordinates. The amplitude-dependent
contact is solved per frequency line by single-harmonic balance: a fixed point
on the contact stiffnesses, batched over lines, each line frozen once it has
converged.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg

from jointdb.diagnose_bench._truth_fe import _timoshenko_element

__all__ = ["BeamPart", "ToolInHolder", "CARBIDE", "STEEL", "hollow_kappa", "mesh"]

CARBIDE = dict(E=580e9, nu=0.22, rho=14500.0)
STEEL = dict(E=210e9, nu=0.3, rho=7800.0)


def hollow_kappa(nu, outer, inner=0.0):
    """Cowper's (1966) shear coefficient of a hollow circle, ``m = inner/outer``."""
    m2 = (np.asarray(inner, dtype=float) / np.asarray(outer, dtype=float)) ** 2
    c = (1.0 + m2) ** 2
    return 6.0 * (1.0 + nu) * c / ((7.0 + 6.0 * nu) * c + (20.0 + 12.0 * nu) * m2)


def _section_at(sections, z):
    for a, b, outer, inner, mat in sections:
        if a <= z < b:
            return outer, inner, mat
    raise ValueError(f"no section at z={z}")


def mesh(breaks, h, coarse=None):
    """Node positions through every break with elements of at most ``h`` [m].

    ``coarse = (a, b, h2)``: elements of at most ``h2`` inside ``[a, b]``.
    """
    pts = np.unique(np.round(np.asarray(breaks, dtype=float), 12))
    z = [pts[0]]
    for a, b in zip(pts[:-1], pts[1:]):
        hh = coarse[2] if coarse is not None and coarse[0] - 1e-12 <= a and b <= coarse[1] + 1e-12 else h
        n = max(1, int(np.ceil((b - a) / hh - 1e-9)))
        z.extend(np.linspace(a, b, n + 1)[1:])
    return np.asarray(z)


@dataclass
class BeamPart:
    """One beam on its own nodes ``z`` with per-element section stiffness and inertia.

    ``EI`` [N·m²], ``kGA`` [N], ``rhoA`` [kg/m], ``rhoI`` [kg·m] per element.
    """

    z: np.ndarray
    EI: np.ndarray
    kGA: np.ndarray
    rhoA: np.ndarray
    rhoI: np.ndarray

    @classmethod
    def from_sections(cls, z, sections):
        """Elements take the section ``(a, b, outer, inner, material)`` containing their midpoint.

        Raises
        ------
        ValueError
            If an element lies in no section.
        """
        z = np.asarray(z, dtype=float)
        mid = 0.5 * (z[1:] + z[:-1])
        arrays = {k: np.full(mid.size, np.nan) for k in ("EI", "kGA", "rhoA", "rhoI")}
        for a, b, outer, inner, mat in sections:
            sel = (mid > a) & (mid < b)
            A = np.pi * (outer**2 - inner**2) / 4.0
            I = np.pi * (outer**4 - inner**4) / 64.0
            G = mat["E"] / (2.0 * (1.0 + mat["nu"]))
            arrays["EI"][sel] = mat["E"] * I
            arrays["kGA"][sel] = hollow_kappa(mat["nu"], outer, inner) * G * A
            arrays["rhoA"][sel] = mat["rho"] * A
            arrays["rhoI"][sel] = mat["rho"] * I
        if np.isnan(arrays["EI"]).any():
            raise ValueError("an element of the truth beam lies in no section")
        return cls(z=z, **arrays)

    def matrices(self, shear: bool = True):
        """Stiffness and consistent mass ``(2n, 2n)``, DOFs ``(x, θ)`` per node."""
        h = np.diff(self.z)
        kGA = self.kGA if shear else np.full(h.size, 1e30)
        ke, me = _timoshenko_element(self.EI, kGA, self.rhoA, self.rhoI, h)
        n = 2 * self.z.size
        K = np.zeros((n, n))
        M = np.zeros((n, n))
        for e in range(h.size):  # assembly over elements (not frequency)
            s = slice(2 * e, 2 * e + 4)
            K[s, s] += ke[e]
            M[s, s] += me[e]
        return K, M


@dataclass
class ToolInHolder:
    """Holder + tool as two concentric beams tied by a contact layer (see module docstring).

    Build with :meth:`build`; then :meth:`receptance` (linear) or
    :meth:`receptance_amplitude_dependent` (micro-slip contact). Output and
    input coordinates are given as ``(part, z, dof)`` with part ``"tool"`` or
    ``"holder"`` and dof ``"x"`` or ``"t"`` (rotation).
    """

    holder: BeamPart
    tool: BeamPart
    contact_holder_nodes: np.ndarray     # holder node index of each contact pair
    contact_tool_nodes: np.ndarray       # tool node index of each contact pair
    contact_k: np.ndarray                # lumped translational contact stiffness of each pair [N/m]
    contact_kt: np.ndarray               # lumped rotational contact stiffness of each pair [N·m/rad]
    contact_radius: float                # interface radius [m] (axial slip = radius × relative rotation)
    contact_loss: float = 0.0
    base: tuple | None = (1e9, 1e7)      # (k_x [N/m], k_θ [N·m/rad]); None = rigid clamp
    base_loss: float = 0.0
    rayleigh: tuple = (0.0, 0.0)
    shear: bool = True
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    @classmethod
    def build(cls, holder_sections, tool_sections, z_face, insertion, z_tip, contact_kprime,
              profile=None, h=0.002, extra_breaks=(), contact_radius=None, tangential_ratio=1.0,
              contact_nodes=None):
        """Mesh both beams on one grid and lump the contact layer at the shared nodes.

        Parameters
        ----------
        holder_sections, tool_sections
            Lists of ``(a, b, outer_diameter, inner_diameter, material)`` [m], material a dict
            ``{"E", "nu", "rho"}``; together they must cover ``[0, z_face]`` and
            ``[z_face − insertion, z_tip]``.
        z_face, insertion, z_tip
            Holder face, insertion length and tool tip [m]; ``z_tip ≥ z_face``.
        contact_kprime
            Mean contact stiffness per unit length k' [N/m²] (transverse, between the x DOFs).
        contact_radius, tangential_ratio
            Interface radius r [m] (default: half the tool's diameter at the face) and the
            ratio of tangential (axial) to normal contact stiffness per area. A bonded
            interface also ties the two sections' rotations through axial shear at radius
            r; over a circle this gives a rotational stiffness per length
            ``k'_θ = k' r² · tangential_ratio / 2`` [N·m/rad/m] with the same profile.
        profile
            ``profile(ζ) -> weight`` over ``ζ = (z − z_face + L)/L ∈ [0, 1]`` (pressure
            distribution); weights are normalised to mean 1 over the insertion.
        h
            Largest element length [m].
        contact_nodes
            If given, the overlap is meshed with about this many + 1 nodes (elements of
            at most ``insertion / contact_nodes``, never shorter than ``h``): the contact
            layer is lumped at fewer pairs, which keeps harmonic balance cheap.

        Raises
        ------
        ValueError
            If the geometry is inconsistent.
        """
        if not 0 < insertion <= z_face or z_tip < z_face:
            raise ValueError("need 0 < insertion <= z_face and z_tip >= z_face")
        z0 = z_face - insertion
        breaks = {0.0, z0, z_face, z_tip, *extra_breaks}
        for a, b, *_ in (*holder_sections, *tool_sections):
            breaks.update((a, b))
        coarse = None if contact_nodes is None else (z0, z_face, max(h, insertion / contact_nodes))
        z = mesh(sorted(b for b in breaks if 0.0 <= b <= z_tip), h, coarse)
        zh = z[z <= z_face + 1e-12]
        zt = z[z >= z0 - 1e-12]
        holder = BeamPart.from_sections(zh, holder_sections)
        tool = BeamPart.from_sections(zt, tool_sections)
        hn = np.where(zh >= z0 - 1e-12)[0]
        tn = np.arange(hn.size)
        zz = zh[hn]
        trib = np.zeros(zz.size)
        trib[:-1] += np.diff(zz) / 2
        trib[1:] += np.diff(zz) / 2
        w = np.ones(zz.size) if profile is None else np.asarray(profile((zz - z0) / insertion), dtype=float)
        if np.any(w < 0):
            raise ValueError("contact pressure profile must be >= 0")
        w = w * insertion / float((w * trib).sum())           # mean 1 over the insertion
        if contact_radius is None:
            contact_radius = 0.5 * _section_at(tool_sections, z0)[0]
        k = contact_kprime * trib * w
        return cls(holder=holder, tool=tool, contact_holder_nodes=hn, contact_tool_nodes=tn,
                   contact_k=k, contact_kt=k * contact_radius**2 * tangential_ratio / 2.0,
                   contact_radius=float(contact_radius))

    # -- coordinates ------------------------------------------------------
    @property
    def n_holder_dofs(self) -> int:
        return 2 * self.holder.z.size

    @property
    def n_dofs(self) -> int:
        return self.n_holder_dofs + 2 * self.tool.z.size

    def dof(self, part: str, z: float, d: str = "x") -> int:
        """Global DOF index of ``d`` ("x" or "t") at position ``z`` on ``part``.

        Raises
        ------
        ValueError
            If that part has no node at ``z``.
        """
        beam, off = (self.tool, self.n_holder_dofs) if part == "tool" else (self.holder, 0)
        i = int(np.argmin(np.abs(beam.z - z)))
        if abs(beam.z[i] - z) > 1e-9:
            raise ValueError(f"no {part} node at z={z}")
        return off + 2 * i + (0 if d == "x" else 1)

    def contact_z(self) -> np.ndarray:
        return self.holder.z[self.contact_holder_nodes]

    def _contact_rows(self) -> np.ndarray:
        """Relative rows tool − holder, ``(2 nc, n_dofs)``: first ``x`` at every pair, then ``θ``."""
        nc = self.contact_k.size
        B = np.zeros((2 * nc, self.n_dofs))
        r = np.arange(nc)
        for d in (0, 1):
            B[d * nc + r, self.n_holder_dofs + 2 * self.contact_tool_nodes + d] = 1.0
            B[d * nc + r, 2 * self.contact_holder_nodes + d] = -1.0
        return B

    def _contact_stiffness(self) -> np.ndarray:
        return np.concatenate([self.contact_k, self.contact_kt])

    def _slip_scale(self) -> np.ndarray:
        """Relative x [m] and θ [rad] to local slip amplitude [m] (θ: axial slip at the interface radius)."""
        nc = self.contact_k.size
        return np.concatenate([np.ones(nc), np.full(nc, self.contact_radius)])

    def _base_rows(self) -> np.ndarray:
        B = np.zeros((2, self.n_dofs))
        B[0, 0] = B[1, 1] = 1.0
        return B

    def _rows(self, coords) -> np.ndarray:
        R = np.zeros((len(coords), self.n_dofs))
        for i, c in enumerate(coords):
            R[i, self.dof(*c) if not isinstance(c, (int, np.integer)) else int(c)] = 1.0
        return R

    # -- matrices and modes ----------------------------------------------
    def matrices(self):
        """Total stiffness (beams + contact + base springs) and mass, ``(n_dofs, n_dofs)``."""
        Kh, Mh = self.holder.matrices(self.shear)
        Kt, Mt = self.tool.matrices(self.shear)
        K = scipy.linalg.block_diag(Kh, Kt)
        M = scipy.linalg.block_diag(Mh, Mt)
        B = self._contact_rows()
        K += B.T @ (self._contact_stiffness()[:, None] * B)
        if self.base is not None:
            K[0, 0] += self.base[0]
            K[1, 1] += self.base[1]
        return K, M

    def free_dofs(self) -> np.ndarray:
        start = 0 if self.base is not None else 2
        return np.arange(start, self.n_dofs)

    def modes(self):
        """``(ω², Φ)`` of all modes; Φ ``(n_dofs, n_modes)`` with zero rows at clamped DOFs."""
        key = ("modes", self.base, self.shear, float(self.contact_k.sum()), float(self.contact_kt.sum()))
        if key not in self._cache:
            K, M = self.matrices()
            free = self.free_dofs()
            w2, phi = scipy.linalg.eigh(K[np.ix_(free, free)], M[np.ix_(free, free)])
            full = np.zeros((self.n_dofs, w2.size))
            full[free] = phi
            self._cache.clear()
            self._cache[key] = (w2, full)
        return self._cache[key]

    def natural_frequencies(self, n: int = 3) -> np.ndarray:
        """The first ``n`` undamped natural frequencies [Hz]."""
        return np.sqrt(np.maximum(self.modes()[0][:n], 0.0)) / (2 * np.pi)

    # -- receptance -------------------------------------------------------
    def _proportional(self, freq_hz, O, I):
        """Modal sum over all modes, Rayleigh damping on the total stiffness: ``(nf, n_o, n_i)``."""
        w2, phi = self.modes()
        Po, Pi = O @ phi, I @ phi
        a, b = self.rayleigh
        w = 2.0 * np.pi * np.asarray(freq_hz, dtype=float)[:, None]
        g = 1.0 / (w2 - w * w + 1j * w * (a + b * w2))
        P = (Po[:, None, :] * Pi[None, :, :]).reshape(-1, w2.size).T      # (m, n_o·n_i)
        H = (g.real @ P) + 1j * (g.imag @ P)
        return H.reshape(-1, O.shape[0], I.shape[0])

    def _connectors(self):
        """Connector rows (contact, then base) and their extra dynamic stiffness ``i η k``.

        The contact rows come first (``2 nc`` of them), always; base rows follow when
        the base is elastic. ``d`` is zero for a loss-free connector.
        """
        rows = [self._contact_rows()]
        d = [1j * self.contact_loss * self._contact_stiffness()]
        if self.base is not None:
            rows.append(self._base_rows())
            d.append(1j * self.base_loss * np.asarray(self.base, dtype=float))
        return np.vstack(rows), np.concatenate(d)

    def _linear(self, freq_hz, O, I, with_contact=False):
        """Exact linear receptance between rows ``O`` and ``I`` (modal sum + Woodbury).

        ``with_contact``: the contact's relative coordinates are prepended to both
        (``(nf, 2nc + n_o, 2nc + n_i)``), at no extra modal-sum cost.
        """
        B, d = self._connectors()
        nc = 2 * self.contact_k.size
        nb = d.size
        if not with_contact and not d.any():
            return self._proportional(freq_hz, O, I)
        H = self._proportional(freq_hz, np.vstack([B, O]), np.vstack([B, I]))
        if d.any():
            S = np.eye(nb)[None] + H[:, :nb, :nb] * d[None, None, :]
            corr = np.linalg.solve(S, H[:, :nb, :])
            H = H - np.einsum("fob,b,fbi->foi", H[:, :, :nb], d, corr)
        keep = np.r_[np.arange(nc), np.arange(nb, H.shape[1])] if with_contact else np.arange(nb, H.shape[1])
        keep_i = np.r_[np.arange(nc), np.arange(nb, H.shape[2])] if with_contact else np.arange(nb, H.shape[2])
        return H[:, keep][:, :, keep_i]

    def receptance(self, freq_hz, outputs, inputs):
        """Linear receptance ``(n_freq, n_out, n_in)`` [m/N or rad/(N·m)…].

        ``outputs``/``inputs``: coordinates ``(part, z, dof)`` or global DOF indices.
        Exact: modal sum over all modes plus a Woodbury correction for the contact
        and base loss factors.
        """
        return self._linear(freq_hz, self._rows(outputs), self._rows(inputs))

    def receptance_amplitude_dependent(self, freq_hz, outputs, inputs, force_amplitudes, law,
                                       tol=1e-8, max_iter=300):
        """Receptances ``(n_levels, n_freq, n_out, n_in)`` with a micro-slip contact (harmonic balance).

        Every contact spring ``k_i`` becomes ``k_i σ(a_i)(1 + i η(a_i))`` with ``a_i`` the local
        slip amplitude [m] at its node — the relative displacement tool − holder for the
        transverse springs, the interface radius times the relative rotation for the
        rotational ones — when a force
        of amplitude ``force_amplitudes[l]`` [N] acts at one input at a time;
        ``law(a) -> (σ, η)`` (arrays like ``a``). The linear contact (σ = 1,
        η = ``contact_loss``) is corrected by a low-rank (Woodbury) update whose contact
        stiffnesses are iterated to a fixed point at every line at once (single-harmonic
        balance). Each line has its own relaxation (halved whenever its residual grows)
        and stops once every spring's change is below ``tol`` (relative to its k).

        Raises
        ------
        RuntimeError
            If some line has not converged after ``max_iter`` iterations.
        """
        nb = 2 * self.contact_k.size
        O = self._rows(outputs)
        I = self._rows(inputs)
        H = self._linear(freq_hz, O, I, with_contact=True)
        Hbb, Hbi = H[:, :nb, :nb], H[:, :nb, nb:]
        Hob, Hoi = H[:, nb:, :nb], H[:, nb:, nb:]
        out = np.empty((len(force_amplitudes), H.shape[0], O.shape[0], I.shape[0]), dtype=complex)
        for lvl, force in enumerate(force_amplitudes):
            for j in range(I.shape[0]):
                dk = self._balance(Hbb, Hbi[:, :, j], float(force), law, tol, max_iter)
                S = np.eye(nb)[None] + Hbb * dk[:, None, :]
                xb = np.linalg.solve(S, Hbi[:, :, j:j + 1])
                out[lvl, :, :, j] = Hoi[:, :, j] - np.einsum("fob,fb,fb->fo", Hob, dk, xb[:, :, 0])
        return out

    def _balance(self, Hbb, hbi, force, law, tol, max_iter):
        """Fixed point of the contact stiffness changes ``dk`` ``(n_freq, n_contact)``."""
        k0 = self._contact_stiffness()
        scale = self._slip_scale()[None] * force
        lin = 1.0 + 1j * self.contact_loss
        nf, nb = hbi.shape
        dk = np.zeros((nf, nb), dtype=complex)
        relax = np.ones(nf)
        last = np.full(nf, np.inf)
        act = np.arange(nf)
        A, b = Hbb, hbi
        eye = np.eye(nb)
        for _ in range(max_iter):
            S = eye[None] + A * dk[act][:, None, :]
            xb = np.linalg.solve(S, b[:, :, None])[:, :, 0]          # relative displacement per N
            sigma, eta = law(np.abs(xb) * scale)
            step = k0[None] * (np.asarray(sigma) * (1 + 1j * np.asarray(eta)) - lin) - dk[act]
            res = (np.abs(step) / k0).max(axis=1)
            grew = res > last[act]
            relax[act[grew]] = np.maximum(0.5 * relax[act[grew]], 1.0 / 64)
            last[act] = res
            dk[act] += relax[act][:, None] * step
            keep = res > tol
            if not keep.any():
                return dk
            if keep.sum() < 0.9 * act.size:                   # compact the working set
                act, A, b = act[keep], A[keep], b[keep]
        raise RuntimeError(f"harmonic balance did not converge on {act.size} of {nf} lines")

    # -- derived ----------------------------------------------------------
    def with_(self, **changes) -> "ToolInHolder":
        """A copy with some fields changed (a fresh mode cache)."""
        from dataclasses import replace

        return replace(self, _cache={}, **changes)

    def rigid_clamp_shift(self, n: int = 3) -> np.ndarray:
        """Relative change ``f_clamped/f − 1`` of the first ``n`` modes if the base were rigid."""
        f = self.natural_frequencies(n)
        fc = self.with_(base=None).natural_frequencies(n)
        return fc / f - 1.0
