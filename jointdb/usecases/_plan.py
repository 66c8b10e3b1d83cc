"""Planning a campaign: which tap points determine the joint best (Fisher information)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from jointdb.errors import InputError

__all__ = ["CampaignPlan", "plan_measurements"]


@dataclass(frozen=True)
class CampaignPlan:
    """The ranked candidate measurements of a campaign and the information of its own ones.

    Parameters
    ----------
    campaign
        The campaign file's name.
    plan
        The :class:`jointdb.campaign.MeasurementPlan` (``rows`` best first, ``targets``,
        ``criterion``, ``noise``, ``target``).
    current
        The campaign's own measurements as a row (``measurements``, ``std_rel``, ``averages``),
        empty when it has none.
    """

    campaign: str
    plan: Any
    current: dict


def plan_measurements(campaign: str | Path, *, n_measurements: int = 2, noise: float = 0.01,
                      target: float = 0.05, criterion: str = "A", targets: list[str] | None = None) -> CampaignPlan:
    """Rank candidate tap points of a campaign by the expected joint-parameter variance.

    Parameters
    ----------
    campaign : str or Path
        The campaign file (``jointdb-campaign/1``), planar or n-point.
    n_measurements : int
        FRFs per candidate set (response/excitation pairs), 1..6.
    noise : float
        Relative noise of one averaged FRF, in (0, 1) (0.01 = 1 %).
    target : float
        Wanted relative standard error of the target parameters, in (0, 1).
    criterion : str
        ``"A"`` (sum of the target variances) or ``"D"`` (determinant of the information).
    targets : list of str, optional
        Parameter names (default: the rotational k, c of a planar joint; all for n-point).

    Returns
    -------
    CampaignPlan

    Raises
    ------
    InputError
        Values out of range, a matrix campaign, too few candidate points.
    """
    from jointdb.campaign import load_campaign
    from jointdb.campaign._plan import plan_campaign

    if not (0 < noise < 1) or not (0 < target < 1):
        raise InputError(f"--noise and --target must be in (0, 1), got {noise:g}, {target:g}")
    if not 1 <= n_measurements <= 6:
        raise InputError(f"--measurements must be 1..6, got {n_measurements}")
    c = load_campaign(campaign)
    plan, current = plan_campaign(c, n_measurements=n_measurements, noise=noise, target=target,
                                  criterion=criterion.upper(), targets=targets)
    return CampaignPlan(c.name, plan, current)
