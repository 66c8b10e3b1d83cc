"""Critical-depth bands from an ensemble of tool-tip FRFs (issue 13, item 3)."""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from jointdb.errors import InputError
from jointdb.frf import FRF

__all__ = ["LobeBand", "milling_lobes_band"]


@dataclass(frozen=True, eq=False)
class LobeBand:
    """Percentiles over an ensemble of lobe diagrams.

    ``depth_m``: ``(3, n_speeds)`` 5/50/95 % of the limiting depth per speed [m];
    ``critical_depth_m``: 5/50/95 % of the smallest depth over the speeds; ``samples``.
    """

    spindle_speed_rpm: np.ndarray
    depth_m: np.ndarray
    critical_depth_m: np.ndarray
    samples: int

    def to_json(self) -> dict:
        return {"quantiles": [0.05, 0.5, 0.95], "samples": self.samples,
                "critical_depth_m": self.critical_depth_m.tolist(),
                "spindle_speed_rpm": self.spindle_speed_rpm.tolist(),
                "depth_m": {"p05": self.depth_m[0].tolist(), "p50": self.depth_m[1].tolist(),
                            "p95": self.depth_m[2].tolist()}}


def milling_lobes_band(tips_x: Sequence[FRF], tips_y: Sequence[FRF] | None, cut, speeds) -> LobeBand:
    """ZOA milling lobes for each sampled tool tip; 5/50/95 % per speed and of the critical depth.

    Parameters
    ----------
    tips_x, tips_y
        Sampled x (and y) driving-point receptances, one FRF per sample (``tips_y`` None:
        the x FRF holds both or the y direction is rigid, as for a single tip file).
    cut
        :class:`~jointdb.stability.MillingCut`.
    speeds
        Spindle speeds [rpm].

    Raises
    ------
    InputError
        Fewer than 2 samples, or lengths of ``tips_x`` and ``tips_y`` differ.
    """
    from jointdb.stability._frequency import milling_lobes_zoa

    if len(tips_x) < 2 or (tips_y is not None and len(tips_y) != len(tips_x)):
        raise InputError("a lobe band needs at least 2 samples, the same number in x and y")
    s = np.asarray(speeds, float)
    depth = np.array([milling_lobes_zoa(fx, cut, None if tips_y is None else tips_y[k], spindle_speed_rpm=s).depth_m
                      for k, fx in enumerate(tips_x)])  # loop over samples; each is batched over lines
    depth = np.where(np.isfinite(depth), depth, np.nan)  # no limit at a speed: left out of its percentiles
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # a speed with no finite limit in any sample gives NaN
        q = np.nanquantile(depth, [0.05, 0.5, 0.95], axis=0)
        crit = np.nanquantile(np.nanmin(depth, axis=1), [0.05, 0.5, 0.95])
    return LobeBand(s, q, crit, len(tips_x))
