"""Tool-tip prediction bands: measurement noise, joint choice and damping law (issues 13 and 22; docs/stacks.md,
*Bands*).

Three sources of error are sampled, per interface:

- *measurement noise*: a catalogued joint that carries an uncertainty record (``theta`` and its
  covariance, see :mod:`jointdb.coupling._propagate`) is drawn from it;
- *joint choice*: a joint taken from the catalogue for conditions it was not identified at is
  wrong by what the choice (nearest joint or interpolation) cannot know; its relative error in
  stiffness and damping, estimated from the catalogue by leave-one-out
  (:mod:`jointdb.store._loo`), scales each sample's dynamic stiffness (:func:`choice_perturbed`);
- *damping law*: a constant spring–damper identified at one mode is viscous by construction; away from that
  mode's frequency its loss could follow any law between viscous and hysteretic (:func:`damping_law`).

Tip-level terms scale each sample's tip receptance by a log-normal factor: the prediction path's model form
(``tip_sigma``), the substructure model's error its campaigns showed (``model_sigma``) and the sensitivity of the
dominant peak to where a chosen joint's features sit (``feature_sigma``, :mod:`jointdb.stack._feature`).

Every sample of the stack is coupled in one batched chain (samples stacked on the frequency axis;
both bending planes, cross terms included when the spindle couples them) and the 5 / 50 / 95 %
percentiles of |H| per line and of the tip peak are returned.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from jointdb.coupling._propagate import band, spring_damper_samples
from jointdb.errors import InputError
from jointdb.frf import FRF, Dof
from jointdb.stack._chain import tool_tip_chain
from jointdb.stack._parts import NODES
from jointdb.stack._predict import _joint_planes, _planes, prediction_grid, stack_parts
from jointdb.stack._spec import INTERFACE_NAMES, MeasuredSpindle, StackSpec

__all__ = ["TipBand", "tip_band", "sampleable_uncertainties", "damping_law"]

QUANTILES = (0.05, 0.5, 0.95)


@dataclass(frozen=True, eq=False)
class TipBand:
    """Percentile band of the predicted tool-tip receptance.

    ``magnitude[d]``: ``(3, n_freq)`` 5/50/95 % of |H_dd| per line; ``peak[d]``: 5/50/95 % of the
    peak |H_dd| [m/N]; ``peak_hz[d]``: the same for its frequency; ``samples``: ensemble size;
    ``interfaces``: the interfaces whose joints were sampled.
    """

    freq: np.ndarray
    magnitude: Mapping[str, np.ndarray]
    peak: Mapping[str, np.ndarray]
    peak_hz: Mapping[str, np.ndarray]
    samples: int
    interfaces: tuple[str, ...]
    tips: Mapping[str, np.ndarray]
    cross: np.ndarray | None = None  # (n, n_freq, 2, 2) samples over (1x, 1y) when the spindle couples the planes

    @property
    def sources(self) -> str:
        """What the samples vary, in words: the interfaces whose joints were drawn, then the other terms
        (``interfaces`` holds both: e.g. "the holder-spindle and tool-holder joints, damping law, prediction path")."""
        joints = [s for s in self.interfaces if s in INTERFACE_NAMES]
        terms = [s for s in self.interfaces if s not in INTERFACE_NAMES]
        named = [f"the {' and '.join(joints)} joint{'s' if len(joints) > 1 else ''}"] if joints else []
        return ", ".join(named + terms)

    def summary(self) -> list[dict]:
        return [{"direction": d, "peak_m_per_n_p05": float(self.peak[d][0]),
                 "peak_m_per_n_p50": float(self.peak[d][1]), "peak_m_per_n_p95": float(self.peak[d][2]),
                 "peak_hz_p05": float(self.peak_hz[d][0]), "peak_hz_p95": float(self.peak_hz[d][2])}
                for d in self.magnitude]

    def to_json(self) -> dict:
        return {"quantiles": list(QUANTILES), "samples": self.samples, "interfaces": list(self.interfaces),
                "peaks": self.summary(), "frequency_hz": self.freq.tolist(),
                "magnitude_m_per_n": {d: {"p05": m[0].tolist(), "p50": m[1].tolist(), "p95": m[2].tolist()}
                                      for d, m in self.magnitude.items()}}

    def tip_frfs(self, direction: str = "x") -> list[FRF]:
        """The sampled tip receptances of one direction as FRFs (for lobes per sample)."""
        dof = Dof(1, direction)
        return [FRF(self.freq, h[:, None, None], [dof], [dof], "receptance") for h in self.tips[direction]]

    def tip_matrices(self) -> list[FRF]:
        """The sampled 2×2 tip receptances over (1x, 1y), cross terms included when present."""
        out = (Dof(1, "x"), Dof(1, "y"))
        if self.cross is not None:
            vals = self.cross
        else:
            vals = np.zeros((self.samples, self.freq.size, 2, 2), dtype=complex)
            vals[:, :, 0, 0], vals[:, :, 1, 1] = self.tips["x"], self.tips["y"]
        return [FRF(self.freq, v, out, out, "receptance") for v in vals]


def describes_catalogued_joint(record: Mapping) -> bool:
    """False for a record kept as information only: the catalogued joint is the per-line IRC joint because
    constant k, c could not represent it, so sampling the constant model would describe another joint."""
    return record.get("describes_catalogued_joint", True) is not False


def sampleable_uncertainties(resolutions: Mapping) -> tuple[dict, list[str]]:
    """``(interface → uncertainty record, notes)`` of the resolved joints a band may sample.

    ``resolutions``: interface → :class:`jointdb.usecases.JointResolution`. Joints whose record does not
    describe their catalogued FRF keep their nominal FRF in the band, with a note saying so.
    """
    unc, notes = {}, []
    for name, r in resolutions.items():
        rec = getattr(r, "uncertainty", None)
        if rec is None or r.kind not in ("catalogued", "query"):
            continue
        if describes_catalogued_joint(rec):
            unc[name] = rec
        else:
            notes.append(f"{name}: joint {r.name}@{r.version} is not sampled in the band — constant k, c could not "
                         "represent it, so its catalogued FRF is the per-line joint and carries no covariance")
    return unc, notes


def _sampled_planes(record: Mapping, f: np.ndarray, n: int, seed: int, what: str) -> np.ndarray:
    """(n, nf, 2, 2) joint receptance samples over (x, θ) from a spring–damper record with x and ry DOFs."""
    if not describes_catalogued_joint(record):
        raise InputError(f"{what}: the joint's covariance belongs to a constant k, c that was rejected for it "
                         "(its catalogued FRF is the per-line joint); it cannot be sampled")
    dirs = [Dof.parse(d).direction for d in record.get("dofs", [])]
    if sorted(dirs) != ["ry", "x"]:
        raise InputError(f"{what}: the joint's uncertainty is over {dirs}; a planar joint over x and ry is needed")
    s = spring_damper_samples(record, f, n, seed)
    order = [dirs.index("x"), dirs.index("ry")]
    return s[:, :, order][:, :, :, order]


def choice_perturbed(planes: np.ndarray, relative: np.ndarray, scale: np.ndarray,
                     rng: np.random.Generator, group: np.ndarray | None = None,
                     shift: np.ndarray | None = None) -> np.ndarray:
    """Joint receptance samples with the joint-choice error applied (docs/stacks.md, *Bands*).

    Each sample draws, per group (a condition axis whose lines were left out, :mod:`jointdb.store._loo`), one
    of the catalogue's leave-one-out errors ``R_j`` (the relative error per line, ``Z_j = (I + R_j) Ẑ_j``, of
    catalogued joints predicted from the others) and a normal amplitude ``t_j = shift_j + scale_j ξ``, and applies them
    multiplicatively to its dynamic stiffness: ``Z' = exp(Σ_g t_g ln(I + R_{j_g})) Z`` (per line; ``t = 1``
    reproduces the left-out error exactly, ``t = −1`` its inverse, so a stiffness or damping error is as likely
    ×2 as ×½ and no draw drives the joint's damping through zero).

    Parameters
    ----------
    planes
        Joint receptance samples ``(n, n_freq, 2, 2)`` over (x, θ).
    relative
        ``(m, n_freq, 2, 2)`` leave-one-out relative errors over (x, θ), on the same lines.
    scale
        ``(m,)`` standard deviation of the amplitude per error (request's distance or gap over the point's,
        times the calibration).
    rng
        Random generator.
    group
        ``(m,)`` integer group of each error (None: one group); the groups' draws are independent and add.
    shift
        ``(m,)`` mean amplitude of each error (None: 0, a band centred on the prediction). A line left out along
        an axis is interpolated wrong in the same direction wherever the axis bends the same way, so its error
        scaled to the request (``shift = b · gap ratio``) is a bias the catalogue itself shows.

    Returns
    -------
    ndarray ``(n, n_freq, 2, 2)``
    """
    z = np.linalg.inv(planes)
    n = z.shape[0]
    scale = np.asarray(scale, float)
    group = np.zeros(scale.size, dtype=int) if group is None else np.asarray(group, dtype=int)
    shift = np.zeros(scale.size) if shift is None else np.asarray(shift, float)
    log_r = _matrix_log(np.eye(relative.shape[-1]) + relative)
    s = np.zeros((n,) + log_r.shape[1:], dtype=complex)
    for g in np.unique(group):
        idx = np.flatnonzero(group == g)
        j = idx[rng.integers(idx.size, size=n)]
        t = shift[j] + scale[j] * rng.standard_normal(n)
        s += t[:, None, None, None] * log_r[j]
    return np.linalg.inv(_expm(s) @ z)


def _expm(a: np.ndarray) -> np.ndarray:
    """Matrix exponential of each matrix of ``a`` (``(..., n, n)``): in closed form for 2×2 blocks, batched;
    otherwise :func:`scipy.linalg.expm` (which loops over the batch in Python).

    For a 2×2 ``A`` with ``μ = tr A / 2`` and ``q = det(μI − A)·(−1) = ((a₁₁ − a₂₂)/2)² + a₁₂ a₂₁``,
    ``exp A = e^μ [cosh √q · I + (sinh √q / √q) (A − μI)]`` (Cayley–Hamilton: ``(A − μI)² = q I``; both
    functions are even in √q, so its branch does not matter; near ``q = 0`` their series are used).
    """
    if a.shape[-2:] != (2, 2):
        from scipy.linalg import expm

        return expm(a)
    mu = 0.5 * (a[..., 0, 0] + a[..., 1, 1])
    q = (0.5 * (a[..., 0, 0] - a[..., 1, 1])) ** 2 + a[..., 0, 1] * a[..., 1, 0]
    r = np.sqrt(q.astype(complex))
    small = np.abs(q) < 1e-6
    safe = np.where(small, 1.0, r)
    with np.errstate(over="ignore", invalid="ignore"):  # overflowing entries are redone below
        cosh = np.where(small, 1 + q / 2 + q * q / 24, np.cosh(safe))
        sinhc = np.where(small, 1 + q / 6 + q * q / 120, np.sinh(safe) / safe)
        out = sinhc[..., None, None] * a
        diag = cosh - sinhc * mu
        out[..., 0, 0] += diag
        out[..., 1, 1] += diag
        out = np.exp(mu)[..., None, None] * out
    bad = ~np.isfinite(out).all(axis=(-2, -1))
    if bad.any():  # cosh √q overflows (|√q| > ~710) where e^μ would bring the product back: scipy's scaling
        from scipy.linalg import expm

        out[bad] = expm(a[bad])
    return out


#: Smallest real part kept for an eigenvalue of ``I + R`` in :func:`_matrix_log`: a relative error
#: is never taken below -95 % (an eigenvalue at or past zero would be a joint with no stiffness or
#: a sign flip, whose logarithm is -inf or the non-physical ``iπ`` branch).
_LOG_FLOOR = 0.05


def _matrix_log(a: np.ndarray) -> np.ndarray:
    """Principal logarithm of each ``(n, n)`` matrix of ``a`` (``(..., n, n)``) through its eigendecomposition,
    eigenvalues' real parts floored at :data:`_LOG_FLOOR`; where the eigenvectors are ill-conditioned
    (a defective matrix) the series ``R - R²/2 + R³/3`` of ``a = I + R`` is used instead."""
    w, v = np.linalg.eig(a)
    w = np.maximum(w.real, _LOG_FLOOR) + 1j * w.imag
    cond = np.linalg.cond(v)
    good = np.isfinite(cond) & (cond < 1e6)
    out = np.empty(a.shape, dtype=complex)
    if good.any():
        vg = v[good]
        out[good] = (vg * np.log(w[good])[..., None, :]) @ np.linalg.inv(vg)
    if (~good).any():
        r = a[~good] - np.eye(a.shape[-1])
        r2 = r @ r
        out[~good] = r - r2 / 2 + (r2 @ r) / 3
    return out


def damping_law(planes: np.ndarray, freq: np.ndarray, f_ref: float, beta: np.ndarray,
                share: float = 1.0) -> np.ndarray:
    """Joint receptance samples whose loss follows a fractional-derivative law instead of the viscous one.

    A constant spring–damper ``Z(f) = K + i 2πf C`` identified at one mode (frequency ``f_ref``) fixes its loss
    there, not its law: a viscous damper (``Im Z ∝ f``) and structural (hysteretic) damping
    (``Im Z = η K``, loss factor ``η = 2π f_ref C / K`` independent of frequency; Ewins, *Modal Testing*, §2)
    give the same joint at ``f_ref`` and differ away from it. Between them lies a power-law loss ``Im Z(f) ∝ f^β``,
    ``0 ≤ β ≤ 1``, with the storage stiffness held fixed (the loss law of fractional-derivative models, Bagley &
    Torvik 1983, AIAA J. 21(5), without their change of ``Re Z``; β = 0 is ideal hysteretic damping, which is not
    causal). Each sample keeps ``Re Z`` and scales ``Im Z`` per line:

        ``Im Z'(f) = Im Z(f) · [share · (f_ref / f)^(1−β) + (1 − share)]``

    (β = 1: as catalogued; β = 0: hysteretic at the loss the joint has at ``f_ref``; at ``f = f_ref`` nothing
    changes). ``share`` < 1 scales only that part of the change (the band uses 1: it samples the law of constant
    joints only, :func:`jointdb.usecases._stack_band.damping_laws`).

    Parameters
    ----------
    planes
        Joint receptance samples ``(n, n_freq, m, m)`` [m/N, rad/N·m, ...], e.g. over (x, θ).
    freq
        ``(n_freq,)`` lines [Hz], all > 0.
    f_ref
        Frequency [Hz] where the constant joint was identified (> 0).
    beta
        ``(n,)`` damping-law exponent of each sample, in [0, 1].
    share
        Weight in [0, 1] of the law's change.

    Returns
    -------
    ndarray ``(n, n_freq, m, m)``
        The samples' receptance with the law applied (the same draw for every DOF pair of a sample).

    Raises
    ------
    InputError
        ``f_ref`` or a line not positive, β outside [0, 1], or a share outside [0, 1].
    """
    f = np.asarray(freq, float)
    beta = np.asarray(beta, float)
    if not (np.isfinite(f_ref) and f_ref > 0) or f.size and f.min() <= 0:
        raise InputError(f"damping law: the reference frequency ({f_ref!r} Hz) and every line must be > 0 Hz")
    if beta.shape != (planes.shape[0],) or np.any((beta < 0) | (beta > 1)):
        raise InputError("damping law: one exponent β in [0, 1] per sample is needed")
    if not 0.0 <= share <= 1.0:
        raise InputError(f"damping law: share {share!r} must lie in [0, 1]")
    z = np.linalg.inv(planes)
    factor = share * (f_ref / f)[None, :] ** (1.0 - beta)[:, None] + (1.0 - share)
    return np.linalg.inv(z.real + 1j * z.imag * factor[:, :, None, None])


def _both_planes(planes: dict, fn) -> dict:
    """``fn`` applied to the samples of each bending plane, once when both planes hold the same joint."""
    x = fn(planes["x"])
    same = planes["x"] is planes["y"] or np.array_equal(planes["x"], planes["y"])
    return {"x": x, "y": x if same else fn(planes["y"])}


def _law_applied(planes: dict, law, f, n, seed, name) -> dict:
    """The planes of one interface with the damping law ``law = (f_ref, share)`` drawn (β uniform on [0, 1], its own
    stream: the other terms' draws do not change) and applied, the same β in both planes (one joint)."""
    if law is None:
        return planes
    f_ref, share = law
    beta = np.random.default_rng([seed, 2718, INTERFACE_NAMES.index(name)]).uniform(0.0, 1.0, n)
    return _both_planes(planes, lambda p: damping_law(p, f, f_ref, beta, share))


def _interface_samples(name, spec, resolved, f, n, seed, uncertainties, choice, rng, law=None):
    """``None`` (rigid) or per plane ``(n, n_freq, 2, 2)`` samples of one interface's joint."""
    if name in uncertainties:
        s = _sampled_planes(uncertainties[name], f, n, seed + 7919 * INTERFACE_NAMES.index(name),
                            f"interfaces.{name}")
        planes = {"x": s, "y": s}
    else:
        nominal, _ = _joint_planes(name, spec, resolved, f)
        if nominal is None:
            return None
        planes = {p: np.broadcast_to(nominal[p], (n,) + nominal[p].shape) for p in ("x", "y")}
    planes = _law_applied(planes, law, f, n, seed, name)
    choice = (choice or {}).get(name)
    if choice is None:
        return planes
    state = rng.bit_generator.state

    def perturbed(p):
        rng.bit_generator.state = state  # the same draws in both planes: one joint
        return choice_perturbed(p, *choice[:2], rng, *choice[2:])

    return _both_planes(planes, perturbed)


def tip_band(spec: StackSpec, resolved_joints: Mapping[str, FRF], uncertainties: Mapping[str, Mapping] | None = None,
             freq=None, n: int = 200, seed: int = 0, choice: Mapping[str, tuple] | None = None,
             tip_sigma: float = 0.0, spindle_estimate=None, model_sigma: float = 0.0,
             damping: Mapping[str, tuple] | None = None, feature_sigma: float = 0.0) -> TipBand:
    """5/50/95 % band of the tool-tip receptance from sampled joints.

    Parameters
    ----------
    spec, resolved_joints, freq
        As :func:`jointdb.stack.predict_tool_tip`.
    uncertainties
        Interface name → uncertainty record of its joint (measurement noise through the fit's
        covariance); interfaces not named keep their nominal joint.
    choice
        Interface name → ``(relative, scale[, group[, shift]])`` of its joint-choice error
        (:func:`choice_perturbed`, arrays on the prediction's lines), applied on top of the covariance samples.
    tip_sigma
        Relative standard error of the prediction path itself (model form: beams joined at points where the
        real stack has distributed contact): each sample's tip receptance is scaled by ``exp(tip_sigma ξ)``.
    spindle_estimate
        A :class:`jointdb.stack._spindle_band.SpindleEstimate` of a single-plane measured spindle: each sample's
        spindle is the nominal one plus the estimate's change under the taps' noise
        (:func:`jointdb.stack._spindle_band.spindle_deviations`); None: the spindle is exact.
    model_sigma
        Relative standard error of the substructure model shown by the campaigns' validation (or tool–holder
        identification) assemblies (log units): each
        sample's tip receptance is scaled by ``exp(model_sigma ξ)``, independently of ``tip_sigma``.
    damping
        Interface name → ``(f_ref, share)`` of a constant spring–damper joint whose damping law is unknown
        (:func:`damping_law`): each sample draws β uniform on [0, 1] and applies it before the joint-choice error.
    feature_sigma
        Relative standard error (log units) from where the chosen joints' features sit
        (:func:`jointdb.stack._feature.peak_shift_sensitivity` times a factor): combined with ``model_sigma`` in
        quadrature, one draw ``exp(sqrt(model_sigma² + feature_sigma²) ξ)`` per sample.
    n, seed
        Ensemble size and random seed.

    Returns
    -------
    TipBand
        Both planes; with a spindle whose FRF couples the planes the chain runs on (x, θx, y, θy) and the
        samples carry the cross terms (``cross``).

    Raises
    ------
    InputError
        Nothing to sample, or a record that is not a planar spring–damper.
    """
    from jointdb.stack._twoplane import spindle_four, two_plane_tip

    uncertainties = dict(uncertainties or {})
    choice = {k: v for k, v in (choice or {}).items() if v is not None}
    damping = {k: v for k, v in (damping or {}).items() if v is not None}
    active = set(uncertainties) | set(choice) | {term for term, on in (
        ("damping law", bool(damping)), ("prediction path", tip_sigma > 0), ("spindle", spindle_estimate is not None),
        ("substructure model", model_sigma > 0), ("feature position", feature_sigma > 0)) if on}
    if not active:
        raise InputError("no interface joint carries an uncertainty record, a joint-choice error or an unknown "
                         "damping law; nothing to sample")
    f = prediction_grid(spec, freq)
    parts = stack_parts(spec, f)
    node = spec.spindle.node if isinstance(spec.spindle, MeasuredSpindle) else NODES["spindle_nose"]
    spindle, has_y = _planes(parts["spindle"], "spindle FRF", node)
    resolved = dict(resolved_joints or {})
    rng = np.random.default_rng([seed, 104729])

    def flat(a):
        a = np.broadcast_to(a, (n,) + a.shape[-3:]) if a.ndim == 3 else a
        return np.ascontiguousarray(a).reshape((n * f.size,) + a.shape[2:])

    joints = {name: _interface_samples(name, spec, resolved, f, n, seed, uncertainties, choice, rng, damping.get(name))
              for name in INTERFACE_NAMES}
    joints = {k: None if v is None else {p: flat(v[p]) for p in ("x", "y")} for k, v in joints.items()}
    tool, holder = flat(parts["tool"].values), flat(parts["holder"].values)
    spindle4 = spindle_four(parts["spindle"], node) if has_y else None
    if spindle_estimate is not None:
        if has_y:
            raise InputError("a spindle estimate describes one bending plane; a spindle measured in both planes "
                             "is not sampled")
        from jointdb.stack._spindle_band import spindle_deviations

        sampled = spindle["x"][None] + spindle_deviations(spindle_estimate, f, n, rng)
        spindle = {"x": sampled, "y": sampled}
    full = np.zeros((n, f.size, 2, 2), dtype=complex)
    if spindle4 is not None:
        t4 = two_plane_tip(tool, holder, flat(spindle4), joints["tool-holder"], joints["holder-spindle"])
        full[:] = t4[:, [0, 2]][:, :, [0, 2]].reshape(n, f.size, 2, 2)
    else:
        for k, plane in enumerate(("x", "y")):
            jt, jh = (None if j is None else j[plane] for j in (joints["tool-holder"], joints["holder-spindle"]))
            full[:, :, k, k] = tool_tip_chain(tool, holder, flat(spindle[plane]), jt, jh)[:, 0, 0].reshape(n, f.size)
    for sigma in (tip_sigma, float(np.hypot(model_sigma, feature_sigma))):
        if sigma > 0:
            full *= np.exp(sigma * rng.standard_normal(n))[:, None, None, None]
    return _band_of(f, full, active, full if spindle4 is not None else None)


def _band_of(f: np.ndarray, full: np.ndarray, active: set, cross) -> TipBand:
    """The :class:`TipBand` of ``(n, n_freq, 2, 2)`` sampled tip receptances over (1x, 1y)."""
    tips, mags, peaks, peak_hz = {}, {}, {}, {}
    for k, plane in enumerate(("x", "y")):
        tips[plane] = full[:, :, k, k]
        mag = np.abs(tips[plane])
        mags[plane] = band(mag, QUANTILES)
        peaks[plane] = band(mag.max(axis=1), QUANTILES)
        peak_hz[plane] = band(f[np.argmax(mag, axis=1)], QUANTILES)
    return TipBand(f, mags, peaks, peak_hz, int(full.shape[0]), tuple(sorted(active)), tips, cross)
