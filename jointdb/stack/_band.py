"""Tool-tip prediction bands from the joints' parameter covariance (issue 13, item 3).

Each interface whose catalogued joint carries an uncertainty record (``theta`` and its
covariance, see :mod:`jointdb.coupling._propagate`) is sampled ``n`` times; every sample of
the stack is coupled in one batched chain (samples stacked on the frequency axis) and the
5 / 50 / 95 % percentiles of |H| per line and of the tip peak are returned.
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

__all__ = ["TipBand", "tip_band", "sampleable_uncertainties"]

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


def tip_band(spec: StackSpec, resolved_joints: Mapping[str, FRF], uncertainties: Mapping[str, Mapping],
             freq=None, n: int = 200, seed: int = 0) -> TipBand:
    """5/50/95 % band of the tool-tip receptance from sampled joints.

    Parameters
    ----------
    spec, resolved_joints, freq
        As :func:`jointdb.stack.predict_tool_tip`.
    uncertainties
        Interface name → uncertainty record of its joint (interfaces not named keep their
        nominal joint).
    n, seed
        Ensemble size and random seed.

    Raises
    ------
    InputError
        No interface with an uncertainty, or a record that is not a planar spring–damper.
    """
    if not uncertainties:
        raise InputError("no interface joint carries an uncertainty record; nothing to sample")
    f = prediction_grid(spec, freq)
    parts = stack_parts(spec, f)
    node = spec.spindle.node if isinstance(spec.spindle, MeasuredSpindle) else NODES["spindle_nose"]
    spindle, _ = _planes(parts["spindle"], "spindle FRF", node)
    resolved = dict(resolved_joints or {})

    def tile(a):
        return np.broadcast_to(a, (n,) + a.shape).reshape((n * a.shape[0],) + a.shape[1:])

    joints = {}
    for name in INTERFACE_NAMES:
        if name in uncertainties:
            s = _sampled_planes(uncertainties[name], f, n, seed + 7919 * INTERFACE_NAMES.index(name),
                                f"interfaces.{name}")
            joints[name] = s.reshape((n * f.size, 2, 2))
        else:
            planes, _ = _joint_planes(name, spec, resolved, f)
            joints[name] = None if planes is None else {p: tile(planes[p]) for p in ("x", "y")}
    tool, holder = tile(parts["tool"].values), tile(parts["holder"].values)
    tips, mags, peaks, peak_hz = {}, {}, {}, {}
    for plane in ("x", "y"):
        jt, jh = (j if j is None or isinstance(j, np.ndarray) else j[plane]
                  for j in (joints["tool-holder"], joints["holder-spindle"]))
        tip = tool_tip_chain(tool, holder, tile(spindle[plane]), jt, jh)[:, 0, 0].reshape(n, f.size)
        tips[plane] = tip
        mag = np.abs(tip)
        mags[plane] = band(mag, QUANTILES)
        i = np.argmax(mag, axis=1)
        peaks[plane] = band(mag.max(axis=1), QUANTILES)
        peak_hz[plane] = band(f[i], QUANTILES)
    return TipBand(f, mags, peaks, peak_hz, int(n), tuple(sorted(uncertainties)), tips)
