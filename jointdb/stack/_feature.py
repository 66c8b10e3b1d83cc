"""Where a joint's features sit: a joint read at stretched frequencies, and how much the tool tip's dominant peak
depends on it (issue 22; docs/stacks.md, *Bands*).

A per-line joint identified by inverse receptance coupling is not smooth in frequency where it absorbs its
identification assembly's dynamics (truth family C's tool–holder joints jump, Re Z even turning negative, over
0.9–1.3 kHz, at positions that move with bore and drawbar force). A joint chosen for conditions it was not identified
at — interpolated between catalogued ones, or the nearest one — cannot place those features where the real joint
has them, and a stack whose mode sits on one errs by its sensitivity to where they are. :func:`peak_shift_sensitivity`
measures that sensitivity deterministically (two more predictions per stack);
:mod:`jointdb.usecases._stack_band` turns it into the band's *feature position* term.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

import numpy as np

from jointdb.errors import InputError
from jointdb.frf import FRF
from jointdb.stack._predict import predict_tool_tip
from jointdb.stack._spec import StackSpec

__all__ = ["frequency_shifted", "read_shifted", "peak_shift_sensitivity"]


def frequency_shifted(planes: np.ndarray, freq: np.ndarray, eps: np.ndarray) -> np.ndarray:
    """Joint receptance samples each read at stretched frequencies: ``out[i](f) = planes[i](f (1 + eps_i))``.

    A feature at ``f₀`` moves to ``f₀ / (1 + eps_i)``.

    Parameters
    ----------
    planes
        Joint receptance samples ``(n, n_freq, m, m)``.
    freq
        ``(n_freq,)`` increasing lines [Hz].
    eps
        ``(n,)`` relative shift of each sample (0: the line itself); lines read beyond the grid take its end value.

    Returns
    -------
    ndarray ``(n, n_freq, m, m)``
        Linear interpolation between the two neighbouring lines (exact for a receptance linear in f).
    """
    f = np.asarray(freq, float)
    g = np.clip(f[None, :] * (1.0 + np.asarray(eps, float))[:, None], f[0], f[-1])
    hi = np.clip(np.searchsorted(f, g), 1, f.size - 1)
    w = ((g - f[hi - 1]) / (f[hi] - f[hi - 1]))[:, :, None, None]
    lo_vals = np.take_along_axis(planes, (hi - 1)[:, :, None, None], axis=1)
    hi_vals = np.take_along_axis(planes, hi[:, :, None, None], axis=1)
    return (1.0 - w) * lo_vals + w * hi_vals


def read_shifted(frf: FRF, eps: float) -> FRF:
    """A joint receptance read at ``f (1 + eps)`` on its own lines (:func:`frequency_shifted`).

    Parameters
    ----------
    frf
        Joint receptance ``(n_freq, n_dof, n_dof)``.
    eps
        Relative shift, ``|eps| < 1``.

    Returns
    -------
    FRF
        The same DOFs and lines; its features at ``f₀ / (1 + eps)``.

    Raises
    ------
    InputError
        ``eps`` not a finite number in (−1, 1), or fewer than two lines.
    """
    if not (np.isfinite(eps) and abs(eps) < 1.0):
        raise InputError(f"frequency shift: {eps!r} must be a finite number between -1 and 1")
    if frf.freq.size < 2:
        raise InputError("frequency shift: the joint needs at least two lines to be read between them")
    return frf.replace(values=frequency_shifted(frf.values[None], frf.freq, np.array([float(eps)]))[0])


def peak_shift_sensitivity(spec: StackSpec, resolved_joints: Mapping[str, FRF], nominal: FRF,
                           interfaces: Iterable[str], delta: float = 0.03) -> dict[str, float]:
    """How much the tip's dominant peak moves when the named interfaces' joints are read at ``f (1 ± delta)``.

    Per bending plane ``d`` of ``nominal``, ``s_d = sqrt(mean over ±delta of ln²(max|H_dd'| / max|H_dd|))``, with
    ``H'`` the tip receptance predicted with every named joint read at ``f (1 ± delta)`` (:func:`read_shifted`), the
    others as resolved. A log-normal tip factor of standard deviation ``k·s`` is the band's feature-position term
    (:mod:`jointdb.usecases._stack_band`).

    Parameters
    ----------
    spec
        The stack, as :func:`jointdb.stack.predict_tool_tip` takes it.
    resolved_joints
        Interface name → joint receptance used by the prediction.
    nominal
        The prediction's tip receptance over (1x, 1y) ``(n_freq, 2, 2)``; its lines are the prediction's.
    interfaces
        The interfaces whose joints are shifted (those not in ``resolved_joints`` are ignored).
    delta
        Relative shift, ``0 < delta < 1``.

    Returns
    -------
    dict[str, float]
        Direction (``"x"``, ``"y"``) → ``s`` (log units, ≥ 0); every direction 0 when no named interface has a
        resolved joint.

    Raises
    ------
    InputError
        ``delta`` outside (0, 1).
    """
    if not (np.isfinite(delta) and 0.0 < delta < 1.0):
        raise InputError(f"feature position: the shift {delta!r} must lie between 0 and 1")
    shifted = [k for k in interfaces if k in resolved_joints]
    dirs = [(k, d.direction) for k, d in enumerate(nominal.outputs)]
    if not shifted:
        return {d: 0.0 for _, d in dirs}
    peak0 = {d: np.abs(nominal.values[:, k, k]).max() for k, d in dirs}
    logs: dict[str, list[float]] = {d: [] for _, d in dirs}
    for eps in (delta, -delta):
        moved = {k: read_shifted(v, eps) if k in shifted else v for k, v in resolved_joints.items()}
        tip = predict_tool_tip(spec, moved, nominal.freq).tip.values
        for k, d in dirs:
            logs[d].append(float(np.log(np.abs(tip[:, k, k]).max() / peak0[d])))
    return {d: float(np.sqrt(np.mean(np.square(v)))) for d, v in logs.items()}
