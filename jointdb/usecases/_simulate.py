"""Check a cut in the time domain: fit the tool tip's modes, simulate, judge (docs/theory.md §5)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from jointdb.frf import FRF


@dataclass(frozen=True, eq=False)
class TipSimulation:
    """Simulated cuts of one tool tip, with the modal model they ran on.

    Parameters
    ----------
    results
        One :class:`jointdb.stability.SimulationResult` per (speed, depth), in the order given.
    model
        The tool-tip :class:`jointdb.modal.ModalModel` (x/y) the cuts were simulated on.
    fit_quality
        Normalised mean square error of the modal fit per direction (DOF label -> NMSE, dimensionless).
    """

    results: tuple
    model: object
    fit_quality: dict


def simulate_tip(frf: FRF, cut, spindle_speed_rpm: Sequence[float] | float, depth_m: Sequence[float] | float, *,
                 feed_per_tooth_m: float = 1e-4, revolutions: int = 200, runout_m: Sequence[float] | None = None,
                 n_modes: int | None = None, band: Sequence[float] | None = None,
                 steps_per_tooth: int | None = None) -> TipSimulation:
    """Fit the x/y tool-tip modes of ``frf`` and simulate milling at each (speed, depth).

    Parameters
    ----------
    frf
        Tool-tip FRF with the x and/or y driving points (receptance, m/N; any quantity is converted).
    cut
        :class:`jointdb.stability.MillingCut`.
    spindle_speed_rpm, depth_m
        Speeds [rpm] and axial depths [m], one depth per speed.
    feed_per_tooth_m, revolutions, runout_m, steps_per_tooth
        See :func:`jointdb.stability.simulate_milling`.
    n_modes, band
        Modal fit per direction (see :func:`jointdb.modal.fit_tool_tip`).

    Returns
    -------
    TipSimulation

    Raises
    ------
    InputError
        No x/y driving point, or bad cut parameters.
    """
    from jointdb.modal import fit_tool_tip
    from jointdb.stability import simulate_milling

    model, fits = fit_tool_tip(frf, None, n_modes, band)
    quality = {str(f.model.outputs[0]): float(f.quality.nmse_total) for f in fits}
    results = simulate_milling(model, cut, spindle_speed_rpm, depth_m, feed_per_tooth_m=feed_per_tooth_m,
                               revolutions=revolutions, runout_m=runout_m, steps_per_tooth=steps_per_tooth)
    return TipSimulation(tuple(results), model, quality)
